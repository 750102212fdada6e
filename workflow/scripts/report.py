"""Rule report: the results folder -> results/report/index.html (the dataset browser)."""
from pathlib import Path

from flyover.report import build_report
from flyover.workflow_log import setup_logging

setup_logging(snakemake.log[0])
build_report(snakemake.params.results, Path(snakemake.output.index).parent)
