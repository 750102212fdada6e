"""Rule geometry_table: every class's rows → results/geometry.parquet."""
import logging

from flyover.geometry.tables import merge_tables
from flyover.workflow_log import setup_logging

setup_logging(snakemake.log[0])
n = merge_tables(snakemake.input, snakemake.output.table)
logging.info("geometry.parquet: %d ramps", n)
