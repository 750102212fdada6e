# flyover: real interchanges → topology classes → covering arrays → 3D
# interchanges → OpenDRIVE/SUMO → evaluation. See README.md and ../shared/DESIGN.md.
from snakemake.utils import min_version

min_version("9.10")


configfile: "config/config.yaml"


include: "workflow/rules/common.smk"
include: "workflow/rules/topology.smk"
include: "workflow/rules/sampling.smk"
include: "workflow/rules/geometry.smk"
include: "workflow/rules/export.smk"
include: "workflow/rules/throughput.smk"
include: "workflow/rules/plugins.smk"
include: "workflow/rules/report.smk"


# Aggregates and targets run where Snakemake runs (seconds each), not as cluster jobs.
localrules:
    all,
    topology,
    sampling,
    coverage_table,
    geometry,
    geometry_table,
    export,
    validation,
    plugins,


rule all:
    input:
        "results/classes.parquet",
        "results/rejected.parquet",
        "results/classes/manifest.json",
        class_topology_outputs,
        "results/coverage.parquet",
        "results/geometry.parquet",
        class_tables("export"),
        "results/validation.parquet",
        "results/clients_sample.parquet",
        "results/throughput.parquet",
        "results/throughput_stats.parquet",
        plugin_class_tables,
        "results/report/index.html",
    default_target: True


onsuccess:
    print_summary(log)


onerror:
    print_summary(log, failed=True)
