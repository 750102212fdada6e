# Step 5: geometry.json → OpenDRIVE (.xodr, plan.png) → SUMO network; validation table.
#
# One interchange that cannot be written or converted must not cost the table: each
# interchange's validation reads only its geometry.json and writes the .xodr itself (same
# writer, same options, same bytes as export_xodr), so a failed export_xodr/export_sumo
# job (reported, nothing half-written; the default profile keeps going) leaves a failed
# `export`/`netconvert` row in results/validation.parquet instead of a missing table.
# The files themselves are targets of rule all (export_outputs in common.smk).


rule export_xodr:
    """One interchange: geometry.json → interchange.xodr (OpenDRIVE 1.8) and plan.png."""
    input:
        geometry="results/interchanges/{class_id}/{sample}/geometry.json",
    output:
        xodr="results/interchanges/{class_id}/{sample}/interchange.xodr",
        plan="results/interchanges/{class_id}/{sample}/plan.png",
    log:
        "logs/export/{class_id}/{sample}/xodr.log",
    conda:
        "../envs/flyover.yaml"
    params:
        version=EXPORT_VERSION,
        export=config["export"],
    benchmark:
        "logs/benchmarks/export_xodr/{class_id}/{sample}.tsv"
    script:
        "../scripts/export_xodr.py"


rule export_sumo:
    """One interchange: interchange.xodr → interchange.net.xml (netconvert)."""
    input:
        xodr="results/interchanges/{class_id}/{sample}/interchange.xodr",
    output:
        net="results/interchanges/{class_id}/{sample}/interchange.net.xml",
    log:
        "logs/export/{class_id}/{sample}/netconvert.log",
    conda:
        "../envs/flyover.yaml"
    params:
        version=EXPORT_VERSION,
    benchmark:
        "logs/benchmarks/export_sumo/{class_id}/{sample}.tsv"
    script:
        "../scripts/export_sumo.py"


rule validate_interchange:
    """One interchange: export, XSD, ASAM checker (1.8 and 1.7), 3D continuity, netconvert, routes,
    clearance."""
    input:
        geometry="results/interchanges/{class_id}/{sample}/geometry.json",
    output:
        table="results/interchanges/{class_id}/{sample}/validation.parquet",
    log:
        "logs/export/{class_id}/{sample}/validation.log",
    conda:
        "../envs/flyover.yaml"
    params:
        version=VALIDATION_VERSION,
        export=config["export"],
        asam_qc=config["validation"]["asam_qc"],
        clearance_m=config["geometry"]["clearance_m"],
    benchmark:
        "logs/benchmarks/validate/{class_id}/{sample}.tsv"
    script:
        "../scripts/export_validate.py"


rule validation:
    """All interchanges → results/validation.parquet."""
    input:
        tables=validation_tables,
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
