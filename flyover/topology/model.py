"""The topology model of an interchange (paper §III-A, Definition 1).

A topology is a labeled digraph. Nodes are *roads* (one-way carriageways of
an expressway) and *ramps*; an edge ``u -> v`` means traffic flows from ``u``
to ``v`` and carries exactly one :class:`Label`.

Example
-------
>>> from flyover.topology import Topology, Road, Ramp, Connection, Label
>>> t = Topology.build(
...     "tiny",
...     roads=[Road("A1", "A"), Road("B1", "B")],
...     ramps=[Ramp("r1")],
...     connections=[Connection("A1", "r1", Label.OUT_R), Connection("r1", "B1", Label.IN_R)],
... )
>>> t.n_roads, t.n_ramps, t.shape
(2, 1, 'cross')
"""

from __future__ import annotations

import enum
from collections import Counter
from dataclasses import dataclass
from typing import Iterable, Mapping

import networkx as nx

from flyover.errors import TopologyError

__all__ = [
    "Kind",
    "Label",
    "Road",
    "Ramp",
    "Connection",
    "Topology",
    "Shape",
]


class Kind(str, enum.Enum):
    """Node kind: a one-way carriageway (``road``) or a ``ramp``."""

    ROAD = "road"
    RAMP = "ramp"


class Label(str, enum.Enum):
    """Edge label (paper Def. 1, plus the straight-on pair for T interchanges)."""

    OUT_R = "Out-R"
    OUT_L = "Out-L"
    OUT_M = "Out-M"
    IN_R = "In-R"
    IN_L = "In-L"
    IN_M = "In-M"

    @property
    def is_out(self) -> bool:
        """True for diverges (the target leaves the source)."""
        return self.value.startswith("Out")

    @property
    def side(self) -> str:
        """``right``, ``left`` or ``middle`` (straight-on)."""
        return {"R": "right", "L": "left", "M": "middle"}[self.value[-1]]

    @classmethod
    def of(cls, is_out: bool, side: str) -> "Label":
        """The label for a diverge (``is_out``) or merge on ``side``."""
        letter = {"right": "R", "left": "L", "middle": "M"}[side]
        return cls(("Out-" if is_out else "In-") + letter)


class Shape(str, enum.Enum):
    """Overall shape by number of legs: 3 → ``T``, 4 → ``cross``."""

    T = "T"
    CROSS = "cross"
    OTHER = "other"


@dataclass(frozen=True)
class Road:
    """A one-way carriageway; ``expressway`` groups opposite carriageways."""

    id: str
    expressway: str
    lanes: int | None = None


@dataclass(frozen=True)
class Ramp:
    """A ramp (one-way link between carriageways or other ramps)."""

    id: str


@dataclass(frozen=True)
class Connection:
    """Edge ``source -> target`` with its label and optional position 0..1."""

    source: str
    target: str
    label: Label
    pos: float | None = None

    @property
    def element(self) -> str:
        return f"{self.source}->{self.target}"


class Topology:
    """A validated interchange topology.

    Build one with :meth:`build` (validates) rather than the constructor.
    The graph is exposed as :attr:`graph`, a :class:`networkx.DiGraph` with
    node attributes ``kind`` (and ``expressway``, ``lanes`` for roads) and
    edge attributes ``label`` (a :class:`Label`) and ``pos``. Treat it as
    read-only: views derived from it are kept with the topology (:meth:`derived`).
    """

    __slots__ = ("name", "graph", "source", "attrs", "_derived")

    def __init__(self, name: str, graph: nx.DiGraph, source: str | None = None,
                 attrs: Mapping[str, object] | None = None):
        self.name = name
        self.graph = graph
        self.source = source
        self.attrs = dict(attrs or {})
        self._derived: dict[str, dict] = {}

    # -- construction -----------------------------------------------------
    @classmethod
    def build(
        cls,
        name: str,
        roads: Iterable[Road],
        ramps: Iterable[Ramp],
        connections: Iterable[Connection],
        *,
        source: str | None = None,
        node_attrs: Mapping[str, Mapping[str, object]] | None = None,
        attrs: Mapping[str, object] | None = None,
    ) -> "Topology":
        """Validate the parts and return a :class:`Topology`.

        Raises
        ------
        TopologyError
            Naming ``source``, the node or edge at fault, and the rule broken.
        """
        roads, ramps, connections = list(roads), list(ramps), list(connections)
        _check_parts(roads, ramps, connections, source)
        g = nx.DiGraph()
        extra = node_attrs or {}
        for r in sorted(roads, key=lambda r: r.id):
            data = {"kind": Kind.ROAD, "expressway": r.expressway}
            if r.lanes is not None:
                data["lanes"] = int(r.lanes)
            data.update(extra.get(r.id, {}))
            g.add_node(r.id, **data)
        for r in sorted(ramps, key=lambda r: r.id):
            g.add_node(r.id, kind=Kind.RAMP, **extra.get(r.id, {}))
        for c in sorted(connections, key=lambda c: (c.source, c.target)):
            data = {"label": c.label}
            if c.pos is not None:
                data["pos"] = float(c.pos)
            g.add_edge(c.source, c.target, **data)
        topo = cls(name, g, source, attrs)
        _check_graph(topo)
        return topo

    # -- views --------------------------------------------------------------
    def derived(self, view: str) -> dict:
        """The memo of one view derived from the (read-only) graph, kept with this
        topology and filled by whoever reads it (:func:`flyover.geometry.chains.ends`:
        ``derived("ends")``, ramp → its ends): each view is computed once per topology,
        never shared between two (a :meth:`relabeled` copy starts empty)."""
        return self._derived.setdefault(view, {})

    @property
    def roads(self) -> tuple[str, ...]:
        """Road ids, sorted."""
        return tuple(sorted(n for n, k in self.graph.nodes(data="kind") if k is Kind.ROAD))

    @property
    def ramps(self) -> tuple[str, ...]:
        """Ramp ids, sorted."""
        return tuple(sorted(n for n, k in self.graph.nodes(data="kind") if k is Kind.RAMP))

    @property
    def n_roads(self) -> int:
        return len(self.roads)

    @property
    def n_ramps(self) -> int:
        return len(self.ramps)

    @property
    def expressways(self) -> dict[str, tuple[str, ...]]:
        """Expressway name → its carriageways (sorted)."""
        out: dict[str, list[str]] = {}
        for r in self.roads:
            out.setdefault(self.graph.nodes[r]["expressway"], []).append(r)
        return {k: tuple(v) for k, v in sorted(out.items())}

    def connections(self) -> list[Connection]:
        """All edges as :class:`Connection` values, sorted by (source, target)."""
        return [
            Connection(u, v, d["label"], d.get("pos"))
            for u, v, d in sorted(self.graph.edges(data=True), key=lambda e: (e[0], e[1]))
        ]

    def label_counts(self) -> dict[str, int]:
        """Number of edges per label, every label present (zero included)."""
        counts = Counter(d["label"] for _, _, d in self.graph.edges(data=True))
        return {lab.value: counts.get(lab, 0) for lab in Label}

    @property
    def legs(self) -> int:
        """Number of legs: an expressway ending here (Out-M / In-M) counts 1, else 2."""
        legs = 0
        for roads in self.expressways.values():
            ends = any(
                d["label"] in (Label.OUT_M, Label.IN_M)
                for r in roads
                for _, _, d in [*self.graph.out_edges(r, data=True), *self.graph.in_edges(r, data=True)]
            )
            legs += 1 if ends else 2
        return legs

    @property
    def shape(self) -> str:
        """``T`` for 3 legs, ``cross`` for 4, ``other`` otherwise."""
        return {3: Shape.T, 4: Shape.CROSS}.get(self.legs, Shape.OTHER).value

    def summary(self) -> str:
        """One line: name, roads, ramps, shape and label counts."""
        labels = " ".join(f"{k}={v}" for k, v in self.label_counts().items() if v)
        return (f"{self.name}: {self.n_roads} roads, {self.n_ramps} ramps, "
                f"shape {self.shape}, {labels}")

    def relabeled(self, mapping: Mapping[str, str], name: str | None = None) -> "Topology":
        """A copy with node ids renamed by ``mapping`` (the class is unchanged)."""
        g = nx.relabel_nodes(self.graph, dict(mapping), copy=True)
        h = nx.DiGraph()
        h.add_nodes_from(sorted(g.nodes(data=True)))
        h.add_edges_from(sorted(g.edges(data=True), key=lambda e: (e[0], e[1])))
        return Topology(name or self.name, h, self.source, self.attrs)

    def __repr__(self) -> str:
        return f"Topology({self.name!r}, roads={self.n_roads}, ramps={self.n_ramps})"


# -- validation -----------------------------------------------------------

def _fail(reason: str, source: str | None, element: str | None) -> TopologyError:
    return TopologyError(reason, source=source, element=element)


def _check_parts(roads: list[Road], ramps: list[Ramp], conns: list[Connection],
                 source: str | None) -> None:
    kinds: dict[str, Kind] = {}
    for node, kind in [*((r.id, Kind.ROAD) for r in roads), *((r.id, Kind.RAMP) for r in ramps)]:
        if not isinstance(node, str) or not node:
            raise _fail("node id must be a non-empty string", source, repr(node))
        if not node.isprintable():  # GraphML (XML) cannot hold control characters
            raise _fail("node id must be printable text (no control characters)", source, repr(node))
        if node in kinds:
            raise _fail("duplicate node id", source, node)
        kinds[node] = kind
    for r in roads:
        if not r.expressway:
            raise _fail("road has no expressway", source, r.id)
        if not r.expressway.isprintable():
            raise _fail(f"expressway name {r.expressway!r} must be printable text (no control characters)",
                        source, r.id)
        if r.lanes is not None and (isinstance(r.lanes, bool) or not isinstance(r.lanes, int) or r.lanes < 1):
            raise _fail(f"lanes must be a positive integer, got {r.lanes!r}"[:200], source, r.id)
    seen: set[tuple[str, str]] = set()
    for c in conns:
        el = c.element
        if not isinstance(c.label, Label):
            raise _fail(f"unknown label {c.label!r} (expected one of "
                        f"{', '.join(x.value for x in Label)})", source, el)
        for end in (c.source, c.target):
            if end not in kinds:
                raise _fail(f"edge refers to unknown node {end!r}", source, el)
        if c.source == c.target:
            raise _fail("self-loop", source, el)
        if (c.source, c.target) in seen:
            raise _fail("duplicate edge", source, el)
        seen.add((c.source, c.target))
        ks, kt = kinds[c.source], kinds[c.target]
        if ks is Kind.ROAD and kt is Kind.ROAD:
            raise _fail("road -> road edge (roads connect only through ramps)", source, el)
        if c.label.is_out and kt is not Kind.RAMP:
            raise _fail(f"{c.label.value} target must be a ramp, {c.target!r} is a road", source, el)
        if not c.label.is_out and ks is not Kind.RAMP:
            raise _fail(f"{c.label.value} source must be a ramp, {c.source!r} is a road", source, el)
        if c.pos is not None and not (0.0 <= float(c.pos) <= 1.0):
            raise _fail(f"pos must be within 0..1, got {c.pos!r}", source, el)


def _check_graph(topo: Topology) -> None:
    g, src = topo.graph, topo.source
    for n in topo.ramps:
        if g.in_degree(n) == 0:
            raise _fail("ramp has no way in", src, n)
        if g.out_degree(n) == 0:
            raise _fail("ramp has no way out", src, n)
    for n in topo.roads:
        outs = [v for _, v, d in g.out_edges(n, data=True) if d["label"] is Label.OUT_M]
        ins = [u for u, _, d in g.in_edges(n, data=True) if d["label"] is Label.IN_M]
        if len(outs) > 1:
            raise _fail(f"carriageway has more than one Out-M ({', '.join(sorted(outs))})", src, n)
        if len(ins) > 1:
            raise _fail(f"carriageway has more than one In-M ({', '.join(sorted(ins))})", src, n)
    for name, roads in topo.expressways.items():
        if len(roads) > 2:
            raise _fail(f"expressway has more than two carriageways ({', '.join(roads)})",
                        src, f"expressway {name}")
    entering = [n for n in topo.roads
                if not any(d["label"] is Label.IN_M for _, _, d in g.in_edges(n, data=True))]
    reached, todo = set(entering), list(entering)  # one traversal: linear in the graph
    while todo:
        for v in g.successors(todo.pop()):
            if v not in reached:
                reached.add(v)
                todo.append(v)
    missing = sorted(set(g.nodes) - reached)
    if missing:
        more = f" and {len(missing) - 10} more" if len(missing) > 10 else ""
        raise _fail("unreachable from any entering road", src, ", ".join(missing[:10]) + more)
    if not topo.ramps:
        raise _fail("topology has no ramps", src, None)
