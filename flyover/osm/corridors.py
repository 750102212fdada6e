"""Corridors of carriageways: which motorway each one-way carriageway belongs to.

Refs are a hint, not the rule (issue 23): a carriageway's corridor is the ref covering most
of its length; refs met along one carriageway are one corridor (a route joining or leaving,
a number changing). A carriageway without any ref is named, in this order:

1. with an opposite carriageway also without ref that shares its name (compared where the
   two are closest, so that one may turn away): one corridor of their own (DC's Potomac
   Freeway south, Sydney's Cahill Expressway), before
2. the ref of the nearest opposite carriageway that has one (within 150 m), or
3. a geometric name ``way{id}`` shared with an opposite carriageway without ref, else its own.

Each choice is a quirk line of the extract.
"""

from __future__ import annotations

from collections import Counter, defaultdict

import numpy as np

from flyover.osm.geom import segment_distances

__all__ = ["name_corridors"]


def name_corridors(b) -> None:
    """Set ``corridor`` on every carriageway of a builder, by the rules of this module.

    Parameters
    ----------
    b
        A :class:`flyover.osm.build._Builder`: its carriageways ``b.groups`` (each with
        ``stretches``, ``ways``, ``xy``, ``corridor`` from its refs or ``None``), stretches
        ``b.st`` and network ``b.nw`` (refs by way, the ways' tags, ``quirk`` for the notes).
    """
    _unify_corridors(b)
    _pair_named_carriageways(b)
    _pair_missing_refs(b, with_ref=True)
    _pair_missing_refs(b, with_ref=False)


def _unit(v: np.ndarray) -> np.ndarray:
    n = float(np.hypot(*v))
    return v / n if n > 0 else v


def _opposite_distance(a: np.ndarray, b: np.ndarray) -> float:
    """Least distance (m) from a vertex of polyline ``a`` to a segment of ``b`` running the
    other way there (cosine of the directions below -0.5); ``inf`` if nowhere."""
    da = np.diff(a, axis=0)
    da = np.vstack([da, da[-1:]])  # the direction at each vertex: of its outgoing segment
    db = np.diff(b, axis=0)
    pb, qb = b[:-1], b[1:]
    best = float("inf")
    for p, d in zip(a, da):
        dist, _ = segment_distances(p, pb, qb)
        cos = (db @ d) / np.maximum(np.hypot(*db.T) * float(np.hypot(*d)), 1e-9)
        dist = dist[cos < -0.5]
        if len(dist):
            best = min(best, float(dist.min()))
    return best



def _unify_corridors(b) -> None:
    """Refs met along one carriageway (a route joining or leaving, a route number changing)
    are one corridor, named by the ref covering most length."""
    parent: dict[str, str] = {}

    def find(r):
        while parent.setdefault(r, r) != r:
            r = parent[r]
        return r

    length = Counter()
    for g in b.groups:
        refs = []
        for c in g.stretches:
            st = b.st[c]
            for w in st.ways:
                if b.nw.ref[w]:
                    refs.append(b.nw.ref[w])
                    length[b.nw.ref[w]] += st.length / len(st.ways)
        for r in refs[1:]:
            x, y = find(refs[0]), find(r)
            if x != y:
                parent[max(x, y)] = min(x, y)
    members = defaultdict(list)
    for r in list(parent):
        members[find(r)].append(r)
    name = {}
    for rs in members.values():
        best = max(sorted(rs), key=lambda r: length[r])
        for r in rs:
            name[r] = best
        if len(rs) > 1:
            b.nw.quirk(f"refs {', '.join(sorted(rs))} follow one another along a carriageway: "
                          f"one corridor {best}")
    for g in b.groups:
        if g.corridor is not None:
            g.corridor = name.get(g.corridor, g.corridor)


def _names(b, g) -> set[str]:
    return {n for w in g.ways if (n := b.nw.net.ways[w].tag("name"))}

def _pair_named_carriageways(b) -> None:
    """Two carriageways without ref that share a name and run opposite to each other
    within 150 m somewhere (compared where they are closest, so that one may turn away, as
    the Cahill Expressway does) are one corridor, before any ref is taken from an opposite
    carriageway of another name or of another road that runs beside them."""
    free = [g for g in b.groups if g.corridor is None and len(g.xy) > 1]
    names = {g.gid: _names(b, g) for g in free}
    for g in free:
        if g.corridor is not None or not names[g.gid]:
            continue
        best, best_d = None, 150.0
        for h in free:
            if h is g or h.corridor is not None or not names[g.gid] & names[h.gid]:
                continue
            d = _opposite_distance(g.xy, h.xy)
            if d < best_d:
                best, best_d = h, d
        if best is not None:
            g.corridor = best.corridor = f"way{min(g.ways + best.ways)}"
            b.nw.quirk(f"carriageways way(s) {g.ways[:3]} and {best.ways[:3]} without ref, both named "
                          f"{sorted(names[g.gid] & names[best.gid])[0]}, opposite and {best_d:.0f} m "
                          f"apart: corridor named {g.corridor}")

def _pair_missing_refs(b, with_ref: bool) -> None:
    """Give a carriageway without ref its opposite carriageway's ref (``with_ref``),
    or else pair it with an opposite carriageway also without ref under a geometric name."""
    for g in b.groups:
        if g.corridor is not None:
            continue
        heading = _unit(g.xy[-1] - g.xy[0])
        best, best_d = None, 150.0
        for h in b.groups:
            if h is g or (h.corridor is None) == with_ref or \
                    float(np.dot(heading, _unit(h.xy[-1] - h.xy[0]))) > -0.5:
                continue
            d, _ = segment_distances(g.xy[len(g.xy) // 2], h.xy[:-1], h.xy[1:])
            if d.min() < best_d:
                best, best_d = h, float(d.min())
        if best is not None and with_ref:
            g.corridor = best.corridor
            b.nw.quirk(f"carriageway way(s) {g.ways[:3]} without ref: ref {best.corridor} "
                          f"from the opposite carriageway {best_d:.0f} m away")
        elif best is not None:
            g.corridor = best.corridor = f"way{min(g.ways + best.ways)}"
            b.nw.quirk(f"carriageways way(s) {g.ways[:3]} and {best.ways[:3]} without ref, "
                          f"opposite and {best_d:.0f} m apart: corridor named {g.corridor}")
        elif not with_ref:
            g.corridor = f"way{min(g.ways)}"
            b.nw.quirk(f"carriageway way(s) {g.ways[:3]} without ref: corridor named {g.corridor}")
