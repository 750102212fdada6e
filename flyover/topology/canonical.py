"""Canonical form of a labeled topology, and the stable class id derived from it.

Two topologies get the same canonical form iff they are isomorphic with node
kind and edge label preserved (paper Def. 2–3). The form is computed by
individualization–refinement, the method of nauty/bliss, in plain Python:

1. colour refinement (1-WL on the labeled digraph) from the node kinds until
   the partition is stable; colours are ranked canonically at every round, so
   the partition does not depend on node names or input order;
2. while some colour class has several nodes, branch on each node of the
   first smallest such class (individualize, refine again);
3. every discrete leaf orders the nodes; its adjacency code is a candidate,
   and the smallest candidate is the canonical form.

Topologies have tens of nodes and small automorphism groups; the one common
source of large groups, parallel ramps between the same parents (twins), is
pruned, so the search tree stays small.
"""

from __future__ import annotations

import hashlib
from functools import lru_cache

from flyover.topology.model import Kind, Label, Topology

__all__ = ["canonical_form", "canonical_labeling", "labeling_with_invariant", "class_id", "class_id_of_form", "CanonicalForm"]

#: (node kinds in canonical order, sorted edges as (i, j, label))
CanonicalForm = tuple[tuple[str, ...], tuple[tuple[int, int, str], ...]]

_KIND_CODE = {Kind.ROAD: 0, Kind.RAMP: 1}
_LABEL_CODE = {lab: i for i, lab in enumerate(Label)}


def _refine(colors: list[int], outs: list[list[tuple[int, int]]],
            ins: list[list[tuple[int, int]]]) -> list[int]:
    """Refine to the coarsest equitable partition; colours are canonical ranks."""
    n_classes = len(set(colors))
    while True:
        sig = [
            (colors[v],
             tuple(sorted((lab, colors[w]) for w, lab in outs[v])),
             tuple(sorted((lab, colors[w]) for w, lab in ins[v])))
            for v in range(len(colors))
        ]
        rank = {s: i for i, s in enumerate(sorted(set(sig)))}
        colors = [rank[s] for s in sig]
        if len(rank) == n_classes:
            return colors
        n_classes = len(rank)


def _untwinned(cell: list[int], outs, ins) -> list[int]:
    """One node per group of twins (same labeled in- and out-neighbours).

    Swapping two twins is an automorphism that fixes every other node, so
    individualizing either gives the same leaves: branch on one only. This
    keeps parallel ramps (k of them would cost k! leaves) cheap.
    """
    seen, keep = set(), []
    for v in cell:
        key = (frozenset(outs[v]), frozenset(ins[v]))
        if key not in seen:
            seen.add(key)
            keep.append(v)
    return keep


def _search(colors, outs, ins, edges, best):
    n = len(colors)
    counts: dict[int, int] = {}
    for c in colors:
        counts[c] = counts.get(c, 0) + 1
    cells = [c for c, k in counts.items() if k > 1]
    if not cells:
        code = tuple(sorted((colors[u], colors[v], lab) for u, v, lab in edges))
        if best[0] is None or code < best[0]:
            best[0], best[1] = code, colors
        return
    target = min(cells, key=lambda c: (counts[c], c))
    for v in _untwinned([v for v in range(n) if colors[v] == target], outs, ins):
        # individualize v: it sorts before the rest of its cell
        split = [2 * c + (0 if (u == v or c != target) else 1) for u, c in enumerate(colors)]
        _search(_refine(split, outs, ins), outs, ins, edges, best)


def canonical_form(topology: Topology) -> CanonicalForm:
    """The canonical form of ``topology`` (equal iff isomorphic); see :func:`canonical_labeling`."""
    return canonical_labeling(topology)[0]


def canonical_labeling(topology: Topology) -> tuple[CanonicalForm, tuple[str, ...]]:
    """The canonical form of ``topology`` and its nodes in canonical order.

    Two isomorphic topologies have equal forms, and pairing their node orders
    position by position is an isomorphism between them.

    Examples
    --------
    >>> from flyover.topology.catalog import catalog_topologies
    >>> t = catalog_topologies()["cloverleaf"]
    >>> u = t.relabeled({n: n + "_x" for n in t.graph})
    >>> canonical_form(t) == canonical_form(u)
    True
    """
    form, order, _ = labeling_with_invariant(topology)
    return form, order


def _encode(topology: Topology):
    """Nodes (sorted), kind codes, labeled out/in adjacency and edge list, by node index."""
    g = topology.graph
    nodes = sorted(g.nodes)
    index = {v: i for i, v in enumerate(nodes)}
    kinds = [_KIND_CODE[g.nodes[v]["kind"]] for v in nodes]
    outs: list[list[tuple[int, int]]] = [[] for _ in nodes]
    ins: list[list[tuple[int, int]]] = [[] for _ in nodes]
    edges = []
    for u, v, d in g.edges(data=True):
        lab = _LABEL_CODE[d["label"]]
        outs[index[u]].append((index[v], lab))
        ins[index[v]].append((index[u], lab))
        edges.append((index[u], index[v], lab))
    return nodes, kinds, outs, ins, edges


def labeling_with_invariant(topology: Topology) -> tuple[CanonicalForm, tuple[str, ...], tuple]:
    """:func:`canonical_labeling` plus a cheap invariant from the same refinement.

    The invariant (sizes and the stable colour histogram with labeled
    out-neighbour colours) is equal for isomorphic topologies; classification
    buckets by it.
    """
    g = topology.graph
    nodes, kinds, outs, ins, edges = _encode(topology)
    colors = _refine(kinds, outs, ins)
    invariant = (len(nodes), len(edges),
                 tuple(sorted((colors[i], tuple(sorted((lab, colors[w]) for w, lab in outs[i])))
                              for i in range(len(nodes)))))
    best: list = [None, None]
    _search(colors, outs, ins, edges, best)
    order = sorted(range(len(nodes)), key=lambda i: best[1][i])
    labels = list(Label)
    kind_names = tuple(g.nodes[nodes[i]]["kind"].value for i in order)
    form = (kind_names, tuple((u, v, labels[lab].value) for u, v, lab in best[0]))
    return form, tuple(nodes[i] for i in order), invariant


@lru_cache(maxsize=None)
def _digest(form: CanonicalForm) -> str:
    text = "|".join(form[0]) + "#" + ";".join(f"{u},{v},{lab}" for u, v, lab in form[1])
    return hashlib.sha256(text.encode()).hexdigest()[:10]


def class_id_of_form(form: CanonicalForm) -> str:
    """Stable class id: ``"c"`` + 10 hex digits of the canonical form's SHA-256."""
    return "c" + _digest(form)


def class_id(topology: Topology) -> str:
    """The stable class id of ``topology`` (see :func:`class_id_of_form`)."""
    return class_id_of_form(canonical_form(topology))
