"""Rule export_class: one class's geometry.json files → .xodr, plan.png, SUMO network + rows."""
from flyover.opendrive.pipeline import export_class, export_options
from flyover.workflow_log import setup_logging

setup_logging(snakemake.log[0])
export_class(snakemake.input.geometry, snakemake.params.folder, snakemake.output.table,
             class_id=snakemake.wildcards.class_id,
             options=export_options(snakemake.params.export), workers=snakemake.threads)
