# Step 4: feature sets → concrete 3D interchanges (road layout + ramps fitted by DE).
#
# Fan-out: the samples of a class are known only once its feature sets exist, so
# checkpoint geometry_plan lists them for every class (results/geometry/plan.json, a
# cheap job); each interchange is then its own job (rule geometry) whose inputs are
# only its class's topology and feature sets, so a new city or a changed class reruns
# only its own interchanges (plus the plan and the aggregate table). Helpers: common.smk.


checkpoint geometry_plan:
    """Every class's feature sets → class id → its sample numbers (the fan-out)."""
    input:
        geometry_features,
    output:
        plan="results/geometry/plan.json",
    log:
        "logs/geometry/plan.log",
    conda:
        "../envs/flyover.yaml"
    params:
        version=GEOMETRY_VERSION,
    script:
        "../scripts/geometry_plan.py"


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
    conda:
        "../envs/flyover.yaml"
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
    conda:
        "../envs/flyover.yaml"
    params:
        version=GEOMETRY_VERSION,
    script:
        "../scripts/geometry_table.py"
