"""Streaming reader of OpenStreetMap XML: the motorway network only.

The file is parsed twice with :func:`xml.etree.ElementTree.iterparse`, each
element cleared once read, so memory grows with the motorway network, not
with the file: pass 1 keeps the ``highway=motorway|motorway_link`` ways (and
``trunk|trunk_link`` when asked), pass 2 the coordinates of their nodes and
which of those nodes ordinary roads touch (exits to ordinary roads).
"""

from __future__ import annotations

import logging
import os
from dataclasses import dataclass, field
from pathlib import Path
from xml.etree.ElementTree import ParseError, iterparse

from flyover.errors import InputFormatError

__all__ = ["OsmWay", "OsmNetwork", "read_motorway_network", "normalize_ref"]

log = logging.getLogger(__name__)

_KEEP_TAGS = ("highway", "ref", "oneway", "lanes", "name", "layer", "bridge", "tunnel", "incline")


@dataclass(frozen=True)
class OsmWay:
    """A network way: id, node ids in digitised order, the tags flyover uses."""

    id: int
    nodes: tuple[int, ...]
    tags: tuple[tuple[str, str], ...]

    def tag(self, key: str, default: str | None = None) -> str | None:
        return dict(self.tags).get(key, default)


@dataclass
class OsmNetwork:
    """The motorway network of one extract.

    Attributes
    ----------
    ways
        Network ways by id.
    coords
        Node id → (lat, lon) for every node the ways use and the file holds.
    elevation
        Node id → ``ele`` in metres where tagged.
    ordinary
        Network node id → the tags (``highway``, ``ref``, ``name``) of an
        ordinary road touching it.
    """

    source: str
    ways: dict[int, OsmWay] = field(default_factory=dict)
    coords: dict[int, tuple[float, float]] = field(default_factory=dict)
    elevation: dict[int, float] = field(default_factory=dict)
    ordinary: dict[int, dict[str, str]] = field(default_factory=dict)


def normalize_ref(ref: str | None) -> str | None:
    """``"A 9"`` → ``"A9"``; ``"I 70;US 40"`` → ``"I70;US40"``; blank → ``None``."""
    if not ref or not ref.strip():
        return None
    parts = sorted({p.strip().replace(" ", "") for p in ref.split(";") if p.strip()})
    return ";".join(parts) or None


def _elements(path: str):
    """Yield the top-level elements (node, way, relation) and free them once used."""
    context = iterparse(path, events=("start", "end"))
    root = None
    depth = 0
    for event, el in context:
        if event == "start":
            if root is None:
                root = el
            depth += 1
            continue
        depth -= 1
        if depth == 1:
            yield el
            el.clear()
            root.clear()


def read_motorway_network(path: str | os.PathLike, highways: frozenset[str]) -> OsmNetwork:
    """Read the ways whose ``highway`` is in ``highways`` and their nodes.

    Raises
    ------
    InputFormatError
        The file is not OSM XML (names the file and the line where parsing failed).
    """
    src = str(path)
    if src.endswith(".pbf"):
        raise InputFormatError("OSM PBF is not supported: convert it with 'osmium cat FILE -o FILE.osm'",
                               source=src)
    net = OsmNetwork(source=src)
    bad_coords: list[int] = []
    try:
        saw_osm = False
        for el in _elements(src):
            saw_osm = True
            if el.tag != "way":
                continue
            tags = {t.get("k"): t.get("v") for t in el if t.tag == "tag"}
            if tags.get("highway") not in highways:
                continue
            wid = int(el.get("id"))
            nodes = tuple(int(n.get("ref")) for n in el if n.tag == "nd")
            if len(nodes) < 2:
                log.warning("%s: way %d: fewer than two nodes, ignored", src, wid)
                continue
            kept = tuple((k, tags[k]) for k in _KEEP_TAGS if k in tags)
            net.ways[wid] = OsmWay(wid, nodes, kept)
        needed = {n for w in net.ways.values() for n in w.nodes}
        for el in _elements(src):
            if el.tag == "node":
                nid = int(el.get("id"))
                if nid in needed:
                    lat, lon = float(el.get("lat")), float(el.get("lon"))
                    if not (-90.0 <= lat <= 90.0 and -180.0 <= lon <= 180.0):  # also nan
                        bad_coords.append(nid)
                        continue
                    net.coords[nid] = (lat, lon)
                    for t in el:
                        if t.tag == "tag" and t.get("k") == "ele":
                            try:
                                net.elevation[nid] = float(t.get("v").split()[0].rstrip("m"))
                            except (ValueError, AttributeError, IndexError):
                                log.info("%s: node %d: unreadable ele=%r", src, nid, t.get("v"))
            elif el.tag == "way":
                tags = {t.get("k"): t.get("v") for t in el if t.tag == "tag"}
                hw = tags.get("highway")
                if hw is None or hw in highways:
                    continue
                for n in el:
                    if n.tag == "nd" and int(n.get("ref")) in needed:
                        net.ordinary.setdefault(int(n.get("ref")), {
                            k: tags[k] for k in ("highway", "ref", "name") if k in tags})
    except (ParseError, LookupError) as exc:  # LookupError: a declared encoding Python does not know
        raise InputFormatError(f"malformed OSM XML: {str(exc)[:300]}", source=src) from None
    except (TypeError, ValueError) as exc:
        raise InputFormatError(f"malformed OSM element: {exc}", source=src) from None
    if not saw_osm:
        raise InputFormatError("empty OSM file", source=src)
    if bad_coords:
        log.warning("%s: %d way node(s) with lat/lon off the globe (e.g. node %d): treated as missing",
                    src, len(bad_coords), bad_coords[0])
    missing = needed - net.coords.keys()
    if missing:
        log.warning("%s: %d way node(s) missing from the file (e.g. node %d); their ways are cut there",
                    src, len(missing), min(missing))
    log.info("%s: %d network ways, %d nodes", Path(src).name, len(net.ways), len(net.coords))
    return net
