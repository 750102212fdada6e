"""Lane links of an OpenDRIVE file as link-following clients see them.

Clients that build lanes by following lane links (CommonRoad's converter,
esmini-style players) need every lane that continues across a road end to
be linked there, shoulders included. :func:`dangling_lanes` lists the lanes
that do not; :func:`link_gaps` measures how far apart the borders of two
linked lanes are at the link (the figure that tells a client's tolerance
from our geometry). :func:`levels_at` lists the heights at which roads pass over
a point of the plan: where a client working in 2D sees lanes cross, whether the
file has them at different levels.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from flyover.opendrive.reader import XodrNetwork, XodrRoad

__all__ = ["DanglingLane", "dangling_lanes", "link_gaps", "levels_at", "level_gap"]

_ZERO_M = 1e-6


@dataclass(frozen=True)
class DanglingLane:
    """A lane of nonzero width at a linked road end with no lane link there."""

    road: str
    name: str
    lane: int
    lane_type: str
    end: str  # start | end

    def __str__(self) -> str:
        return f"road {self.road} ({self.name}) lane {self.lane} ({self.lane_type}) at its {self.end}"


def _end_lanes(road: XodrRoad, at_end: bool) -> dict[int, tuple[str, float, tuple[int, ...]]]:
    sec = road.sections[-1] if at_end else road.sections[0]
    ds = road.length - sec.s if at_end else 0.0
    return {lid: (ln.type, float(ln.width(ds)[0]), ln.successors if at_end else ln.predecessors)
            for lid, ln in sec.lanes.items()}


def _junction_links(net: XodrNetwork) -> tuple[set, set]:
    """(incoming road, lane) pairs that a connection leads on, and (road, lane) pairs reached.

    A lane after a junction is reached when a connecting road's lane has it as
    successor (predecessor, for a connecting road that runs against it).
    """
    leaves, reached = set(), set()
    for j in net.junctions.values():
        for c in j.connections:
            leaves.update((c.incoming, a) for a, _ in c.lane_links)
            con = net.roads.get(c.connecting)
            if con is None:
                continue
            for at_end, link in ((True, con.successor), (False, con.predecessor)):
                if link is None or link[0] != "road" or link[1] == c.incoming:
                    continue
                for _, (_, _, nxt) in _end_lanes(con, at_end).items():
                    reached.update((link[1], n) for n in nxt)
    return leaves, reached


def dangling_lanes(net: XodrNetwork) -> list[DanglingLane]:
    """Lanes of nonzero width at a road end that has a neighbour, but no lane link to it."""
    leaves, reached = _junction_links(net)
    out = []
    for road in net.roads.values():
        for at_end, link in ((False, road.predecessor), (True, road.successor)):
            if link is None:
                continue
            for lid, (typ, width, linked) in sorted(_end_lanes(road, at_end).items()):
                if abs(width) <= _ZERO_M or linked:
                    continue
                if link[0] == "junction" and ((road.id, lid) in leaves or (road.id, lid) in reached):
                    continue
                out.append(DanglingLane(road.id, road.name, lid, typ, "end" if at_end else "start"))
    return out


def _borders(road: XodrRoad, lane: int, at_end: bool):
    s = road.length if at_end else 0.0
    bt = road.lane_t(lane, s, at_end)
    if bt is None:
        return None
    x, y, z, h = (float(a[0]) for a in road.reference(s))
    return tuple((x - math.sin(h) * t, y + math.cos(h) * t) for t in bt)


def link_gaps(net: XodrNetwork) -> list[tuple[str, int, str, int, float]]:
    """For every road-to-road lane successor link: ``(road, lane, next road, next lane, gap_m)``.

    ``gap_m`` is the larger of the two border distances (inner, outer) between
    the lane's end and its successor's start, evaluated from the file itself.
    """
    out = []
    for road in net.roads.values():
        link = road.successor
        if link is None or link[0] != "road" or link[1] not in net.roads:
            continue
        nxt = net.roads[link[1]]
        at_end_next = link[2] == "end"
        for lid, (_, width, succ) in _end_lanes(road, True).items():
            for n in succ:
                a, b = _borders(road, lid, True), _borders(nxt, n, at_end_next)
                if a is None or b is None:
                    continue
                # an end-to-end link runs the other way: inner/outer borders swap sides
                gap = max(math.dist(a[0], b[0]), math.dist(a[1], b[1]))
                out.append((road.id, lid, nxt.id, n, gap))
    return out


def levels_at(net: XodrNetwork, x: float, y: float, step_m: float = 0.25, tol_m: float = 0.1
              ) -> list[tuple[str, float, float]]:
    """Every pass of a road over the plan point ``(x, y)``: ``(road, s, z)``.

    A pass is a run of the road's stations (every ``step_m``) whose cross-section, from
    its outermost left lane border to its outermost right one (widened by ``tol_m``),
    runs through the point; ``s`` and ``z`` are the reference line's at the station
    nearest the point along the road. A road that passes over itself (a loop that turns
    more than a full circle, at another height) has two passes.
    """
    out = []
    for road in net.roads.values():
        n = max(2, int(math.ceil(road.length / step_m)) + 1)
        s = np.linspace(0.0, road.length, n)
        rx, ry, rz, h = road.reference(s)
        dx, dy = x - rx, y - ry
        along = dx * np.cos(h) + dy * np.sin(h)
        lat = -dx * np.sin(h) + dy * np.cos(h)
        near = np.flatnonzero(np.abs(along) <= step_m)
        if not len(near):
            continue
        for run in np.split(near, np.flatnonzero(np.diff(near) > 1) + 1):
            i = int(run[np.argmin(np.abs(along[run]))])
            si = float(s[i])
            sec = road.section_at(si, at_end=i == n - 1)
            ts = [t for lid in ((max(sec.lanes), min(sec.lanes)) if sec.lanes else ())
                  if lid != 0 for t in (road.lane_t(lid, si, at_end=i == n - 1) or ())]
            if ts and min(ts) - tol_m <= lat[i] <= max(ts) + tol_m:
                out.append((road.id, si, float(rz[i])))
    return out


def level_gap(net: XodrNetwork, x: float, y: float) -> float:
    """The largest height gap between the road passes over ``(x, y)`` (:func:`levels_at`):
    how far apart the two levels are that a 2D client puts on top of each other; 0 when
    one level (or none) passes there."""
    z = sorted(z for *_, z in levels_at(net, x, y))
    return max(np.diff(z), default=0.0) if len(z) > 1 else 0.0
