# Step 6: traffic throughput in SUMO (paper §IV-B, Fig. 4-6, Tables II-III).
#
# DRAFT for the lead engineer to wire (not included in the Snakefile yet). It expects the
# reshaped export stage: per class a declared output results/export/{class_id}.parquet
# listing its interchanges (column `sample`), made by the job that also writes each
# results/interchanges/{class_id}/{sample}/interchange.net.xml (+ geometry.json and
# interchange.xodr, which give the topology's movements) beside it.
#
# One job per class runs `throughput.samples_per_class` of its interchanges (a seeded
# choice, recorded in the log) at every density in one process (libsumo in-process); an
# interchange that fails is a row with the reason. The aggregate makes the tables and
# figures. The paper's scale is config/paper.yaml (--configfile config/config.yaml
# config/paper.yaml).

# 1: first version (flows per topology movement, stable window from the balance of N(t))
THROUGHPUT_VERSION = 1


def throughput_class_tables(wildcards):
    """Every class's throughput rows (helper for common.smk)."""
    return expand("results/throughput/{class_id}.parquet", class_id=class_ids())


def throughput_class_series(wildcards):
    """Every class's entering/leaving time series (helper for common.smk)."""
    return expand("results/throughput/{class_id}/series.parquet", class_id=class_ids())


rule throughput_class:
    """One class: its chosen interchanges x densities in SUMO -> rows and time series."""
    input:
        interchanges="results/export/{class_id}.parquet",
    output:
        table="results/throughput/{class_id}.parquet",
        series="results/throughput/{class_id}/series.parquet",
    log:
        "logs/throughput/{class_id}.log",
    benchmark:
        "logs/benchmarks/throughput/{class_id}.tsv"
    threads: 1
    resources:
        mem_mb=1000,
    conda:
        "../envs/flyover.yaml"
    params:
        version=THROUGHPUT_VERSION,
        seed=config["seed"],
        throughput=config["throughput"],
    script:
        "../scripts/throughput_class.py"


rule throughput:
    """All classes -> throughput.parquet, throughput_stats.parquet and Fig. 4-6."""
    input:
        tables=throughput_class_tables,
        series=throughput_class_series,
        classes="results/classes.parquet",
    output:
        table="results/throughput.parquet",
        stats="results/throughput_stats.parquet",
        fig4="results/figures/fig4_entering_leaving.png",
        fig5="results/figures/fig5_class_throughput.png",
        fig6="results/figures/fig6_pvalues.png",
    log:
        "logs/throughput.log",
    conda:
        "../envs/flyover.yaml"
    params:
        version=THROUGHPUT_VERSION,
    script:
        "../scripts/throughput_aggregate.py"
