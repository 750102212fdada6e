"""Rule export_xodr: geometry.json → interchange.xodr and plan.png (both or neither)."""
import logging

from flyover.errors import FlyoverError
from flyover.opendrive.pipeline import export_interchange, export_options
from flyover.workflow_log import setup_logging

setup_logging(snakemake.log[0])
try:
    export_interchange(snakemake.input.geometry, snakemake.output.xodr, snakemake.output.plan,
                       export_options(snakemake.params.export))
except FlyoverError as exc:  # the validation table records it too (its `export` row)
    logging.error("%s", exc.one_line())
    raise SystemExit(exc.one_line()) from None
