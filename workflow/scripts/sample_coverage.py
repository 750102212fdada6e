"""Rule coverage_table: every class's coverage row → results/coverage.parquet."""
import pyarrow.parquet as pq

from flyover.sampling.sample import COVERAGE_SCHEMA
from flyover.topology.tables import write_parquet
from flyover.workflow_log import setup_logging

setup_logging(snakemake.log[0])
rows = [row for path in snakemake.input for row in pq.read_table(path).to_pylist()]
rows.sort(key=lambda r: r["class_id"])
write_parquet(rows, COVERAGE_SCHEMA, snakemake.output.table)
