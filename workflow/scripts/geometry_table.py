"""Rule geometry_table: every class's rows → results/geometry.parquet."""
import logging

from flyover.geometry.tables import GEOMETRY_TIMING_SCHEMA, merge_tables
from flyover.workflow_log import setup_logging

setup_logging(snakemake.log[0])
n = merge_tables(snakemake.input.tables, snakemake.output.table)
merge_tables(snakemake.input.timing, snakemake.output.timing, GEOMETRY_TIMING_SCHEMA)
logging.info("geometry.parquet: %d ramps", n)
