"""Room round a loop: where a cloverleaf's outer connector and the loop it goes round
keep out of each other's way.

Decides how far along a road a loop keeps from a fitted stub whose child goes round
it (:meth:`LoopRoom.room_round`), the fences that keep the loop's body off that
child's turn (:meth:`LoopRoom.fences`), which fitted loops a ramp goes round
(:meth:`LoopRoom.round_loops`) and where along their shared road a ramp must attach to
go round one (:meth:`LoopRoom.round_loop`; on a collector-distributor road
:meth:`LoopRoom.on_collector`); its fences include those of the quadrant a loop by
a collector road shares with its connector (:mod:`flyover.geometry.quadrant`). Reads the
road layout, the ramps' kinds
(:class:`flyover.geometry.chains.Movements`), the ramps fitted so far and their
targets. The attachment windows (:mod:`flyover.geometry.rails`) and the build loop
(:mod:`flyover.geometry.build`) use it.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Mapping

import numpy as np

from flyover.geometry.chains import Movements, ends
from flyover.geometry.fitted import FittedRamps
from flyover.geometry.settings import LayoutSettings, RampFeatures
from flyover.geometry.straight import built_radius

if TYPE_CHECKING:
    from flyover.geometry.quadrant import CollectorQuadrant
    from flyover.geometry.roads import RoadLine

__all__ = ["LoopRoom", "round_need", "side_band"]


class LoopRoom:
    """Room between loops and the ramps that go round them, given what is fitted so far."""

    def __init__(self, moves: Movements, fitted: FittedRamps, st: LayoutSettings,
                 features: Mapping[str, RampFeatures], quadrant: "CollectorQuadrant"):
        self.moves, self.fitted, self.st, self.features = moves, fitted, st, features
        self.roads, self.g, self.topo = moves.roads, moves.g, moves.topo
        #: the quadrant of a loop by a collector road and its outer connector
        self.quadrant = quadrant

    def room_round(self, loop: str, stub: str) -> float:
        """Room (m) a ``loop`` keeps along its road from the free end of a fitted ``stub``
        on it, when a child of the stub is the loop's outer connector (a cloverstack's
        ``oA1`` leaves ``eA1`` and goes round ``lB1``): the connector starts where the stub
        ends, so there it must have room to turn at its radius round the loop: its radius
        target (``inf``: ``inf_reference_m``) and the room between their centre lines (as
        :meth:`round_loop`). 0 otherwise."""
        moves = self.moves
        if not moves.is_loop(loop) or not moves.is_stub(stub):
            return 0.0
        for kid in moves.kids(stub):
            roads = {e[0] for e in ends(self.topo, kid) if e is not None and e[0] in self.roads}
            # (through stubs, a loop joining a collector road: Columbus's r2 round r5)
            if kid in self.features and (any(moves.goes_round_loop(kid, loop, r) for r in roads)
                                         or moves.round_by_collector(kid, loop)):
                r_kid = built_radius(self.features[kid].radius_m, self.st.fit.inf_reference_m)
                return r_kid + self.fitted.width[kid] + self.fitted.width[loop] / 2 + 1.0
        return 0.0

    def fences(self, loop: str) -> list[tuple[float, ...]]:
        """Where a ``loop`` must not go so that an outer connector leaving a fitted stub
        can go round it (:meth:`room_round`): on the side of each road it shares with such
        a stub, everything within that room of the stub's free end and beyond it, away
        from the crossing (:attr:`flyover.geometry.fit.Obstacles.lines` rows without their
        height: the layout keeps them out at every height, as a keep-out loop). The loop's
        window there begins beyond it
        (:meth:`flyover.geometry.rails.RoadWindows.road_rail`); its body may not reach
        back. For a stub whose child goes round a fitted loop (:meth:`connector_fences`),
        where the stub must not go."""
        out = self.connector_fences(loop) + self.quadrant.fences(loop)
        for end, is_start in zip(ends(self.topo, loop), (True, False)):
            if end is None or end[0] not in self.roads:
                continue
            road, label = end
            r = self.roads[road]
            pos = self.g.edges[(road, loop) if is_start else (loop, road)].get("pos")
            if pos is None:
                continue
            lat = side_band(self.roads[road], label, self.st.lane_width_m)
            for p, t_min, t_max, other, _ in self.fitted.attached.get(road, []):
                room = self.room_round(loop, other)
                if room <= 0 or p == pos:
                    continue
                t = (t_max - 1e4, t_max + room) if p < pos else (t_min - room, t_min + 1e4)
                out.append((r.origin[0], r.origin[1], math.cos(r.heading), math.sin(r.heading),
                            *t, *lat))
        return out

    def connector_fences(self, stub: str) -> list[tuple[float, ...]]:
        """Where a stub on a road must not go so that its child, the outer connector of a
        loop fitted before it (:meth:`flyover.geometry.chains.Movements.is_outer_connector`),
        can go round that loop from (into) the stub's free end: on the stub's side of its
        road, everything from where the connector must leave (join) the road to go round the
        loop (:meth:`round_loop`, at the connector's radius and width) toward the loop, at
        every height (Columbus's ``r1``, off I-70 West, whose child ``r11`` goes round the
        loop ``r6`` joining I-70 West: ``r1``, fitted first, ended where ``r11`` could not
        go round ``r6``, and ``r11`` was lifted over it). Empty for any other ramp."""
        moves = self.moves
        if not moves.is_stub(stub):
            return []
        start, end = ends(self.topo, stub)
        fixed, is_start = (start, True) if start is not None else (end, False)
        if fixed is None or fixed[0] not in self.roads:
            return []
        road, label = fixed
        pos = self.g.edges[(road, stub) if is_start else (stub, road)].get("pos")
        if pos is None:
            return []
        r, st = self.roads[road], self.st
        lat = side_band(self.roads[road], label, self.st.lane_width_m)
        out = []
        for kid in moves.kids(stub):
            if kid not in self.features:
                continue
            for p, _, _, loop, _ in self.fitted.attached.get(road, []):
                if p == pos or not moves.is_outer_connector(kid, loop):
                    continue
                side = 1 if p < pos else -1  # the connector leaves after (before) the loop
                t = self.round_loop(loop, road, self.fitted.width[kid], side, self.features[kid])
                span = (t - 1e4, t) if side > 0 else (t, t + 1e4)
                out.append((r.origin[0], r.origin[1], math.cos(r.heading), math.sin(r.heading),
                            *span, *lat))
        return out

    def round_loops(self, ramp: str) -> frozenset[str]:
        """The fitted loops ``ramp`` goes round (a cloverleaf's outer connector: the loop
        joining the same two roads the other way round, on the road they share, or with
        its chain through stubs: :meth:`flyover.geometry.chains.Movements.is_outer_connector`;
        or through a collector road: :meth:`~flyover.geometry.chains.Movements.round_by_collector`)."""
        return frozenset(o for o in self.fitted.fits if self.moves.is_outer_connector(ramp, o)
                         or self.moves.round_by_collector(ramp, o))

    def round_loop(self, loop: str, road: str, width: float, side: int,
                   feat: RampFeatures) -> float:
        """Where along ``road`` a ramp turning at its target radius must attach to go round
        the fitted ``loop``: after (``side`` +1) or before (-1) every point of it, by the
        distance a connector needs to get as far from the road (plus the room between
        their centre lines) when it turns at its radius until it runs at 45° to the road,
        then straight on (:func:`round_need`), as a real outer connector runs across its
        quadrant's diagonal outside the loop (the same shape as
        :meth:`flyover.geometry.levels.LevelPlan.round_room`). A lone arc of its radius
        (what was required before) leaves it inside the loop's far side whenever the
        loop reaches farther from the corner than the arc: the fit then went over the
        loop (one in ten of the workflow's cloverleaf connectors)."""
        r, st = self.roads[road], self.st
        d = np.array([math.cos(r.heading), math.sin(r.heading)])
        rel = self.fitted.stations[loop]["centre"] - np.array(r.origin)
        t = rel @ d
        lat = np.clip(-(rel @ np.array([-d[1], d[0]])) - r.lanes * st.lane_width_m, 0.0, None)
        rad = built_radius(feat.radius_m, st.fit.inf_reference_m)
        c = width + self.fitted.width[loop] / 2 + 1.0
        need = round_need(lat + c, rad)
        return float(np.max(t + need)) if side > 0 else float(np.min(t - need))

    def on_collector(self, cd: str, ramp: str, pos: float, width: float,
                     feat: RampFeatures, lo: float, hi: float) -> tuple[float, float]:
        """The window ``lo..hi`` (stations) of ``ramp`` on the collector-distributor road
        ``cd``, for a loop or an outer connector (``cloverleaf_cd``): a loop attaches
        within ``stub_window_m`` beyond the crossing's room (the other expressway's half
        width and ``crossing_margin_m``) on its side of the crossing, as a loop on a road
        does (in the window ``pos`` gives, 15 % of ``cd`` either side, a loop on a 2 km
        C-D road attached up to 500 m out and swept the quadrant); an outer connector
        where it goes round each fitted loop on ``cd`` (:meth:`round_loop` along the
        carriageway ``cd`` runs beside, as stations of ``cd``), else as long a window
        beyond that, on ``cd``'s middle 90 %. Unchanged where ``cd`` leaves no room."""
        road = ends(self.topo, cd)[0][0]
        r, st = self.roads[road], self.st
        stn = self.fitted.stations[cd]
        along = np.maximum.accumulate(
            (stn["xy"] - np.array(r.origin)) @ np.array([math.cos(r.heading),
                                                        math.sin(r.heading)]))
        length = float(stn["s"][-1])
        first, last = 0.05 * length, 0.95 * length
        if self.moves.is_loop(ramp):
            other = max([x.half_width for x in self.roads.values()
                         if x.expressway != r.expressway] or [0.0])
            tz = other + st.crossing_margin_m
            start = ends(self.topo, ramp)[0]
            t_lo, t_hi = (tz, tz + st.stub_window_m) if start is not None and \
                start[0] == cd else (-tz - st.stub_window_m, -tz)
            s_lo, s_hi = (float(np.interp(t, along, stn["s"])) for t in (t_lo, t_hi))
            s_lo, s_hi = max(s_lo, first), min(s_hi, last)
            return (s_lo, s_hi) if s_hi - s_lo >= 1.0 else (lo, hi)
        new_lo, new_hi = lo, hi
        for p, _, _, other, _ in self.fitted.attached.get(cd, []):
            if p == pos or not self.moves.is_outer_connector(ramp, other):
                continue
            side = 1 if p < pos else -1
            t = self.round_loop(other, road, width, side, feat)
            s = float(np.interp(t, along, stn["s"]))
            new_lo, new_hi = (max(new_lo, s), new_hi) if side > 0 else (new_lo, min(new_hi, s))
        if new_hi - new_lo >= 1.0:
            return new_lo, new_hi
        span = hi - lo
        if lo < new_lo < last - 1.0:  # beyond its window: as long a window beyond the bound
            return new_lo, min(last, new_lo + span)
        if first + 1.0 < new_hi < hi:
            return max(first, new_hi - span), new_hi
        return lo, hi


def side_band(road: RoadLine, label, lane_width_m: float) -> tuple[float, float]:
    """The lateral band (m, left positive) on ``label``'s side of ``road`` beyond its
    lanes (a right label) or its line (a left one): where a fence on that side lies."""
    edge = road.lanes * lane_width_m
    return (-1e4, -edge - 0.5) if label.side == "right" else (0.5, 1e4)


def round_need(lateral_m: np.ndarray, radius_m: float) -> np.ndarray:
    """How far along a road (m) before (after) where it attaches a connector is
    ``lateral_m`` from the road, if it turns off (onto) it at ``radius_m`` up to 45° and
    runs straight from there: along the arc while it is within ``(1 - cos 45°)`` of its
    radius of the road, then one metre along for each metre out.

    >>> [round(float(x), 1) for x in round_need(np.array([0.0, 100.0, 200.0]), 100.0)]
    [0.0, 141.4, 241.4]
    """
    lat = np.asarray(lateral_m, float)
    turn = (1.0 - math.cos(math.pi / 4)) * radius_m  # how far out the 45° arc reaches
    arc = np.sqrt(np.clip(radius_m**2 - (radius_m - np.minimum(lat, turn)) ** 2, 0.0, None))
    return np.where(lat < turn, arc, radius_m * math.sin(math.pi / 4) + lat - turn)
