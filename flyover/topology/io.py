"""Reading and writing topologies: native GraphML, FLYOVER dataset GraphML, YAML spec.

Formats (see ``../shared/DESIGN.md`` and the README):

* **native GraphML** — node ``kind`` (road|ramp), ``expressway``, ``lanes``;
  edge ``label``, ``pos``.
* **FLYOVER dataset GraphML** — node ``type`` (main|link), ``name``, ``lane``,
  ``radius``, ``curv``, ``geo``, ``ctrl``; edge ``ramp`` (out|in), ``junc``
  (right|left|middle), ``part``. The expressway is the letter of a road name.
* **YAML spec** — the hand-writable format of city folders::

      name: trumpet
      expressways: {A: [A1, A2], B: [B1, B2]}
      lanes: {A1: 3}
      ramps:
        r1: {from: A1 right, to: B2 straight}
        r2: {from: [B1 straight], to: [r1 left]}

  An endpoint is ``<node> <side> [@<pos>]`` with side ``right``, ``left`` or
  ``straight``.
"""

from __future__ import annotations

import io
import os
import re
import tempfile
from pathlib import Path
from typing import Any, Iterable
from xml.etree.ElementTree import ParseError

import networkx as nx
import yaml

from flyover.errors import FlyoverError, InputFormatError, TopologyError
from flyover.safe_yaml import load_yaml
from flyover.topology.model import Connection, Kind, Label, Ramp, Road, Topology
from flyover.topology.names import check_name

__all__ = [
    "TOPOLOGY_SUFFIXES",
    "remove_stale_temporaries",
    "write_if_changed",
    "read_graphml",
    "write_graphml",
    "graphml_bytes",
    "read_yaml_spec",
    "write_yaml_spec",
    "read_topologies",
    "atomic_write",
]

#: file suffixes a city folder may hold, mapped to their reader's name
TOPOLOGY_SUFFIXES = (".graphml", ".yaml", ".yml", ".osm", ".pbf", ".gz", ".bz2")

_SIDE_WORDS = {"right": "right", "left": "left", "straight": "middle", "middle": "middle"}


def file_mode() -> int:
    """The mode a newly created file gets under the current umask (``0o666 & ~umask``).

    Temporary files (:func:`tempfile.mkstemp`) are private (``0o600``); results
    renamed from them get this mode instead, like any file the user creates.
    """
    mask = os.umask(0o022)
    os.umask(mask)
    return 0o666 & ~mask


def remove_stale_temporaries(folder: str | os.PathLike, name: str = "*") -> list[Path]:
    """Remove what atomic writes killed before their rename left in ``folder`` (recursively):
    hidden files ``.{name}.*.tmp`` (or ``….tmp.net.xml``, netconvert's). ``name`` (a glob)
    limits it to the temporaries of one file name. Returns what was removed."""
    folder = Path(folder)
    if not folder.is_dir():
        return []
    stale = [p for p in folder.rglob(f".{name}.*.tmp*") if p.is_file()
             and (p.name.endswith(".tmp") or p.name.endswith(".tmp.net.xml"))]
    for p in stale:
        p.unlink(missing_ok=True)
    return stale


def write_if_changed(path: str | os.PathLike, data: bytes) -> bool:
    """:func:`atomic_write` unless ``path`` already holds exactly ``data`` (then its mtime
    stays, and Snakemake sees no change); returns whether it wrote."""
    path = Path(path)
    try:
        if path.read_bytes() == data:
            return False
    except OSError:
        pass
    atomic_write(path, data)
    return True


def atomic_write(path: str | os.PathLike, data: bytes) -> None:
    """Write ``data`` to ``path`` via a temporary file and rename (never half-written)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
        os.chmod(tmp, file_mode())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _parse_label(value: Any, source: str | None, element: str) -> Label:
    try:
        return Label(str(value))
    except ValueError:
        raise TopologyError(
            f"unknown label {value!r} (expected one of {', '.join(x.value for x in Label)})",
            source=source, element=element) from None


# -- GraphML ------------------------------------------------------------------

_CORE_NODE_KEYS = frozenset({"kind", "expressway", "lanes"})


def graphml_bytes(topology: Topology) -> bytes:
    """The native GraphML of ``topology`` as bytes (deterministic)."""
    g = nx.DiGraph(name=topology.name)
    for n, d in sorted(topology.graph.nodes(data=True)):
        attrs = {"kind": d["kind"].value}
        if d["kind"] is Kind.ROAD:
            attrs["expressway"] = d["expressway"]
        if d.get("lanes") is not None:
            attrs["lanes"] = int(d["lanes"])
        # measured extras (OSM ramp length/radius/grade, FLYOVER radius/ctrl ...)
        attrs.update((k, v) for k, v in sorted(d.items())
                     if k not in _CORE_NODE_KEYS and isinstance(v, (str, int, float)) and not isinstance(v, bool))
        g.add_node(n, **attrs)
    for u, v, d in sorted(topology.graph.edges(data=True), key=lambda e: (e[0], e[1])):
        attrs = {"label": d["label"].value}
        if d.get("pos") is not None:
            attrs["pos"] = float(d["pos"])
        g.add_edge(u, v, **attrs)
    buf = io.BytesIO()
    nx.write_graphml(g, buf, encoding="utf-8", prettyprint=True)
    return buf.getvalue()


def write_graphml(topology: Topology, path: str | os.PathLike) -> None:
    """Write ``topology`` as native GraphML, atomically."""
    atomic_write(path, graphml_bytes(topology))


def read_graphml(path: str | os.PathLike, name: str | None = None) -> Topology:
    """Read native or FLYOVER-dataset GraphML (detected from the attributes).

    The topology's name is ``name``, else the graph's ``name`` attribute, else the
    file name without suffix; it must be a safe name (:mod:`flyover.topology.names`).
    FLYOVER-dataset nodes are keyed on their GraphML id (the dataset's ``name``
    attribute can repeat within a file and is kept as a node attribute).

    Raises
    ------
    InputFormatError
        The file is not GraphML or follows neither schema.
    UnsafeNameError
        The name is not a safe name (it becomes a file name).
    TopologyError
        The topology breaks a model rule.
    """
    src = str(path)
    try:
        g = nx.read_graphml(path, force_multigraph=True)
    except (ParseError, nx.NetworkXError, ValueError, KeyError, LookupError) as exc:
        # LookupError: an XML declaration naming an unknown encoding
        raise InputFormatError(f"not readable as GraphML: {_first_line(exc)}", source=src) from None
    name = check_name(name or g.graph.get("name") or Path(path).stem, source=src)
    node_keys = set().union(*(d.keys() for _, d in g.nodes(data=True))) if g.nodes else set()
    if "type" in node_keys and "kind" not in node_keys:
        return _from_flyover_graph(g, name, src)
    return _from_native_graph(g, name, src)


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip()
    return (text.splitlines()[0] if text else type(exc).__name__)[:300]


def _lanes(value: Any, src: str | None, el: str) -> int | None:
    """A lane count from a file: a positive integer (``None`` when absent)."""
    if value is None or value == "":
        return None
    if isinstance(value, bool) or not isinstance(value, (int, str)):
        number = None
    else:
        try:
            number = int(value)
        except ValueError:
            number = None
    if number is None or number < 1:
        raise TopologyError(f"lanes must be a positive integer, got {value!r}"[:300], source=src, element=el)
    return number


def _edges_checked(g: nx.MultiDiGraph, src: str):
    seen = set()
    for u, v, d in g.edges(data=True):
        if (u, v) in seen:
            raise TopologyError("duplicate edge", source=src, element=f"{u}->{v}")
        seen.add((u, v))
        yield u, v, d


def _from_native_graph(g: nx.MultiDiGraph, name: str, src: str) -> Topology:
    roads, ramps, extras = [], [], {}
    for n, d in g.nodes(data=True):
        extras[n] = {k: v for k, v in d.items() if k not in _CORE_NODE_KEYS}
        kind = d.get("kind")
        if kind == Kind.ROAD.value:
            roads.append(Road(n, str(d.get("expressway", "")), _lanes(d.get("lanes"), src, n)))
        elif kind == Kind.RAMP.value:
            ramps.append(Ramp(n))
        else:
            raise TopologyError(f"unknown kind {kind!r} (expected road or ramp)", source=src, element=n)
    conns = []
    for u, v, d in _edges_checked(g, src):
        el = f"{u}->{v}"
        if "label" not in d:
            raise TopologyError("edge has no label", source=src, element=el)
        conns.append(Connection(u, v, _parse_label(d["label"], src, el), _pos(d.get("pos"), src, el)))
    return Topology.build(name, roads, ramps, conns, source=src, node_attrs=extras)


def _pos(value: Any, src: str | None, el: str) -> float | None:
    if value is None or value == "":
        return None
    try:
        return float(value)
    except (TypeError, ValueError):
        raise TopologyError(f"pos must be a number, got {_short(value)}", source=src, element=el) from None


def _short(value: Any, limit: int = 80) -> str:
    """``repr(value)``, cut to ``limit`` characters (error messages stay one short line)."""
    text = repr(value) if not isinstance(value, (list, dict)) else f"<{type(value).__name__}>"
    return text if len(text) <= limit else text[:limit] + "..."


_FLYOVER_NODE_EXTRAS = ("radius", "curv", "geo", "ctrl")


def _from_flyover_graph(g: nx.MultiDiGraph, name: str, src: str) -> Topology:
    """The FLYOVER dataset's schema: nodes keyed on their GraphML id (the dataset's
    ``name`` attribute can repeat within a file); ``name`` is kept as a node attribute
    and gives a road its expressway (its leading letters)."""
    roads, ramps, extras = [], [], {}
    shown = {n: n if str(d.get("name") or n) == n else f"{n} ({d.get('name')})"
             for n, d in g.nodes(data=True)}
    for n, d in g.nodes(data=True):
        el, typ = shown[n], d.get("type")
        extras[n] = {k: d[k] for k in _FLYOVER_NODE_EXTRAS if k in d}
        label = str(d["name"]) if d.get("name") not in (None, "") else n
        if "name" in d:
            extras[n]["name"] = label
        lanes = _lanes(d.get("lane"), src, el)
        if typ == "main":
            m = re.match(r"[A-Za-z]+", label)
            if not m:
                raise TopologyError("road name must start with its expressway letter", source=src, element=el)
            roads.append(Road(n, m.group(0), lanes))
        elif typ == "link":
            if lanes is not None:
                extras[n]["lanes"] = lanes
            ramps.append(Ramp(n))
        else:
            raise TopologyError(f"unknown node type {typ!r} (expected main or link)"[:300], source=src,
                                element=el)
    conns = []
    for u, v, d in _edges_checked(g, src):
        el = f"{shown[u]}->{shown[v]}"
        ramp, junc = d.get("ramp"), d.get("junc")
        if ramp not in ("out", "in"):
            raise TopologyError(f"unknown ramp {ramp!r} (expected out or in)"[:300], source=src, element=el)
        if junc not in ("right", "left", "middle"):
            raise TopologyError(f"unknown junc {junc!r} (expected right, left or middle)"[:300],
                                source=src, element=el)
        conns.append(Connection(u, v, Label.of(ramp == "out", junc), _pos(d.get("part"), src, el)))
    return Topology.build(name, roads, ramps, conns, source=src, node_attrs=extras,
                          attrs={"format": "flyover-graphml"})


# -- YAML spec ----------------------------------------------------------------


def _endpoint(item: Any) -> tuple[str, str, str | None] | None:
    """``"<node> <side> [@<pos>]"`` → (node, side word, pos text), ``None`` if malformed.

    Parsed by splitting, not a regular expression: linear in the text whatever it holds.
    """
    if not isinstance(item, str):
        return None
    head, at, pos = item.partition("@")
    parts = head.split()
    pos = pos.strip() if at else None
    if len(parts) != 2 or parts[1] not in _SIDE_WORDS or (at and (not pos or len(pos.split()) != 1)):
        return None
    return parts[0], parts[1], pos


def read_yaml_spec(path: str | os.PathLike) -> Topology:
    """Read a YAML spec (format in the module docstring and the README).

    The file is parsed by :func:`flyover.safe_yaml.load_yaml` (bounded work); the
    name (``name:``, else the file name without suffix) must be a safe name.

    Raises
    ------
    InputFormatError
        Not UTF-8, malformed YAML, or not a spec (naming the key at fault).
    UnsafeNameError
        The name is not a safe name (it becomes a file name).
    TopologyError
        The topology breaks a model rule.
    """
    src = str(path)
    doc = load_yaml(path, error=InputFormatError)
    return topology_from_spec(doc, src, default_name=Path(path).stem)


def topology_from_spec(doc: Any, src: str | None, default_name: str = "interchange") -> Topology:
    """Build a topology from a parsed YAML spec mapping."""
    if not isinstance(doc, dict):
        raise InputFormatError("a YAML spec must be a mapping", source=src)
    unknown = set(doc) - {"name", "expressways", "lanes", "ramps", "design", "source"}
    if unknown:
        raise InputFormatError(f"unknown key(s): {', '.join(sorted(map(str, unknown)))}", source=src,
                               element=sorted(map(str, unknown))[0])
    exps = doc.get("expressways")
    if not isinstance(exps, dict) or not exps:
        raise InputFormatError("'expressways' must map names to lists of carriageways", source=src,
                               element="expressways")
    lanes = doc.get("lanes") or {}
    if not isinstance(lanes, dict):
        raise InputFormatError("'lanes' must map carriageways to integers", source=src, element="lanes")
    name = doc.get("name")
    if name is None or name == "":
        name = default_name
    elif isinstance(name, bool) or not isinstance(name, (str, int)):
        raise InputFormatError(f"'name' must be a text, got {_short(name)}", source=src, element="name")
    name = check_name(str(name), source=src)
    roads = []
    for exp, cws in exps.items():
        if not isinstance(cws, list) or not all(isinstance(c, str) for c in cws):
            raise InputFormatError("carriageways must be a list of names", source=src,
                                   element=f"expressways.{exp}")
        roads += [Road(c, str(exp), _lanes(lanes.get(c), src, f"lanes.{c}")) for c in cws]
    road_ids = {r.id for r in roads}
    for c in lanes:
        if c not in road_ids:
            raise TopologyError("lanes given for an unknown carriageway", source=src, element=f"lanes.{c}")
    ramps_doc = doc.get("ramps")
    if not isinstance(ramps_doc, dict) or not ramps_doc:
        raise InputFormatError("'ramps' must map ramp names to {from:, to:}", source=src, element="ramps")
    ramps, conns = [], []
    for rid, ends in ramps_doc.items():
        rid = str(rid)
        ramps.append(Ramp(rid))
        if not isinstance(ends, dict) or set(ends) - {"from", "to"}:
            raise InputFormatError("a ramp is {from: ..., to: ...}", source=src, element=f"ramps.{rid}")
        for key, is_out in (("from", True), ("to", False)):
            items = ends.get(key) or []
            el = f"ramps.{rid}.{key}"
            if not isinstance(items, (str, list)):
                raise InputFormatError(f"'{key}' must be one endpoint or a list of them", source=src,
                                       element=el)
            for item in [items] if isinstance(items, str) else items:
                parsed = _endpoint(item)
                if parsed is None:
                    raise InputFormatError(f"endpoint {_short(item)} is not '<node> right|left|straight [@pos]'",
                                           source=src, element=el)
                other, side, pos = parsed
                label = Label.of(is_out, _SIDE_WORDS[side])
                edge = (other, rid) if is_out else (rid, other)
                conns.append(Connection(*edge, label, _pos(pos, src, el)))
    return Topology.build(name, roads, ramps, conns, source=src,
                          attrs={k: doc[k] for k in ("design", "source") if k in doc})


def spec_dict(topology: Topology) -> dict[str, Any]:
    """The YAML-spec mapping of ``topology`` (inverse of :func:`topology_from_spec`)."""
    g = topology.graph
    word = {"right": "right", "left": "left", "middle": "straight"}
    ramps: dict[str, dict[str, list[str]]] = {r: {"from": [], "to": []} for r in topology.ramps}
    for c in topology.connections():
        at = "" if c.pos is None else f" @{c.pos:g}"
        if c.label.is_out:
            ramps[c.target]["from"].append(f"{c.source} {word[c.label.side]}{at}")
        else:
            ramps[c.source]["to"].append(f"{c.target} {word[c.label.side]}{at}")
    doc: dict[str, Any] = {"name": topology.name,
                           "expressways": {k: list(v) for k, v in topology.expressways.items()}}
    lanes = {r: g.nodes[r]["lanes"] for r in topology.roads if g.nodes[r].get("lanes") is not None}
    if lanes:
        doc["lanes"] = lanes
    doc["ramps"] = ramps
    return doc


def write_yaml_spec(topology: Topology, path: str | os.PathLike) -> None:
    """Write ``topology`` as a YAML spec, atomically."""
    text = yaml.safe_dump(spec_dict(topology), sort_keys=False, default_flow_style=None)
    atomic_write(path, text.encode("utf-8"))


# -- any format ---------------------------------------------------------------

def read_topologies(path: str | os.PathLike, *, osm_options: Any = None) -> list[Topology]:
    """Read every interchange in ``path``, whatever its format (by suffix).

    GraphML and YAML files hold one interchange; an OpenStreetMap extract
    (``.osm``, ``.osm.pbf``, ``.osm.gz``, ``.osm.bz2``) may hold several (needs
    :mod:`flyover.osm`; ``osm_options`` is its :class:`flyover.osm.OsmOptions`, default from ``config/config.yaml``).
    """
    p = Path(path)
    suffix = p.suffix.lower()
    try:
        if suffix == ".graphml":
            return [read_graphml(p)]
        if suffix in (".yaml", ".yml"):
            return [read_yaml_spec(p)]
        if p.name.lower().endswith((".osm", ".osm.pbf", ".osm.gz", ".osm.bz2", ".pbf")):
            try:
                from flyover.osm import read_osm_topologies  # noqa: PLC0415 (optional stage)
            except ImportError:
                raise InputFormatError("OpenStreetMap import is not available in this build",
                                       source=str(p)) from None
            return read_osm_topologies(p, osm_options)
    except OSError as exc:
        raise InputFormatError(f"cannot read: {exc.strerror}", source=str(p)) from None
    raise InputFormatError(f"unknown file type {suffix!r} (expected one of {', '.join(TOPOLOGY_SUFFIXES)})",
                           source=str(p))


def iter_files(paths: Iterable[str | os.PathLike]) -> list[Path]:
    """Expand folders into the topology files they hold (sorted)."""
    out: list[Path] = []
    for p in map(Path, paths):
        if p.is_dir():
            out += sorted(f for f in p.iterdir() if f.suffix.lower() in TOPOLOGY_SUFFIXES)
        else:
            out.append(p)
    return out


def located(exc: FlyoverError, path: str | os.PathLike) -> FlyoverError:
    """Attach ``path`` to an error that has no source yet."""
    return exc.located(str(path))
