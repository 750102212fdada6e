"""Reader of OpenStreetMap extracts (``.osm``, ``.osm.gz``, ``.osm.bz2``, ``.osm.pbf``): the motorway network.

One reader for every format, through pyosmium (the Python binding of
libosmium, ``osmium`` on PyPI), which decodes XML, compressed XML and PBF in
C++. The file is read twice, with filters run inside libosmium so that only
what is needed reaches Python:

1. ways tagged ``highway=motorway|motorway_link`` (and ``trunk|trunk_link``
   when asked), with their nodes' coordinates from libosmium's node-location
   index (``flex_mem``: dense or sparse as the ids are); no node object
   reaches Python;
2. the ``highway=*`` ways (an ordinary road touching the network is an exit)
   and the nodes tagged ``ele``.

Memory: the node-location index (8–16 bytes per node of the file) and the
motorway network.
"""

from __future__ import annotations

import gc
import logging
import os
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

from flyover.errors import InputFormatError

__all__ = ["OsmWay", "OsmNetwork", "read_motorway_network", "normalize_ref", "OSM_SUFFIXES", "is_osm_file"]

log = logging.getLogger(__name__)

_KEEP_TAGS = ("highway", "ref", "oneway", "lanes", "name", "layer", "bridge", "tunnel", "incline",
              "driving_side")

#: the file name endings read as OpenStreetMap extracts (longest first)
OSM_SUFFIXES = (".osm.pbf", ".osm.bz2", ".osm.gz", ".pbf", ".osm")


def is_osm_file(path: str | os.PathLike) -> bool:
    """Whether ``path``'s name ends like an OpenStreetMap extract (case ignored)."""
    return str(path).lower().endswith(OSM_SUFFIXES)


@dataclass(frozen=True)
class OsmWay:
    """A network way: id, node ids in digitised order, the tags flyover uses."""

    id: int
    nodes: tuple[int, ...]
    tags: tuple[tuple[str, str], ...]

    def tag(self, key: str, default: str | None = None) -> str | None:
        for k, v in self.tags:  # (a handful of tags: no dict built per call)
            if k == key:
                return v
        return default


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


def _format_error(src: str, exc: Exception) -> InputFormatError:
    """libosmium's error as one line naming the file and what kind of file it was read as."""
    msg = " ".join(str(exc).split())[:300]
    low = src.lower()
    if "could not detect file format" in msg.lower():
        return InputFormatError(f"not an OSM extract (expected one of {', '.join(OSM_SUFFIXES)})", source=src)
    if msg.lower().startswith("open failed"):
        return InputFormatError("cannot read: " + msg.split(":")[-1].strip(), source=src)
    kind = "OSM PBF" if low.endswith(".pbf") else "OSM XML"
    if "eof" in msg.lower() or "truncated" in msg.lower():
        return InputFormatError(f"malformed {kind} (file cut short?): {msg}", source=src)
    return InputFormatError(f"malformed {kind}: {msg}", source=src)


def _ele(value: str | None) -> float | None:
    try:
        ele = float(value.split()[0].rstrip("m"))
    except (ValueError, AttributeError, IndexError):
        return None
    return ele if ele == ele and abs(ele) < 1e5 else None


@contextmanager
def gc_paused():
    """Python's cyclic garbage collector off for a while: reading makes millions of small
    acyclic objects (node ids, coordinates), and each of the collector's full passes walks all
    of them again, so that the time grew faster than the extract."""
    was = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was:
            gc.enable()


def read_motorway_network(path: str | os.PathLike, highways: frozenset[str],
                          bbox: tuple[float, float, float, float] | None = None, workers: int = 1) -> OsmNetwork:
    """Read the ways whose ``highway`` is in ``highways`` and their nodes.

    Parameters
    ----------
    path
        ``.osm``, ``.osm.gz``, ``.osm.bz2`` or ``.osm.pbf`` (the format is taken from the name).
    highways
        The ``highway`` values of the network.
    bbox
        ``(min_lon, min_lat, max_lon, max_lat)``: keep only network ways with a
        node inside (each kept whole), as extracts are cut.
    workers
        Processes that share the second pass (the ordinary roads' nodes are looked at in
        Python: each process looks at every ``workers``-th way). The result does not depend on it.

    Raises
    ------
    InputFormatError
        The file is not an OSM extract, is malformed or cut short (names the file
        and what libosmium reported); nothing is returned then.
    """
    import osmium  # noqa: PLC0415 (optional stage: the import is light, libosmium is not)

    src = str(path)
    net = OsmNetwork(source=src)
    if not Path(src).is_file():
        raise InputFormatError("cannot read: no such file", source=src)
    if not is_osm_file(src):
        raise InputFormatError(f"not an OSM extract name (expected one of {', '.join(OSM_SUFFIXES)})",
                               source=src)
    ways: dict[int, OsmWay] = {}
    coords: dict[int, tuple[float, float]] = {}
    with gc_paused():  # (nothing read makes a reference cycle)
        try:
            # 1. the network's ways (tag filter in libosmium) with their nodes' locations
            #    (node-location index in libosmium: no node reaches Python)
            flt = osmium.filter.TagFilter(*(("highway", h) for h in sorted(highways)))
            proc = osmium.FileProcessor(src, osmium.osm.NODE | osmium.osm.WAY).with_locations("flex_mem") \
                .with_filter(osmium.filter.EntityFilter(osmium.osm.WAY)).with_filter(flt)
            for w in proc:
                nodes, pts = [], []
                for nd in w.nodes:
                    nodes.append(nd.ref)
                    loc = nd.location
                    if loc.valid():
                        pts.append((nd.ref, loc.lat, loc.lon))
                if len(nodes) < 2:
                    log.warning("%s: way %d: fewer than two nodes, ignored", src, w.id)
                    continue
                if bbox is not None and not any(bbox[0] <= lon <= bbox[2] and bbox[1] <= lat <= bbox[3]
                                                 for _, lat, lon in pts):
                    continue
                tags = w.tags  # (only the kept keys are looked up, in libosmium)
                ways[w.id] = OsmWay(w.id, tuple(nodes), tuple((k, v) for k in _KEEP_TAGS
                                                              if (v := tags.get(k)) is not None))
                for ref, lat, lon in pts:
                    coords[ref] = (lat, lon)
            needed = {n for w in ways.values() for n in w.nodes}
            # 2. ordinary roads touching the network (exits) and the ele of network nodes: the
            #    nodes tagged ele and the ways tagged highway reach Python. (libosmium's id
            #    tracker would pick the ways holding a network node in C++, but its id set is
            #    dense: ~1.5 GB for node ids spread over today's OSM id range.)
            if ways:
                net.elevation, net.ordinary = _exits_and_elevation(src, highways, needed, workers)
        except (RuntimeError, ValueError, UnicodeDecodeError, osmium.InvalidLocationError) as exc:
            # libosmium: unknown format, XML/PBF errors, cut-short files, unreadable coordinates
            raise _format_error(src, exc) from None
    missing = [(wid, n) for wid, w in ways.items() for n in w.nodes if n not in coords]
    missing.sort()
    net.ways, net.coords = ways, coords
    if missing:
        w0, n0 = missing[0]
        log.warning("%s: way %d refers to node %d, missing from the file or off the globe "
                    "(%d such reference(s)): the way is cut there", src, w0, n0, len(missing))

    log.info("%s: %d network ways, %d nodes", Path(src).name, len(net.ways), len(net.coords))
    return net


class _PassError(Exception):
    """libosmium's error in a process of the second pass, handed back as its message."""


#: (file, network highways, network node ids, processes) while forked processes read the
#: second pass (inherited, not pickled to them)
_SECOND: tuple[str, frozenset[str], set[int], int] | None = None


def _second_pass_share(share: int) -> tuple[dict[int, float], list[tuple[int, int, int, dict[str, str]]]]:
    """One share of the second pass: the ele of network nodes (share 0 only) and, for every
    ``shares``-th way tagged ``highway`` off the network, the network nodes it holds, as
    ``(way's rank in the file, node's rank in the way, node id, tags)``."""
    import osmium  # noqa: PLC0415

    src, highways, needed, shares = _SECOND
    elevation: dict[int, float] = {}
    hits: list[tuple[int, int, int, dict[str, str]]] = []
    seen: set[int] = set()
    second = osmium.FileProcessor(src, osmium.osm.NODE | osmium.osm.WAY) \
        .with_filter(osmium.filter.KeyFilter("ele").enable_for(osmium.osm.NODE)) \
        .with_filter(osmium.filter.KeyFilter("highway").enable_for(osmium.osm.WAY))
    rank = -1
    try:
        for o in second:
            if o.is_node():
                if share == 0 and "ele" in o.tags and o.id in needed:
                    ele = _ele(o.tags["ele"])
                    if ele is None:
                        log.info("%s: node %d: unreadable ele=%r", src, o.id, o.tags["ele"])
                    else:
                        elevation[o.id] = ele
                continue
            rank += 1
            if rank % shares != share:
                continue
            hw = o.tags.get("highway")
            if hw is None or hw in highways:
                continue
            info = None
            for i, nd in enumerate(o.nodes):
                ref = nd.ref
                if ref in needed and ref not in seen:
                    if info is None:
                        info = {k: o.tags[k] for k in ("highway", "ref", "name") if k in o.tags}
                    seen.add(ref)
                    hits.append((rank, i, ref, info))
    except (RuntimeError, ValueError, UnicodeDecodeError, osmium.InvalidLocationError) as exc:
        raise _PassError(str(exc)) from None
    return elevation, hits


def _exits_and_elevation(src: str, highways: frozenset[str], needed: set[int],
                         workers: int) -> tuple[dict[int, float], dict[int, dict[str, str]]]:
    """The second pass (``workers`` forked processes, each on every ``workers``-th way): the
    ele of network nodes, and network node id → tags of the first ordinary road (in file
    order) holding it.

    Raises
    ------
    RuntimeError
        libosmium's error in any of the processes (its message).
    """
    global _SECOND  # noqa: PLW0603 (inherited by the forked processes, not pickled to them)
    _SECOND = (src, highways, needed, max(1, workers))
    try:
        if workers > 1:
            import multiprocessing  # noqa: PLC0415

            with multiprocessing.get_context("fork").Pool(workers) as pool:
                shares = pool.map(_second_pass_share, range(workers))
        else:
            shares = [_second_pass_share(0)]
    except _PassError as exc:
        raise RuntimeError(str(exc)) from None
    finally:
        _SECOND = None
    elevation = shares[0][0]
    ordinary: dict[int, dict[str, str]] = {}
    for _, _, ref, info in sorted((h for _, hits in shares for h in hits), key=lambda h: h[:2]):
        ordinary.setdefault(ref, info)  # the first way in the file holding the node
    return elevation, ordinary
