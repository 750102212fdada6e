# Step 5: geometry.json → OpenDRIVE (.xodr, plan.png) → SUMO network; validation.
#
# One job per class and stage. export_class writes every interchange's interchange.xodr,
# plan.png and interchange.net.xml (netconvert, once per interchange) beside its
# geometry.json, and its `export` and `netconvert` rows; validate_class checks the files
# export_class made (XSD and ASAM checker for the whole class in one process of the
# checker's environment; continuity, routes on the SUMO network, clearance). An
# interchange that cannot be written or converted is failed rows with the one-line error
# naming the file and element, no half-written file, and the rest of its class is built.


rule export_class:
    """One class: every geometry.json → interchange.xodr, plan.png, interchange.net.xml."""
    input:
        geometry="results/geometry/{class_id}.parquet",
    output:
        table="results/export/{class_id}.parquet",
    log:
        "logs/export/{class_id}.log",
    conda:
        "../envs/flyover.yaml"
    params:
        version=EXPORT_VERSION,
        export=config["export"],
        folder="results/interchanges/{class_id}",
    threads: 2  # forked workers share the class's interchanges (flyover.parallel)
    # measured per Slurm job: peak 0.70 GB; CPU 3.5 s + up to 0.65 s per interchange
    # (per worker; with 2 workers the job needs up to about twice it)
    resources:
        mem_mb=2000,
        runtime=15,
    benchmark:
        "logs/benchmarks/export/{class_id}.tsv"
    script:
        "../scripts/export_class.py"


rule validate_class:
    """One class: XSD, ASAM checker (1.8 and 1.7), 3D continuity, netconvert, routes, clearance."""
    input:
        export="results/export/{class_id}.parquet",
    output:
        table="results/validation/{class_id}.parquet",
    log:
        "logs/validation/{class_id}.log",
    conda:
        "../envs/flyover.yaml"
    params:
        version=VALIDATION_VERSION,
        export=config["export"],
        asam_qc=config["validation"]["asam_qc"],
        clearance_m=config["geometry"]["clearance_m"],
        folder="results/interchanges/{class_id}",
    threads: 2  # forked workers share the class's interchanges (flyover.parallel)
    # measured per Slurm job: peak 0.73 GB (grows with the class: ~0.9 GB for 93 turbines);
    # CPU 3.5 s + up to 1.8 s per interchange (ASAM checker, netconvert routes, clearance)
    # (per worker; with 2 workers the job needs up to about twice it)
    resources:
        mem_mb=2000,
        runtime=20,
    benchmark:
        "logs/benchmarks/validation/{class_id}.tsv"
    script:
        "../scripts/validate_class.py"


rule validation:
    """Every class's rows → results/validation.parquet."""
    input:
        class_tables("validation"),
    output:
        table="results/validation.parquet",
    log:
        "logs/validation.log",
    conda:
        "../envs/flyover.yaml"
    params:
        version=VALIDATION_VERSION,
    script:
        "../scripts/export_validation_table.py"


rule clients_sample:
    """CommonRoad's conversion and map verifier on one interchange of the run (seeded)."""
    input:
        exports=class_tables("export"),
    output:
        table="results/clients_sample.parquet",
    log:
        "logs/clients_sample.log",
    conda:
        "../envs/flyover.yaml"
    params:
        version=CLIENTS_SAMPLE_VERSION,
        sample=config["validation"]["clients_sample"],
    threads: 1
    # measured: see README "Compatibility" (CPU of one conversion and verification)
    resources:
        mem_mb=1500,
        runtime=10,
    benchmark:
        "logs/benchmarks/clients_sample.tsv"
    script:
        "../scripts/clients_sample.py"


rule export:
    """Target: the export stage (every interchange's files) and the validation table."""
    input:
        "results/validation.parquet",
        class_tables("export"),
