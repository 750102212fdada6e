"""Topology classes by exact labeled-graph isomorphism (paper §III-B, Def. 2–3).

A cheap invariant (the stable colour-refinement partition of the labeled
digraph) buckets candidates; inside a bucket, networkx's VF2 matcher with node
kind and edge label preserved decides. Each class gets the stable id of its
canonical form (:func:`flyover.topology.canonical.class_id`), and the name of a
catalog design when one is isomorphic to it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

from networkx.algorithms import isomorphism as iso

from flyover.topology.canonical import _KIND_CODE, _LABEL_CODE, _refine, class_id
from flyover.topology.catalog import catalog_class_names
from flyover.topology.model import Topology

__all__ = ["TopologyClass", "classify", "is_isomorphic", "invariant"]

_node_match = iso.categorical_node_match("kind", None)
_edge_match = iso.categorical_edge_match("label", None)


@dataclass(frozen=True)
class TopologyClass:
    """One isomorphism class: its id, readable name and members."""

    class_id: str
    class_name: str
    representative: Topology
    members: tuple[Topology, ...] = field(repr=False)

    @property
    def n_roads(self) -> int:
        return self.representative.n_roads

    @property
    def n_ramps(self) -> int:
        return self.representative.n_ramps

    @property
    def shape(self) -> str:
        return self.representative.shape

    def label_counts(self) -> dict[str, int]:
        return self.representative.label_counts()


def invariant(topology: Topology) -> tuple:
    """An isomorphism invariant: sizes, label counts and the refined colour histogram."""
    g = topology.graph
    nodes = sorted(g.nodes)
    index = {v: i for i, v in enumerate(nodes)}
    outs: list[list] = [[] for _ in nodes]
    ins: list[list] = [[] for _ in nodes]
    for u, v, d in g.edges(data=True):
        outs[index[u]].append((index[v], _LABEL_CODE[d["label"]]))
        ins[index[v]].append((index[u], _LABEL_CODE[d["label"]]))
    colors = _refine([_KIND_CODE[g.nodes[v]["kind"]] for v in nodes], outs, ins)
    sig = tuple(sorted((colors[i], tuple(sorted((lab, colors[w]) for w, lab in outs[i])))
                       for i in range(len(nodes))))
    return len(nodes), g.number_of_edges(), sig


def is_isomorphic(a: Topology, b: Topology) -> bool:
    """Exact isomorphism with node kind and edge label preserved (VF2)."""
    return iso.DiGraphMatcher(a.graph, b.graph, node_match=_node_match,
                              edge_match=_edge_match).is_isomorphic()


def fallback_name(topology: Topology) -> str:
    """Readable name for a class with no catalog design: shape, roads, ramps."""
    return f"{topology.shape}-{topology.n_roads}roads-{topology.n_ramps}ramps"


def classify(topologies: Sequence[Topology]) -> list[TopologyClass]:
    """Group ``topologies`` into isomorphism classes.

    The result is sorted by class id; members keep their input order, and the
    representative is the member first by ``(source, name)`` so the result
    does not depend on input order.
    """
    buckets: dict[tuple, list[list[Topology]]] = {}
    for t in topologies:
        groups = buckets.setdefault(invariant(t), [])
        for group in groups:
            if is_isomorphic(group[0], t):
                group.append(t)
                break
        else:
            groups.append([t])
    names = catalog_class_names()
    classes = []
    for groups in buckets.values():
        for group in groups:
            rep = min(group, key=lambda t: (str(t.source or ""), t.name))
            cid = class_id(rep)
            classes.append(TopologyClass(cid, names.get(cid, fallback_name(rep)), rep, tuple(group)))
    return sorted(classes, key=lambda c: c.class_id)
