"""Rule validate_interchange: every check on one interchange → its rows of validation.parquet."""
from flyover.opendrive.pipeline import validate_interchange
from flyover.workflow_log import setup_logging

setup_logging(snakemake.log[0])
validate_interchange(snakemake.input.xodr, snakemake.input.geometry, snakemake.output.table,
                     run_qc=snakemake.params.asam_qc, class_id=snakemake.wildcards.class_id,
                     sample=int(snakemake.wildcards.sample))
