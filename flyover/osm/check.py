"""A self-check of each interchange read from OpenStreetMap, against its own geometry.

What the topology says is compared with what the map shows, independently of how the
topology was built:

- **legs**: the carriageways are cut by a ring around the interchange's centre (the
  mean of its junction points; radius: the farthest junction plus ``RING_MARGIN_M``).
  The crossing points, the places inside the ring where a carriageway ends with nothing
  going on (a stub ending at ordinary roads, the extract's edge) or turns back at once (a
  stub's two carriageways joined at its end) — those carried on to the ring along their
  direction — are grouped where they lie within ``LEG_WIDTH_M`` of each other along the
  ring; a group is as many legs as it pairs inbound with outbound carriageways (at least
  one). The topology's legs (:attr:`flyover.topology.Topology.legs`) must be as many.
  Known limit: a leg of two dual carriageways side by side (express and local lanes both
  tagged motorway) counts as two;
- **ramps**: every ramp is reached from a road and reaches a road (through ramps only),
  and the two are not one and the same carriageway;
- **shape**: three legs on the map is a ``T``, four a ``cross``.

Each disagreement is a row (interchange, check, detail) for the city's notes.

>>> from flyover.osm.check import self_check  # doctest: +SKIP
>>> self_check(topology)  # doctest: +SKIP
[{'check': 'legs', 'detail': 'ring around the centre crosses 3 legs, the topology has 4'}]
"""

from __future__ import annotations

import networkx as nx
import numpy as np

from flyover.topology.model import Kind, Topology

__all__ = ["self_check", "ring_legs", "RING_MARGIN_M", "LEG_WIDTH_M"]

#: the ring passes this far (m) beyond the farthest junction of the interchange
RING_MARGIN_M = 120.0
#: crossings of the ring closer than this (m) along it are one leg (its two carriageways)
LEG_WIDTH_M = 150.0
#: a carriageway turning back by more than this (degrees) at one vertex: a stub's end
TURN_BACK_DEG = 120.0


def _crossings(line: np.ndarray, centre: np.ndarray, radius: float) -> list[tuple[np.ndarray, bool]]:
    """Where ``line`` crosses the ring, and whether it leaves the ring there (outbound)."""
    d = np.hypot(*(line - centre).T) - radius
    out = []
    for k in np.nonzero(np.sign(d[:-1]) * np.sign(d[1:]) < 0)[0]:
        t = d[k] / (d[k] - d[k + 1])
        out.append((line[k] + t * (line[k + 1] - line[k]), bool(d[k + 1] > 0)))
    return out


def _onto_ring(p: np.ndarray, direction: np.ndarray, centre: np.ndarray, radius: float) -> np.ndarray:
    """Where a road ending at ``p`` inside the ring would cross it, going on along ``direction``
    (so that a leg's ends at different distances from the centre are compared where they
    would meet the ring)."""
    d = np.asarray(direction, float)
    n = float(np.hypot(*d))
    if n == 0:
        return p
    d = d / n
    q = p - centre
    b = float(q @ d)
    t = -b + np.sqrt(max(b * b - (float(q @ q) - radius * radius), 0.0))
    return p + max(t, 0.0) * d


def _turn_backs(line: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """Vertices where a carriageway turns back at once (more than ``TURN_BACK_DEG``), with the
    direction it arrived in: two carriageways of a motorway stub joined at the ordinary road
    they end at."""
    d = np.diff(line, axis=0)
    keep = np.hypot(*d.T) > 0.5
    idx = np.nonzero(keep)[0]
    if len(idx) < 2:
        return []
    d = d[idx]
    cos = np.einsum("ij,ij->i", d[:-1], d[1:]) / (np.hypot(*d[:-1].T) * np.hypot(*d[1:].T))
    sharp = np.nonzero(cos < np.cos(np.radians(TURN_BACK_DEG)))[0]
    return [(line[idx[k] + 1], d[k]) for k in sharp]


def ring_legs(topology: Topology) -> tuple[int, float]:
    """Legs the map shows, and the ring's radius.

    The points where carriageways cross the ring (outbound or inbound), end inside it with
    nothing going on (``osm["dead_ends"]``: a stub ending at ordinary roads, a carriageway cut
    by the extract's edge; inbound where it begins, outbound where it ends) or turn back inside
    it (a stub's two carriageways joined at its end), seen from the centre, are grouped along
    the ring within ``LEG_WIDTH_M``. A group holds one leg per inbound and outbound
    carriageway it pairs (at least one): the two legs of a fork that run side by side are
    two pairs, a leg with a third carriageway (Sydney's Cahill Expressway lanes on the bridge)
    is still one."""
    osm = topology.attrs["osm"]
    junctions = np.array([j[0] for j in osm["junctions"]], float).reshape(-1, 2)
    centre = junctions.mean(axis=0)
    spread = np.hypot(*(junctions - centre).T)
    radius = float(spread.max()) + RING_MARGIN_M
    found: list[tuple[np.ndarray, bool]] = []  # (point, outbound)
    for road in topology.roads:
        line = np.asarray(osm.get("carriageways", osm["lines"]).get(road, []), float).reshape(-1, 2)
        if len(line) < 2:
            continue
        found += _crossings(line, centre, radius)
        found += [(_onto_ring(p, d, centre, radius), o) for p, d in _turn_backs(line)
                  if float(np.hypot(*(p - centre))) <= radius for o in (True, False)]
    for x, y, dx, dy, kind in osm.get("dead_ends", []):
        p = np.array([x, y], float)
        if float(np.hypot(*(p - centre))) <= radius:
            found.append((_onto_ring(p, np.array([dx, dy]), centre, radius), kind == "out"))
    points = sorted((float(np.arctan2(*(p - centre)[::-1])), outbound) for p, outbound in found)
    if not points:
        return 0, radius
    a = np.array([p[0] for p in points])
    gaps = np.diff(np.concatenate([a, [a[0] + 2 * np.pi]])) * radius  # arc to the next point
    ends = np.nonzero(gaps > LEG_WIDTH_M)[0]
    if not len(ends):
        groups = [points]
    else:
        rolled = points[ends[0] + 1:] + points[:ends[0] + 1]  # begins right after a gap
        cut = np.nonzero(np.roll(gaps, -(ends[0] + 1)) > LEG_WIDTH_M)[0]
        groups = [rolled[i + 1:j + 1] for i, j in zip([-1, *cut[:-1]], cut)]
    legs = sum(max(1, min(sum(o for _, o in g), sum(not o for _, o in g))) for g in groups)
    return legs, radius


def _first_roads(g: nx.DiGraph, start: str, step) -> set[str]:
    """The roads reached from ramp ``start`` through ramps only (``step``: successors or
    predecessors): where its traffic comes from or goes to, not what lies beyond those roads."""
    seen, stack, roads = {start}, [start], set()
    while stack:
        for v in step(stack.pop()):
            if g.nodes[v]["kind"] is Kind.ROAD:
                roads.add(v)
            elif v not in seen:
                seen.add(v)
                stack.append(v)
    return roads


def _ramp_ends(topology: Topology) -> list[tuple[str, set[str], set[str]]]:
    g = topology.graph
    return [(r, _first_roads(g, r, g.predecessors), _first_roads(g, r, g.successors))
            for r in sorted(topology.ramps)]


def self_check(topology: Topology) -> list[dict]:
    """Disagreements between ``topology`` and the OSM geometry it was read from (empty: none)."""
    rows = []
    legs, radius = ring_legs(topology)
    if legs != topology.legs:
        rows.append({"check": "legs", "detail": f"a ring of {radius:.0f} m around the centre crosses "
                     f"{legs} legs of carriageways, the topology has {topology.legs} ({topology.shape})"})
    shape = {3: "T", 4: "cross"}.get(legs, "other")
    if legs in (3, 4) and shape != topology.shape:
        rows.append({"check": "shape", "detail": f"{legs} legs on the map is a {shape}, "
                     f"the topology is {topology.shape}"})
    for ramp, up, down in _ramp_ends(topology):
        if not up or not down:
            rows.append({"check": "ramp", "detail": f"ramp {ramp} is not between two roads "
                         f"(from {sorted(up) or 'no road'} to {sorted(down) or 'no road'})"})
        elif up == down and len(up) == 1:
            rows.append({"check": "ramp", "detail": f"ramp {ramp} leaves and joins the same "
                         f"carriageway {next(iter(up))}"})
    return rows
