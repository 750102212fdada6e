"""Step 1 from open data: OpenStreetMap extracts → interchange topologies.

>>> from flyover.osm import read_osm_topologies  # doctest: +SKIP
>>> [t.summary() for t in read_osm_topologies("city.osm")]  # doctest: +SKIP
"""

from __future__ import annotations

import logging
import os

from flyover.errors import InputFormatError
from flyover.osm.build import OsmOptions, build_topologies
from flyover.osm.reader import OsmNetwork, read_motorway_network

__all__ = ["OsmOptions", "read_osm_topologies", "read_motorway_network", "build_topologies",
           "OsmNetwork", "default_options"]

log = logging.getLogger(__name__)


def default_options() -> OsmOptions:
    """Options from the ``osm:`` section of ``config/config.yaml`` when present, else defaults."""
    from flyover.config import DEFAULT_CONFIG, load_config  # noqa: PLC0415
    from flyover.errors import ConfigError  # noqa: PLC0415

    if not DEFAULT_CONFIG.exists():
        return OsmOptions()
    try:
        return OsmOptions.from_config(load_config(DEFAULT_CONFIG))
    except ConfigError as exc:
        log.warning("osm options from defaults, config unusable: %s", exc.one_line())
        return OsmOptions()


def read_osm_topologies(path: str | os.PathLike, options: OsmOptions | None = None, *, workers: int | None = None):
    """Every motorway-to-motorway interchange of an OSM extract, as topologies.

    ``.osm``, ``.osm.gz``, ``.osm.bz2`` and ``.osm.pbf`` are read by one reader
    (:func:`flyover.osm.reader.read_motorway_network`), cut to ``options.bbox`` if set.

    Each topology's name is stable (its corridors' refs and its first OSM
    node id); ``topology.attrs["osm"]`` carries the geometry for
    :func:`flyover.osm.plot.plot_osm_topology`, ramps carry ``length_m``,
    ``min_radius_m``, ``turn_deg`` (heading change from start to end, left positive, not
    wrapped: a loop about -270, in the right-hand frame of a mirrored left-hand extract;
    the road layout turns them as they really do) and ``grade_pct`` where nodes have
    ``ele``. ``workers`` > 1
    (default ``options.workers``) reads the extract's second pass and builds the places
    of a large extract in that many processes (the same result).
    """
    options = options or default_options()
    workers = options.workers if workers is None else workers
    net = read_motorway_network(path, options.highways, options.bbox, workers=workers)
    if not net.ways:
        where = " inside the bbox" if options.bbox else ""
        raise InputFormatError(f"no {' or '.join(sorted(options.highways))} way{where}: "
                               "not a motorway extract", source=str(path))
    return build_topologies(net, options, workers=workers)
