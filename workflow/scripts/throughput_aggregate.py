"""Rule throughput: per-class tables -> throughput.parquet, throughput_stats.parquet, Fig. 4-6."""
from flyover.traffic.batch import aggregate_tables
from flyover.traffic.figures import class_names, throughput_figures
from flyover.workflow_log import setup_logging

setup_logging(snakemake.log[0])
rows, stats, series = aggregate_tables(snakemake.input.tables, snakemake.input.series,
                                       snakemake.output.table, snakemake.output.stats)
throughput_figures(rows, stats, series, class_names(snakemake.input.classes),
                   snakemake.output.fig4, snakemake.output.fig5, snakemake.output.fig6)
