"""Rule export_sumo: interchange.xodr → interchange.net.xml (netconvert); warnings to the log."""
import logging

from flyover.sumo.netconvert import run_netconvert
from flyover.workflow_log import setup_logging

setup_logging(snakemake.log[0])
log = logging.getLogger("export_sumo")
result = run_netconvert(snakemake.input.xodr, snakemake.output.net)
for w in result.warnings:
    log.info("netconvert %s", w)
log.info("netconvert %.3f s, %d warnings", result.seconds, len(result.warnings))
if not result.ok:
    raise SystemExit(f"{snakemake.input.xodr}: netconvert failed: {'; '.join(result.errors[:3])}")
