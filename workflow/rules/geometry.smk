# Step 4: feature sets → concrete 3D interchanges (road layout + ramps fitted by DE).
#
# One job per class (process start-up and imports are paid once per class, not per
# interchange): its declared output is the class's rows of geometry.parquet; beside it the
# job writes results/interchanges/{class_id}/{sample}/geometry.json for every sample
# (flyover.geometry.batch). A changed class or a new city reruns only its own classes
# (plus the aggregate table). Helpers: common.smk.


rule geometry_class:
    """One class's feature sets → every sample's geometry.json and the class's geometry rows."""
    input:
        topology="results/classes/{class_id}/topology.graphml",
        features="results/features/{class_id}.parquet",
    output:
        table="results/geometry/{class_id}.parquet",
        timing="results/geometry_timing/{class_id}.parquet",
    log:
        "logs/geometry/{class_id}.log",
    conda:
        "../envs/flyover.yaml"
    params:
        version=GEOMETRY_VERSION,
        settings=config["geometry"],
        seed=config["seed"],
        folder="results/interchanges/{class_id}",
    threads: 2  # forked workers share the class's interchanges (flyover.parallel)
    # measured per Slurm job (README "Running on a cluster"): peak 0.65 GB; CPU 3.5 s
    # start-up + up to 5.5 s per interchange (stack4) -> 106 interchanges in ~10 min
    # (per worker; with 2 workers the job needs up to about twice it)
    resources:
        mem_mb=2000,
        runtime=60,
    benchmark:
        "logs/benchmarks/geometry/{class_id}.tsv"
    script:
        "../scripts/geometry_class.py"


rule geometry_table:
    """Every class's rows → results/geometry.parquet (and the fitting times beside it)."""
    input:
        tables=class_tables("geometry"),
        timing=class_tables("geometry_timing"),
    output:
        table="results/geometry.parquet",
        timing="results/geometry_timing.parquet",
    log:
        "logs/geometry.log",
    conda:
        "../envs/flyover.yaml"
    params:
        version=GEOMETRY_VERSION,
    script:
        "../scripts/geometry_table.py"


rule geometry:
    """Target: the geometry stage only (every class's interchanges and geometry.parquet)."""
    input:
        "results/geometry.parquet",
