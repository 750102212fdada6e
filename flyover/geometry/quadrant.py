"""The quadrant of a loop by a collector road: where its outer connector goes round it.

Decides, for an outer connector that goes round a loop only by way of a collector road
(:meth:`flyover.geometry.chains.Movements.round_by_collector`: Columbus I-70 / I-270's
``r2``, from the free end of the stub ``r8`` into that of ``r14``, round the loop ``r5``
from I-70 East into the collector road ``r13``; no catalog design has one), how far from
the crossing the stubs the connector leaves and joins must end (:meth:`CollectorQuadrant.reach`),
the fences that keep them out of the loop's quadrant (:meth:`CollectorQuadrant.fences`),
and where on the collector road the loop joins it, near the crossing
(:meth:`CollectorQuadrant.window`). Reads the road layout, the ramps' kinds, the ramps
fitted so far and their targets. The attachment windows (:mod:`flyover.geometry.rails`)
and the loop room (:mod:`flyover.geometry.loop_room`, whose fences include these) use it.
"""

from __future__ import annotations

import math
from typing import Mapping

import numpy as np

from flyover.geometry.chains import Movements, ends
from flyover.geometry.fitted import FittedRamps
from flyover.geometry.loop_room import round_need, side_band
from flyover.geometry.profile import loop_radius
from flyover.geometry.settings import LayoutSettings, RampFeatures
from flyover.geometry.straight import built_radius

__all__ = ["CollectorQuadrant", "LOOP_SPREAD"]

#: how much wider than its radius a fitted loop turns (a Bezier loop is no circle)
LOOP_SPREAD = 1.3


class CollectorQuadrant:
    """The quadrant a loop by a collector road and its outer connector share, given what
    is fitted so far."""

    def __init__(self, moves: Movements, fitted: FittedRamps, st: LayoutSettings,
                 features: Mapping[str, RampFeatures]):
        self.moves, self.fitted, self.st, self.features = moves, fitted, st, features
        self.roads, self.topo = moves.roads, moves.topo

    def fences(self, stub: str) -> list[tuple[float, ...]]:
        """Where a stub fitted before a loop must not go so that its child, the loop's
        outer connector by a collector road (:meth:`Movements.goes_round` with
        ``collectors``: Columbus's ``r2`` from the stub ``r8`` into the stub ``r14``, round
        the loop ``r5`` from I-70 East into the collector road ``r13``), can go round the
        loop: on the stub's side of its road, from the crossing out to
        :meth:`reach`, at every height. Empty for any other ramp."""
        reach = self.reach(stub)
        if reach is None:
            return []
        road, is_start, label, t_q, need = reach
        r = self.roads[road]
        lat = side_band(r, label, self.st.lane_width_m)
        span = (t_q - need, t_q + 1e4) if is_start else (t_q - 1e4, t_q + need)
        return [(r.origin[0], r.origin[1], math.cos(r.heading), math.sin(r.heading), *span,
                 *lat)]

    def reach(self, stub: str) -> tuple | None:
        """How far from the crossing (m, along its road) a stub's free end must lie for
        its child to go round a loop by a collector road (:meth:`fences`):
        ``(road, is_start, label, crossing station, reach)``, the largest over such loops
        not fitted yet, or ``None``. The loop is taken as a circle
        ``LOOP_SPREAD`` times its radius (at least that of a loop as long as its climb,
        :func:`flyover.geometry.profile.loop_radius`) in the quadrant's corner, beyond the
        other road's half width and the room between connector and loop; the connector
        turns round every point of it (:func:`round_need` at its radius)."""
        moves = self.moves
        if not moves.is_stub(stub):
            return None
        start, end = ends(self.topo, stub)
        fixed, is_start = (start, True) if start is not None else (end, False)
        if fixed is None or fixed[0] not in self.roads:
            return None
        road, label = fixed
        r, st = self.roads[road], self.st
        d = np.array([math.cos(r.heading), math.sin(r.heading)])
        best = None
        for kid in moves.kids(stub):
            for loop in self.topo.ramps:
                if kid not in self.features or loop not in self.features \
                        or loop in self.fitted.fits or not moves.round_by_collector(kid, loop):
                    continue
                a, b = moves.through_stubs(loop, False), moves.through_stubs(loop, True, True)
                other = b if a == road else a if b == road else None
                if other is None or other not in self.roads:
                    continue
                q = self.roads[other]
                e = np.array([math.cos(q.heading), math.sin(q.heading)])
                across = float(d[0] * e[1] - d[1] * e[0])
                if abs(across) < 0.5:
                    continue
                rel = np.array(q.origin) - np.array(r.origin)
                t_q = float(rel[0] * e[1] - rel[1] * e[0]) / across  # the crossing
                r_l = LOOP_SPREAD * self._taken_radius(self.features[loop], abs(q.z - r.z))
                r_c = built_radius(self.features[kid].radius_m, st.fit.inf_reference_m)
                c = moves.round_gap(kid, loop, st.ramp_lane_width_m)
                th = np.linspace(0.0, 2.0 * math.pi, 73)
                along = q.half_width / abs(across) + c + st.gap_m + r_l * (1.0 + np.cos(th))
                out_m = 3.0 * c + r_l * (1.0 + np.sin(th))
                need = float(np.max(along + round_need(out_m + c, r_c)))
                if best is None or need > best[4]:
                    best = (road, is_start, label, t_q, need)
        return best

    def window(self, cd: str, loop: str, feat: RampFeatures, lo: float, hi: float
                      ) -> tuple[float, float]:
        """The window ``lo..hi`` (stations) of a ``loop`` joining the collector road ``cd``
        (a stub, :meth:`flyover.geometry.chains.Movements.collects`: Columbus's ``r5``
        into ``r13``): where ``cd`` lies on the loop's side of the road the loop leaves,
        from that expressway's half width and ``crossing_margin_m`` out to its radius
        more (at least that of a loop as long as its climb), so that the loop turns in the
        corner of its quadrant and its outer connector can go round it. Unchanged where
        ``cd`` does not pass there."""
        start = ends(self.topo, loop)[0]
        if start is None or start[0] not in self.roads or not any(
                self.moves.round_by_collector(c, loop) for c in self.topo.ramps):
            return lo, hi
        q, st = self.roads[start[0]], self.st
        stn = self.fitted.stations[cd]
        left = np.array([-math.sin(q.heading), math.cos(q.heading)])
        side = -1.0 if start[1].side == "right" else 1.0
        out_m = side * ((stn["xy"] - np.array(q.origin)) @ left)
        r_l = self._taken_radius(feat, abs(q.z - float(stn["z"][-1])))
        near = q.half_width + st.crossing_margin_m
        length = float(stn["s"][-1])
        inside = (out_m >= near) & (out_m <= near + r_l) & (stn["s"] >= 0.05 * length) \
            & (stn["s"] <= 0.95 * length)
        if not inside.any():
            return lo, hi
        s = stn["s"][inside]
        return (float(s.min()), float(s.max())) if s.max() - s.min() >= 1.0 else (lo, hi)

    def _taken_radius(self, feat: RampFeatures, height: float) -> float:
        """The radius a loop of ``feat`` takes up climbing ``height``
        (:func:`flyover.geometry.profile.loop_radius`; ``inf``: ``inf_reference_m``)."""
        st = self.st
        return loop_radius(built_radius(feat.radius_m, st.fit.inf_reference_m), height,
                           feat.slope_pct, st.fit.transition_m)
