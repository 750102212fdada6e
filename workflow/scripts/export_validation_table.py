"""Rule validation: every class's rows → results/validation.parquet."""
from flyover.opendrive.pipeline import collect_validation
from flyover.workflow_log import setup_logging

setup_logging(snakemake.log[0])
collect_validation(snakemake.input, snakemake.output.table)
