"""Rule report: the results folder -> results/report/index.html (the dataset browser)."""
from pathlib import Path

from flyover.report import build_report
from flyover.workflow_log import setup_logging

setup_logging(snakemake.log[0])
# the results folder is where classes.parquet lies; the report where its index.html goes
build_report(Path(snakemake.input.classes).parent, Path(snakemake.output.index).parent)
