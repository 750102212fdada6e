"""Rule validate_interchange: geometry.json → the .xodr, every check → its rows of validation.parquet."""
from flyover.opendrive.pipeline import export_options, validate_interchange
from flyover.workflow_log import setup_logging

setup_logging(snakemake.log[0])
validate_interchange(snakemake.input.geometry, snakemake.output.table,
                     class_id=snakemake.wildcards.class_id, sample=int(snakemake.wildcards.sample),
                     options=export_options(snakemake.params.export), run_qc=snakemake.params.asam_qc,
                     clearance_m=float(snakemake.params.clearance_m))
