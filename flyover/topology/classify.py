"""Topology classes by exact labeled-graph isomorphism (paper §III-B, Def. 2–3).

How membership is decided, exactly and fast:

* every topology gets its canonical labeling (:mod:`flyover.topology.canonical`);
  topologies with equal canonical forms join one class only after the node
  correspondence the two labelings imply has been checked edge by edge and
  label by label — an explicit isomorphism, so membership is proven;
* a cheap invariant (sizes and the stable colour-refinement histogram)
  buckets topologies; whenever a new canonical form appears in a bucket that
  already holds other classes, networkx's VF2 matcher (node kind and edge
  label preserved) decides against each of them, so two classes are never
  split by the canonical form alone.

Each class gets the stable id of its canonical form and, when a catalog design
is isomorphic to it, that design's name.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import Sequence

from networkx.algorithms import isomorphism as iso

from flyover.topology.canonical import class_id_of_form, labeling_with_invariant
from flyover.topology.catalog import catalog_class_names
from flyover.topology.model import Topology

__all__ = ["TopologyClass", "classify", "is_isomorphic", "invariant", "fallback_name"]

log = logging.getLogger(__name__)

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
    """An isomorphism invariant: sizes and the refined colour histogram with edge labels."""
    return labeling_with_invariant(topology)[2]


def is_isomorphic(a: Topology, b: Topology) -> bool:
    """Exact isomorphism with node kind and edge label preserved (networkx VF2)."""
    return iso.DiGraphMatcher(a.graph, b.graph, node_match=_node_match,
                              edge_match=_edge_match).is_isomorphic()


def is_isomorphism(a: Topology, b: Topology, mapping: dict[str, str]) -> bool:
    """True if ``mapping`` (nodes of ``a`` → nodes of ``b``) is a labeled isomorphism."""
    ga, gb = a.graph, b.graph
    if len(mapping) != len(ga) or len(set(mapping.values())) != len(gb) or len(ga) != len(gb):
        return False
    if ga.number_of_edges() != gb.number_of_edges():
        return False
    if any(ga.nodes[n]["kind"] is not gb.nodes[mapping[n]]["kind"] for n in ga):
        return False
    return all(gb.has_edge(mapping[u], mapping[v]) and gb.edges[mapping[u], mapping[v]]["label"] is lab
               for u, v, lab in ga.edges(data="label"))


def fallback_name(topology: Topology) -> str:
    """Readable name for a class with no catalog design: shape, roads, ramps."""
    return f"{topology.shape}-{topology.n_roads}roads-{topology.n_ramps}ramps"


def classify(topologies: Sequence[Topology]) -> list[TopologyClass]:
    """Group ``topologies`` into isomorphism classes.

    The result is sorted by class id; members keep their input order, and the
    representative is the member first by ``(source, name)``, so the result
    does not depend on input order.
    """
    # invariant bucket -> canonical form -> [(topology, canonical node order)]
    buckets: dict[tuple, dict[tuple, list[tuple[Topology, tuple[str, ...]]]]] = {}
    for t in topologies:
        form, order, key = labeling_with_invariant(t)
        groups = buckets.setdefault(key, {})
        if form in groups:
            first, first_order = groups[form][0]
            if not is_isomorphism(first, t, dict(zip(first_order, order))):
                raise RuntimeError(f"canonical labeling of {t.name!r} is not an isomorphism "
                                   f"onto {first.name!r}")
            groups[form].append((t, order))
            continue
        twin = next((f for f, members in groups.items() if is_isomorphic(members[0][0], t)), None)
        if twin is not None:  # VF2 overrules a canonical form that failed to be canonical
            log.error("canonical forms of isomorphic %r and %r differ", groups[twin][0][0].name, t.name)
            groups[twin].append((t, order))
        else:
            groups[form] = [(t, order)]
    names = catalog_class_names()
    classes = []
    for groups in buckets.values():
        for form, members in groups.items():
            group = tuple(m for m, _ in members)
            rep = min(group, key=lambda m: (str(m.source or ""), m.name))
            cid = class_id_of_form(form)
            classes.append(TopologyClass(cid, names.get(cid, fallback_name(rep)), rep, group))
    return sorted(classes, key=lambda c: c.class_id)
