# Step 4: feature sets → concrete 3D interchanges (road layout + ramps fitted by DE).
#
# Fan-out: the samples of a class are known only once its feature sets exist, so
# checkpoint geometry_samples lists them (results/geometry/{class_id}/samples.json);
# each interchange is then its own job (rule geometry), so one changed class or a
# new sample reruns only what depends on it.

GEOMETRY_VERSION = 1


def _features_buildable(class_id):
    """True when a rule makes (or has made) the class's feature sets."""
    made = any("results/features/" in str(o) for r in workflow.rules for o in r.output)
    return made or Path(f"results/features/{class_id}.parquet").exists()


def geometry_interchanges():
    """(class_id, sample) of every interchange to build (used by the export rules)."""
    pairs = []
    for c in class_ids():
        if not _features_buildable(c):
            continue
        path = checkpoints.geometry_samples.get(class_id=c).output.samples
        pairs += [(c, int(s)) for s in json.loads(Path(path).read_text(encoding="utf-8"))]
    return pairs


def geometry_tables(wildcards):
    return [f"results/interchanges/{c}/{s}/geometry.parquet" for c, s in geometry_interchanges()]


checkpoint geometry_samples:
    """A class's feature sets → the list of its samples."""
    input:
        features="results/features/{class_id}.parquet",
    output:
        samples="results/geometry/{class_id}/samples.json",
    log:
        "logs/geometry/{class_id}/samples.log",
    params:
        version=GEOMETRY_VERSION,
    script:
        "../scripts/geometry_samples.py"


rule geometry:
    """One feature set → geometry.json and its rows of geometry.parquet."""
    input:
        topology="results/classes/{class_id}/topology.graphml",
        features="results/features/{class_id}.parquet",
    output:
        geometry="results/interchanges/{class_id}/{sample}/geometry.json",
        table="results/interchanges/{class_id}/{sample}/geometry.parquet",
    log:
        "logs/geometry/{class_id}/{sample}.log",
    params:
        version=GEOMETRY_VERSION,
        settings=config["geometry"],
        seed=config["seed"],
    threads: 1
    benchmark:
        "logs/benchmarks/geometry/{class_id}/{sample}.tsv"
    script:
        "../scripts/geometry_interchange.py"


rule geometry_table:
    """All interchanges → results/geometry.parquet."""
    input:
        geometry_tables,
    output:
        table="results/geometry.parquet",
    log:
        "logs/geometry.log",
    params:
        version=GEOMETRY_VERSION,
    script:
        "../scripts/geometry_table.py"
