# Step 7: evaluation plugins (paper §IV-C: truck fuel per ramp), one generic step.
#
# Input: per class results/geometry/{class_id}.parquet (its ramps' rows, column `sample`),
# made by the job that also writes each results/interchanges/{class_id}/{sample}/geometry.json.
#
# The plugins to run are the keys of the config's `plugins:` section (each value is that
# plugin's own config section, validated by the schema the plugin ships). One job per
# class x plugin evaluates all of the class's interchanges in one process (plugin start-up,
# e.g. building the truck model, is paid once per class) and writes:
#   results/{table}/class_id={class_id}/sample={sample}/part-0.parquet   (hive partitions,
#       what `flyover query` reads; written beside the declared output, atomically)
#   results/plugins/{plugin}/{class_id}.parquet                          (declared output:
#       the class's rows with every column)
# An interchange a plugin cannot evaluate is logged (and a row when the plugin records
# failures), never a failed job. A plugin's version is a rerun trigger (params).
# Helpers (plugin_names, plugin_version, ...) are in common.smk.

rule plugin_class:
    """One class's interchanges through one plugin → hive partitions + the class's rows."""
    input:
        geometry="results/geometry/{class_id}.parquet",
    output:
        table="results/plugins/{plugin}/{class_id}.parquet",
    log:
        "logs/plugins/{plugin}/{class_id}.log",
    benchmark:
        "logs/benchmarks/plugins/{plugin}/{class_id}.tsv"
    threads: 2  # forked workers share the class's interchanges
    # measured per Slurm job (truck_fuel): peak 0.73 GB; CPU 3.5 s + up to 0.75 s per
    # interchange
    resources:
        mem_mb=1200,
        runtime=15,
    conda:
        "../envs/flyover.yaml"
    params:
        version=PLUGINS_VERSION,
        plugin_version=plugin_version,
        settings=plugin_config,
    script:
        "../scripts/plugins_class.py"


rule plugins:
    """Target: every configured plugin on every class (e.g. the `fuel` table)."""
    input:
        plugin_class_tables,
