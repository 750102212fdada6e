# Step 6: traffic throughput in SUMO (paper §IV-B, Fig. 4-6, Tables II-III).
#
# Input: per class results/export/{class_id}.parquet listing its interchanges (column
# `sample`), made by the job that also writes each
# results/interchanges/{class_id}/{sample}/interchange.net.xml (+ geometry.json and
# interchange.xodr, which give the topology's movements) beside it.
#
# One job per class runs `throughput.samples_per_class` of its interchanges (a seeded
# choice, recorded in the log) at every density in one process (libsumo in-process); an
# interchange that fails is a row with the reason. The aggregate makes the tables and
# figures. The paper's scale is config/paper.yaml (--configfile config/config.yaml
# config/paper.yaml).

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
    threads: 2  # forked workers share the class's runs (one libsumo each)
    # measured per Slurm job: peak 0.66 GB; CPU up to 7 s per SUMO run (2000 s simulated):
    # half a minute per run (samples x densities) leaves a loaded node 4x the time
    resources:
        mem_mb=1000,
        runtime=5
        + config["throughput"]["samples_per_class"] * len(config["throughput"]["densities"]) // 2,
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
        tables=class_tables("throughput"),
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
