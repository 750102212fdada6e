# Step 7: evaluation plugins (paper §IV-C: truck fuel per ramp), one generic step.
#
# DRAFT for the lead engineer to wire (not included in the Snakefile yet). It expects the
# reshaped geometry stage: per class a declared output results/geometry/{class_id}.parquet
# (its ramps' rows, column `sample`), made by the job that also writes each
# results/interchanges/{class_id}/{sample}/geometry.json beside it.
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
# Helpers below belong in common.smk once wired.

# 1: first version (generic plugin step; truck_fuel 0.1.0)
PLUGINS_VERSION = 1


wildcard_constraints:
    plugin=r"[a-z][a-z0-9_]*",


def plugin_names():
    """The plugins the config asks for (keys of `plugins:`)."""
    return sorted(config.get("plugins") or {})


def plugin_version(wildcards):
    """The installed version of a plugin's distribution (metadata only, nothing imported)."""
    from flyover.plugins.registry import plugin_entry_points

    for info in plugin_entry_points():
        if info.name == wildcards.plugin:
            return info.distribution_version
    raise ValueError(f"plugin {wildcards.plugin!r} is configured but not installed "
                     f"(`flyover plugins` lists what is)")


def plugin_config(wildcards):
    """A plugin's config section (the plugin fills its defaults and validates it)."""
    return config["plugins"][wildcards.plugin] or {}


def plugin_class_tables(wildcards):
    """Every configured plugin's rows of every class."""
    return expand("results/plugins/{plugin}/{class_id}.parquet", plugin=plugin_names(),
                  class_id=class_ids())


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
    threads: 1
    resources:
        mem_mb=1000,
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
