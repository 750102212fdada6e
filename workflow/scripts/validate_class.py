"""Rule validate_class: one class's exported files → its rows of validation.parquet."""
from flyover.opendrive.pipeline import export_options, validate_class
from flyover.workflow_log import setup_logging

setup_logging(snakemake.log[0])
validate_class(snakemake.input.export, snakemake.params.folder, snakemake.output.table,
               class_id=snakemake.wildcards.class_id,
               options=export_options(snakemake.params.export),
               run_qc=bool(snakemake.params.asam_qc),
               clearance_m=float(snakemake.params.clearance_m), workers=snakemake.threads)
