# Step 8: the dataset browser (static HTML, flyover/report/): results/report/index.html and
# the pages, figures and assets beside it (overview, a page per class and per interchange,
# evaluation). Opens from disk; links to the results files where they lie.
#
# Inputs are every table and picture it shows, so it is rebuilt exactly when one of them
# changes (a per-interchange file changes only with its class's table, which is declared).
# `flyover report` builds the same pages from whatever a results folder holds.

# 1: first version
REPORT_VERSION = 2  # 2: no fitting times (the report is byte-reproducible)


rule report:
    """Everything the pipeline made -> results/report/index.html (the dataset browser)."""
    input:
        classes="results/classes.parquet",
        rejected="results/rejected.parquet",
        manifest="results/classes/manifest.json",
        cities=expand("results/topology/{city}", city=CITIES),
        topology=class_topology_outputs,
        coverage="results/coverage.parquet",
        geometry="results/geometry.parquet",
        geometry_classes=class_tables("geometry"),
        export=class_tables("export"),
        validation="results/validation.parquet",
        throughput="results/throughput.parquet",
        throughput_stats="results/throughput_stats.parquet",
        figures=expand(
            "results/figures/{figure}.png",
            figure=["fig4_entering_leaving", "fig5_class_throughput", "fig6_pvalues"],
        ),
        plugins=plugin_class_tables,
    output:
        index="results/report/index.html",
    log:
        "logs/report.log",
    benchmark:
        "logs/benchmarks/report.tsv"
    threads: 1
    resources:
        mem_mb=1000,
    conda:
        "../envs/flyover.yaml"
    params:
        version=REPORT_VERSION,
    script:
        "../scripts/report.py"
