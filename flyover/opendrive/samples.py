"""Small hand-built interchanges (``geometry.json`` values) for tests and demos.

``sample_geometry("loop")`` — a cloverleaf loop: right exit, 270° right turn
climbing to the crossing road; ``"flyover"`` — a right exit that crosses
over its own expressway to the left; ``"t"`` — a T end: a carriageway
ending into a ramp (``Out-M``) with a left exit that flies over the through
road; ``"fork"`` — a two-lane ramp whose free end forks into two
one-lane ramps (one back to its road, one up to the crossing road); ``"y"`` —
a carriageway that ends by splitting into a straight-on ramp (``Out-M``,
flying over to the left) and a ramp beside it (``Out-R``) at the same point.
"""

from __future__ import annotations

import math

import numpy as np

from flyover.geometry.model import (Attachment, BezierPiece, ElevationPoly, InterchangeGeometry,
                                    RampGeometry, RoadGeometry)
from flyover.opendrive.curves import BezierChain

__all__ = ["sample_geometry", "detached_ramp", "SAMPLES"]

SAMPLES = ("loop", "flyover", "t", "fork", "y")
_K = 4 * (math.sqrt(2) - 1) / 3  # Bézier quarter-circle handle


def _ramp(id_, pieces, z0, z1, start, end, lanes=1, hump=None):
    chain = BezierChain([np.array(p, dtype=float) for p in pieces])
    L = chain.length
    if hump is None:
        elev = (ElevationPoly(0.0, z0, 0.0, 3 * (z1 - z0) / L ** 2, -2 * (z1 - z0) / L ** 3),)
        slope = 1.5 * abs(z1 - z0) / L * 100
    else:  # up to z0 + hump at mid-length, back down to z1 (== z0)
        h = L / 2
        elev = (ElevationPoly(0.0, z0, 0.0, 3 * hump / h ** 2, -2 * hump / h ** 3),
                ElevationPoly(h, z0 + hump, 0.0, -3 * hump / h ** 2, 2 * hump / h ** 3))
        slope = 1.5 * hump / h * 100
    return RampGeometry(
        id=id_, lanes=lanes,
        plan=tuple(BezierPiece(tuple(map(tuple, p)), float(ln))
                   for p, ln in zip(chain.pieces, chain.lengths)),
        elevation=elev, start=start, end=end, target_radius_m=math.inf, target_slope_pct=slope,
        min_radius_m=math.inf, max_slope_pct=slope, length_m=L)


def _quarter(c, r, a0, a1):
    """Bézier of a circular arc around ``c`` from angle a0 to a1 (|a1-a0| = 90°)."""
    k = _K * r * (1 if a1 > a0 else -1)
    p0 = np.array([c[0] + r * math.cos(a0), c[1] + r * math.sin(a0)])
    p3 = np.array([c[0] + r * math.cos(a1), c[1] + r * math.sin(a1)])
    t0 = np.array([-math.sin(a0), math.cos(a0)])
    t1 = np.array([-math.sin(a1), math.cos(a1)])
    return [p0, p0 + k * t0, p3 - k * t1, p3]


def sample_geometry(kind: str) -> InterchangeGeometry:
    """A small interchange of the given kind (one of :data:`SAMPLES`)."""
    lw, rw = 3.75, 4.0
    if kind == "loop":
        a1 = RoadGeometry("A1", "A", 2, 0, 0.0, (-400.0, 0.0), 0.0, 800.0)
        b1 = RoadGeometry("B1", "B", 2, 1, 6.5, (5.0, -400.0), math.pi / 2, 800.0)
        R, c = 47.5, (60.0, -7.5 - 47.5)
        pieces = [_quarter(c, R, math.pi / 2, 0.0), _quarter(c, R, 0.0, -math.pi / 2),
                  _quarter(c, R, -math.pi / 2, -math.pi)]
        start = Attachment("A1", "Out-R", 460.0, -2 * lw, 0.0, 0.0)
        end = Attachment("B1", "In-R", 400.0 - 55.0, -2 * lw, math.pi / 2, 6.5)
        ramps = (_ramp("r1", pieces, 0.0, 6.5, start, end),)
        return InterchangeGeometry("cloop", 0, 1, lw, 2.5, rw, (0.0, 6.5), (a1, b1), ramps)
    if kind == "flyover":
        a1 = RoadGeometry("A1", "A", 2, 0, 0.0, (-500.0, 0.0), 0.0, 1000.0)
        a2 = RoadGeometry("A2", "A", 2, 0, 0.0, (500.0, 5.0), math.pi, 1000.0)
        b1 = RoadGeometry("B1", "B", 2, 1, 6.5, (5.0, -500.0), math.pi / 2, 1000.0)
        p = [(-300.0, -7.5), (-100.0, -7.5), (12.5, 100.0), (12.5, 300.0)]
        start = Attachment("A1", "Out-R", 200.0, -2 * lw, 0.0, 0.0)
        end = Attachment("B1", "In-R", 800.0, -2 * lw, math.pi / 2, 6.5)
        ramps = (_ramp("r1", [p], 0.0, 6.5, start, end),)
        return InterchangeGeometry("cfly", 0, 2, lw, 2.5, rw, (0.0, 6.5), (a1, a2, b1), ramps)
    if kind == "t":
        a1 = RoadGeometry("A1", "A", 2, 0, 0.0, (-500.0, 0.0), 0.0, 1000.0)
        a2 = RoadGeometry("A2", "A", 2, 0, 0.0, (500.0, 5.0), math.pi, 1000.0)
        c1 = RoadGeometry("C1", "C", 2, 0, 0.0, (20.0, -600.0), math.pi / 2, 400.0)
        p1 = [(20.0, -200.0), (20.0, -100.0), (150.0, -7.5), (300.0, -7.5)]
        r1 = _ramp("r1", [p1], 0.0, 0.0,
                   Attachment("C1", "Out-M", 400.0, 0.0, math.pi / 2, 0.0),
                   Attachment("A1", "In-R", 800.0, -2 * lw, 0.0, 0.0))
        p2 = [(16.0, -300.0), (16.0, -50.0), (-50.0, 12.5), (-300.0, 12.5)]
        r2 = _ramp("r2", [p2], 0.0, 0.0,
                   Attachment("C1", "Out-L", 300.0, rw, math.pi / 2, 0.0),
                   Attachment("A2", "In-R", 800.0, -2 * lw, math.pi, 0.0), hump=6.5)
        return InterchangeGeometry("ct", 0, 3, lw, 2.5, rw, (0.0, 6.5), (a1, a2, c1), (r1, r2))
    if kind == "fork":
        a1 = RoadGeometry("A1", "A", 2, 0, 0.0, (-500.0, 0.0), 0.0, 1000.0)
        b2 = RoadGeometry("B2", "B", 2, 1, 6.5, (50.0, 500.0), -math.pi / 2, 1000.0)
        free = Attachment("", "", 0.0, 0.0, 0.0, 0.0)
        p1 = [(-300.0, -7.5), (-250.0, -7.5), (-200.0, -20.0), (-150.0, -20.0)]
        r1 = _ramp("r1", [p1], 0.0, 0.0, Attachment("A1", "Out-R", 200.0, -2 * lw, 0.0, 0.0),
                   free, lanes=2)
        r1 = RampGeometry(**{**r1.__dict__, "end": Attachment("", "", 0.0, 0.0, 0.0, 0.0)})
        L1 = r1.length_m
        p2 = [(-150.0, -20.0), (-50.0, -20.0), (0.0, -7.5), (100.0, -7.5)]
        r2 = _ramp("r2", [p2], 0.0, 0.0, Attachment("r1", "Out-L", L1, 0.0, 0.0, 0.0),
                   Attachment("A1", "In-R", 600.0, -2 * lw, 0.0, 0.0))
        p3 = [(-150.0, -24.0), (-50.0, -24.0), (42.5, -100.0), (42.5, -200.0)]
        r3 = _ramp("r3", [p3], 0.0, 6.5, Attachment("r1", "Out-R", L1, -rw, 0.0, 0.0),
                   Attachment("B2", "In-R", 700.0, -2 * lw, -math.pi / 2, 6.5))
        return InterchangeGeometry("cfork", 0, 4, lw, 2.5, rw, (0.0, 6.5), (a1, b2), (r1, r2, r3))
    if kind == "y":
        a1 = RoadGeometry("A1", "A", 2, 0, 0.0, (-500.0, 0.0), 0.0, 1000.0)
        a2 = RoadGeometry("A2", "A", 2, 0, 0.0, (500.0, 5.0), math.pi, 1000.0)
        c1 = RoadGeometry("C1", "C", 2, 0, 0.0, (20.0, -600.0), math.pi / 2, 400.0)
        p1 = [(20.0, -200.0), (20.0, -50.0), (-50.0, 12.5), (-300.0, 12.5)]
        r1 = _ramp("r1", [p1], 0.0, 0.0, Attachment("C1", "Out-M", 400.0, 0.0, math.pi / 2, 0.0),
                   Attachment("A2", "In-R", 800.0, -2 * lw, math.pi, 0.0), hump=6.5)
        p2 = [(27.5, -200.0), (27.5, -100.0), (150.0, -7.5), (300.0, -7.5)]
        r2 = _ramp("r2", [p2], 0.0, 0.0, Attachment("C1", "Out-R", 400.0, -2 * lw, math.pi / 2, 0.0),
                   Attachment("A1", "In-R", 800.0, -2 * lw, 0.0, 0.0))
        return InterchangeGeometry("cy", 0, 5, lw, 2.5, rw, (0.0, 6.5), (a1, a2, c1), (r1, r2))
    raise ValueError(f"unknown sample {kind!r} (one of {', '.join(SAMPLES)})")


def detached_ramp(g: InterchangeGeometry, shift_m: float = 30.0) -> InterchangeGeometry:
    """``g`` with its first ramp's start moved ``shift_m`` along its parent: the ramp no
    longer begins where it attaches (bad input the writer must refuse, naming the ramp)."""
    ramp = g.ramps[0]
    st = ramp.start
    moved = type(st)(st.parent, st.label, st.s_m + shift_m, st.offset_m, st.heading_rad, st.z_m)
    ramps = (type(ramp)(**{**ramp.__dict__, "start": moved}),) + tuple(g.ramps[1:])
    return type(g)(g.class_id, g.sample, g.seed, g.lane_width_m, g.shoulder_width_m,
                   g.ramp_lane_width_m, g.levels_m, g.roads, ramps)
