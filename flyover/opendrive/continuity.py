"""3D continuity at every lane link of an OpenDRIVE network.

The ASAM checker only looks at plan-view gaps; heights are invisible to it.
Here every linked pair of lane ends — across lane sections, across road links
and through junction connections — must meet in x, y **and z** within
``tol_m`` (1 cm) and in heading within ``tol_deg`` (0.5°, direction-agnostic
so that start–start links of opposite roads compare too).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from flyover.opendrive.reader import XodrNetwork, XodrRoad

__all__ = ["LinkGap", "lane_link_gaps", "check_continuity"]


@dataclass(frozen=True)
class LinkGap:
    """The mismatch at one lane link."""

    a: str
    b: str
    xy_m: float
    z_m: float
    heading_deg: float

    def ok(self, tol_m: float, tol_deg: float) -> bool:
        return (self.xy_m <= tol_m and self.z_m <= tol_m
                and (math.isnan(self.heading_deg) or self.heading_deg <= tol_deg))


def _end(road: XodrRoad, contact: str) -> tuple[float, bool]:
    return (road.length, True) if contact == "end" else (0.0, False)


def _gap(ra: XodrRoad, la: int, sa: float, ea: bool, rb: XodrRoad, lb: int, sb: float, eb: bool
         ) -> LinkGap | None:
    pa, pb = ra.lane_point(la, sa, ea), rb.lane_point(lb, sb, eb)
    name_a, name_b = f"road {ra.id} lane {la} s={sa:g}", f"road {rb.id} lane {lb} s={sb:g}"
    if pa is None or pb is None:
        return LinkGap(name_a, name_b, math.inf, math.inf, math.inf)
    dh = abs((pa[3] - pb[3] + math.pi / 2) % math.pi - math.pi / 2)
    return LinkGap(name_a, name_b, math.hypot(pa[0] - pb[0], pa[1] - pb[1]),
                   abs(pa[2] - pb[2]), math.degrees(dh))


def lane_link_gaps(net: XodrNetwork) -> list[LinkGap]:
    """The gap at every lane link of ``net`` (sections, road links, junction connections)."""
    gaps: list[LinkGap | None] = []
    for road in net.roads.values():
        secs = road.sections
        for cur, nxt in zip(secs, secs[1:]):
            for lane in cur.lanes.values():
                for k in lane.successors:
                    gaps.append(_gap(road, lane.id, nxt.s, True, road, k, nxt.s, False))
        for which, sec, s0, e0 in (("successor", secs[-1], road.length, True),
                                   ("predecessor", secs[0], 0.0, False)):
            link = getattr(road, which)
            if link is None or link[0] != "road" or link[1] not in net.roads:
                continue
            other = net.roads[link[1]]
            s1, e1 = _end(other, link[2] or "start")
            for lane in sec.lanes.values():
                for k in (lane.successors if which == "successor" else lane.predecessors):
                    gaps.append(_gap(road, lane.id, s0, e0, other, k, s1, e1))
    for j in net.junctions.values():
        for c in j.connections:
            inc, con = net.roads.get(c.incoming), net.roads.get(c.connecting)
            if inc is None or con is None:
                continue
            if inc.successor and inc.successor[0] == "junction" and inc.successor[1] == j.id:
                s0, e0 = inc.length, True
            else:
                s0, e0 = 0.0, False
            s1, e1 = _end(con, c.contact_point)
            for a, b in c.lane_links:
                gaps.append(_gap(inc, a, s0, e0, con, b, s1, e1))
    return [g for g in gaps if g is not None]


def check_continuity(net: XodrNetwork, tol_m: float = 0.01, tol_deg: float = 0.5
                     ) -> tuple[bool, str]:
    """``(ok, detail)``: every lane link within ``tol_m`` in x, y, z and ``tol_deg``."""
    gaps = lane_link_gaps(net)
    bad = [g for g in gaps if not g.ok(tol_m, tol_deg)]
    if not gaps:
        return True, "no lane links"
    worst_xy = max(g.xy_m for g in gaps)
    worst_z = max(g.z_m for g in gaps)
    worst_h = max((g.heading_deg for g in gaps if not math.isnan(g.heading_deg)), default=0.0)
    detail = (f"{len(gaps)} lane links, {len(bad)} off; worst xy {worst_xy:.4f} m, "
              f"z {worst_z:.4f} m, heading {worst_h:.3f} deg")
    if bad:
        g = max(bad, key=lambda g: (g.xy_m, g.z_m, g.heading_deg))
        detail += f"; e.g. {g.a} -> {g.b}: xy {g.xy_m:.4f} m z {g.z_m:.4f} m {g.heading_deg:.3f} deg"
    return not bad, detail
