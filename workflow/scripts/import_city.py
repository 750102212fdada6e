"""Rule import_city: every file of one city → topology GraphML files + index."""
import dataclasses
import logging

from flyover.osm import OsmOptions
from flyover.topology.city import import_city
from flyover.workflow_log import setup_logging

setup_logging(snakemake.log[0])
index = import_city(
    snakemake.params.city,
    snakemake.input,
    snakemake.output[0],
    # the rule's threads build the places of a large OSM extract in parallel (same result)
    osm_options=dataclasses.replace(OsmOptions.from_config({"osm": snakemake.params.osm}),
                                    workers=max(1, int(snakemake.threads))),
)
logging.getLogger("import_city").info(
    "%s: %d interchanges, %d rejected",
    snakemake.params.city,
    len(index["interchanges"]),
    len(index["rejected"]),
)
