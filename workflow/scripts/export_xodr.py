"""Rule export_xodr: geometry.json → interchange.xodr and plan.png."""
from flyover.opendrive.pipeline import export_interchange, export_options
from flyover.workflow_log import setup_logging

setup_logging(snakemake.log[0])
export_interchange(snakemake.input.geometry, snakemake.output.xodr, snakemake.output.plan,
                   export_options(snakemake.config))
