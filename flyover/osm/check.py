"""A self-check of each interchange read from OpenStreetMap, against its own geometry.

What the topology says is compared with what the map shows, independently of how the
topology was built:

- **legs**: the carriageways are cut by a ring around the interchange's centre (the
  mean of its junction points; radius: the farthest junction plus ``RING_MARGIN_M``);
  the crossing points (or the ends of carriageways cut short by the extract's edge),
  grouped where they lie within ``LEG_WIDTH_M`` of each other along the ring (a leg's
  two carriageways side by side), are the legs the map shows; the topology's legs
  (:attr:`flyover.topology.Topology.legs`) must be as many. Known limits: a fork whose
  two legs stay closer than ``LEG_WIDTH_M`` at the ring counts as one leg, and a short
  motorway stub ending inside the ring counts as none;
- **ramps**: every ramp is reached from a road and reaches a road (through ramps),
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
#: a carriageway ending between this fraction of the ring's radius and the ring was cut
#: short by the extract's edge: its end counts as its crossing
CUT_SHORT_FRACTION = 0.5
#: a carriageway ending inside the ring this far (m) from any junction is a stub leg
#: (a short motorway ending at ordinary roads)
STUB_END_M = 60.0


def _crossings(line: np.ndarray, centre: np.ndarray, radius: float) -> list[np.ndarray]:
    d = np.hypot(*(line - centre).T) - radius
    out = []
    for k in np.nonzero(np.sign(d[:-1]) * np.sign(d[1:]) < 0)[0]:
        t = d[k] / (d[k] - d[k + 1])
        out.append(line[k] + t * (line[k + 1] - line[k]))
    return out


def ring_legs(topology: Topology) -> tuple[int, float]:
    """Legs the map shows, and the ring's radius: the points where carriageways cross the
    ring (or, cut short by the extract's edge, end between the junctions and the ring),
    seen from the centre and grouped along the ring within ``LEG_WIDTH_M``."""
    osm = topology.attrs["osm"]
    junctions = np.array([j[0] for j in osm["junctions"]], float).reshape(-1, 2)
    centre = junctions.mean(axis=0)
    spread = np.hypot(*(junctions - centre).T)
    radius = float(spread.max()) + RING_MARGIN_M
    core = CUT_SHORT_FRACTION * radius
    angles = []
    for road in topology.roads:
        line = np.asarray(osm.get("carriageways", osm["lines"]).get(road, []), float).reshape(-1, 2)
        if len(line) < 2:
            continue
        points = _crossings(line, centre, radius)
        for end in (line[0], line[-1]):  # a stub or cut short by the extract's edge
            if float(np.hypot(*(end - centre))) < radius and (
                    float(np.hypot(*(end - centre))) > core
                    or float(np.hypot(*(junctions - end).T).min()) > STUB_END_M):
                points.append(end)
        angles += [float(np.arctan2(*(p - centre)[::-1])) for p in points]
    if not angles:
        return 0, radius
    a = np.sort(np.array(angles))
    gaps = np.diff(np.concatenate([a, [a[0] + 2 * np.pi]])) * radius  # arc lengths between neighbours
    legs = int((gaps > LEG_WIDTH_M).sum())
    return max(legs, 1), radius


def _ramp_ends(topology: Topology) -> list[tuple[str, set[str], set[str]]]:
    g = topology.graph
    ramps = set(topology.ramps)
    out = []
    for r in sorted(ramps):
        up = {u for u in nx.ancestors(g, r) if g.nodes[u]["kind"] is Kind.ROAD}
        down = {v for v in nx.descendants(g, r) if g.nodes[v]["kind"] is Kind.ROAD}
        out.append((r, up, down))
    return out


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
