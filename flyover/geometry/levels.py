"""Level plan: the crest heights fixed up front, and the room ramps leave for them.

Decides the crest of every direct left turn, the height of a stub's free end
and the room a ramp leaves toward the crossing for its children; reads the road
layout, the ramps' movements (:mod:`flyover.geometry.chains`), the targets and
the settings.

* A direct left turn crosses the through expressways, so its crest is the
  lowest level ``clearance_m`` above the highest of them. Where left turns run
  both ways between two expressways they cross each other: those leaving the
  second expressway (a T's terminating one) go one level higher — the two
  flyover levels of a four-level stack, the three levels of a directional T. A left
  turn between two expressways that both end here (a 5-leg's, on one level) crosses
  the ramps on that level and the flyovers leaving or joining it: its crest is the
  lowest level ``clearance_m`` above that level and every other planned crest; where
  such left turns run both ways between a line and a T meeting it at a junction of its
  own (DC's E Street Expressway) they cross, and those into the T go one level higher.
* A stub feeding or fed by such a ramp ends ``clearance_m`` from its road
  toward that crest; if its other children (right turns) go on to a road (a
  turbine), no higher than ``clearance_m`` (and 0.5 m) under the lowest
  planned crest, so that they pass under every flyover.
* A chain of split stubs one of which splits into a loop to a road crossing the one the
  chain comes from (Columbus's collector road ``r8``, ``r13`` beside I-270, whose loop
  ``r6`` goes to I-70) passes under (over) that road first: its stubs end ``clearance_m``
  and a margin below (above) it, and a stub splitting off such a stub goes on at its
  height (:meth:`LevelPlan.loop_road_z`, :meth:`LevelPlan.continues_level`).
* A planned ramp's road ends, and those of a ramp it leaves or joins, keep room
  from the crossing to climb to (descend from) the crest at the ramp's slope.
* A stub one of whose children is a loop's outer connector (a cloverstack's ``eA1``,
  ``oA1`` going round ``lB1``) ends far enough out for that child to go round the loop
  at their radius targets (:meth:`LevelPlan.round_room`); a collector-distributor road
  runs straight far enough for the connector leaving (joining) it to go round the loop
  joining (leaving) it (:meth:`LevelPlan.collector_room`).
"""

from __future__ import annotations

import math
from typing import Mapping

import numpy as np

from flyover.geometry.chains import Movements, ends, road_of, wrap
from flyover.geometry.profile import loop_radius
from flyover.geometry.settings import Z_MARGIN, LayoutSettings, RampFeatures
from flyover.geometry.straight import built_radius

__all__ = ["LevelPlan", "round_diagonal"]


class LevelPlan:
    """Crests (``crests``: ramp → z) and the heights and room that follow from them."""

    def __init__(self, moves: Movements, features: Mapping[str, RampFeatures],
                 st: LayoutSettings):
        self.moves, self.features, self.st = moves, features, st
        self.roads = moves.roads
        self.crests = self._crests()

    def _crests(self) -> dict[str, float]:
        topo, st, roads = self.moves.topo, self.st, self.roads
        through = [r for r in roads.values() if np.isinf(r.t_lo) and np.isinf(r.t_hi)]
        top = max(r.z for r in through or roads.values())
        levels = [z for z in st.levels_m if z >= top + st.fit.clearance_m - 1e-6]
        if not levels:
            return {}
        lefts = {}
        for ramp in topo.ramps:
            start, end = ends(topo, ramp)
            a, b = road_of(topo, ramp, False), road_of(topo, ramp, True)
            if start is None or end is None or not a or not b:
                continue
            raw = wrap(roads[b].heading - roads[a].heading)
            if raw > 1.0 and not self.moves.is_loop(ramp):
                lefts[ramp] = (roads[a].expressway, roads[b].expressway)
        ending = {r.expressway for r in roads.values()} - {r.expressway for r in through}
        plan, between = {}, []
        for ramp, (ea, eb) in lefts.items():
            if ea in ending and eb in ending:
                between.append(ramp)
                continue
            both_ways = (eb, ea) in lefts.values()
            k = roads[road_of(topo, ramp, False)].level if both_ways else 0
            plan[ramp] = float(levels[min(k, len(levels) - 1)])
        # a left turn between two expressways ending here (on one level, a 5-leg's)
        # crosses the ramps on that level and the flyovers leaving or joining it: over
        # them all
        top_plan = max(plan.values(), default=top)
        for ramp in between:
            za = max(roads[road_of(topo, ramp, f)].z for f in (False, True))
            over = [z for z in st.levels_m
                    if z >= max(za, top_plan) + st.fit.clearance_m - 1e-6]
            # a T meeting a line at a junction of its own (its roads' ``junction``): where
            # left turns run both ways between them they cross, and those into the T go one
            # level higher (DC's r10 over r12, r13): they climb on the line beyond the
            # junction and descend on the T's leg, which keeps room for two levels, where
            # those leaving it descend between the junction and the line's terminal
            b = roads[road_of(topo, ramp, True)]
            up = int(b.junction is not None and any(
                roads[road_of(topo, o, False)].junction is not None for o in between))
            if over:
                plan[ramp] = float(over[min(up, len(over) - 1)])
        return plan

    def low_connector(self, ramp: str) -> bool:
        """A ramp between two other ramps, without a planned crest."""
        return ramp not in self.crests and all(e is not None and e[0] not in self.roads
                                               for e in self.moves.ends(ramp))

    def stub_z(self, ramp: str, z_road: float, zf: float) -> float:
        """Height of a stub's free end: the clearance toward its planned children's crest
        (so that they clear the roads near the stub), else ``zf``. If its unplanned
        children (right turns) go on to a road, they are fitted after the flyovers: then
        no higher than the clearance (and a margin) under the lowest planned crest, so
        that they pass under every flyover. (Right turns between two stubs are fitted
        before the flyovers, which pass round or over them.)"""
        kids = self.moves.kids(ramp)
        crests = [self.crests[k] for k in kids if k in self.crests]
        if not crests:
            return zf
        c = max(crests)
        if c <= z_road:
            return zf
        clear = self.st.fit.clearance_m
        z = min(c, z_road + clear)
        if any(k not in self.crests and not self.low_connector(k) for k in kids):
            # they are fitted after the flyovers (they go on to a road): keep them under
            z = min(z, min(self.crests.values()) - clear - Z_MARGIN)
        return float(z) if z > z_road + 0.25 else float(min(c, z_road + clear))

    def loop_road_z(self, ramp: str) -> float | None:
        """The height of the road a loop splitting off ``ramp``'s chain goes to (a child
        of ``ramp``, or of a split stub splitting off it: Columbus's ``r6`` off ``r13``
        off ``r8``), if that road crosses the road the chain comes from: the chain passes
        under (over) it before the loop leaves it, so its stubs end ``clearance_m`` (and
        a margin) below (above) it. ``None`` otherwise."""
        src = road_of(self.moves.topo, ramp, False)
        if not src or src not in self.roads:
            return None
        for kid in self.moves.kids(ramp):
            a, b = ends(self.moves.topo, kid)
            if a is None or a[0] != ramp:
                continue
            if b is None:
                z = self.loop_road_z(kid)
                if z is not None:
                    return z
            elif self.moves.is_loop(kid) and b[0] in self.roads \
                    and self.roads[b[0]].expressway != self.roads[src].expressway:
                return float(self.roads[b[0]].z)
        return None

    def continues_level(self, ramp: str) -> bool:
        """A split stub splitting off a split stub whose chain passes under (over) the road
        of a loop leaving it (:meth:`loop_road_z`): the two are one collector road, which
        goes on at the height its first stub reached (Columbus's ``r13`` after ``r8``); it
        is a level ramp (:func:`flyover.geometry.feasibility.level_ramps`)."""
        start, end = ends(self.moves.topo, ramp)
        if end is not None or start is None or start[0] in self.roads:
            return False
        p_start, p_end = ends(self.moves.topo, start[0])
        return p_end is None and self.loop_road_z(ramp) is not None

    def kids_room(self, kids: list[str], z: float, turning: bool = True) -> float:
        """Room a ramp leaves toward the crossing for the ramps leaving or joining it
        (``kids``, at height ``z``): for the planned ones to climb to their crest, and
        (``turning``) for the turning ones to turn at their radius (``turn_room`` times
        it: the turn, and its straight leads and transitions; ``inf_reference_m`` for an
        ``inf`` target)."""
        extra = 0.0
        for k in kids:
            if k not in self.features:
                continue
            if k in self.crests:
                gk = max(self.features[k].slope_pct, 0.5) / 100.0
                extra = max(extra, abs(self.crests[k] - z) / gk + self.st.fit.transition_m)
            mov = self.moves.movement(k)
            if turning and mov is not None and abs(mov) > 1.0:
                r = self.features[k].radius_m
                extra = max(extra, self.st.turn_room * r if math.isfinite(r)
                            else self.st.fit.inf_reference_m)
            if turning:
                extra = max(extra, self.round_room(k))
        return extra

    def round_room(self, ramp: str) -> float:
        """Room toward the crossing where ``ramp`` starts (ends) on a stub, if it is the
        outer connector of a loop (:meth:`Movements.goes_round_loop`, on a road both
        attach to), so that it can go round the loop without an S-bend
        (:func:`round_diagonal`). 0 otherwise."""
        moves = self.moves
        mine = {e[0] for e in moves.ends(ramp) if e is not None and e[0] in self.roads}
        for loop in moves.topo.ramps:
            theirs = {e[0] for e in moves.ends(loop) if e is not None and e[0] in self.roads}
            if loop in self.features and ramp in self.features and any(
                    moves.goes_round_loop(ramp, loop, road) for road in sorted(mine & theirs)):
                zs = [self.roads[r].z for r in theirs]
                return round_diagonal(self.moves, self.features, self.st, ramp, loop, zs)
        return 0.0

    def collector_room(self, cd: str) -> tuple[float, float]:
        """How far from the crossing (m, along the carriageway it runs beside) the
        collector-distributor road ``cd`` must run straight before and after it, so that
        the outer connector leaving it before the loop joins it goes round that loop
        (``cloverleaf_cd``'s ``oA1`` leaving ``cA1`` round ``lB1``), and the one joining it
        after the loop leaves it round that one (``oB2`` round ``lA1``): the connector's
        diagonal (:func:`round_diagonal`) from the corner of the two C-D roads (their offset
        from their carriageways' edges), moved out by as far as the loop may join or leave
        them beyond the crossing's room (``stub_window_m``,
        :meth:`flyover.geometry.loop_room.LoopRoom.on_collector`). 0 at an end with no such
        pair, and for a ramp that is no C-D road. Sized from its own ramps' radii alone (twice
        the widest, at both ends), the C-D road ended short of where a 280 m connector
        clears a 210 m loop (it went over the loop), and ran far beyond where a narrow pair
        needs it."""
        moves, st, g = self.moves, self.st, self.moves.g
        if not moves.same_road(cd):
            return 0.0, 0.0
        road = ends(moves.topo, cd)[0][0]
        kids = [k for k in moves.kids(cd) if k in self.features]
        other = max([x.half_width for x in self.roads.values()
                     if x.expressway != self.roads[road].expressway] or [0.0])
        corner = other + st.crossing_margin_m + st.stub_window_m \
            + st.cd_offset_m + moves.lanes(cd) * st.ramp_lane_width_m
        out = [0.0, 0.0]
        for conn, loop in ((c, lp) for c in kids for lp in kids
                           if moves.is_outer_connector(c, lp)):
            pos = [(g.edges[cd, k] if g.has_edge(cd, k) else g.edges[k, cd]).get("pos")
                   for k in (conn, loop)]
            if None in pos or pos[0] == pos[1]:
                continue
            zs = [self.roads[r].z for r in (moves.road_of(loop, False), moves.road_of(loop, True))
                  if r in self.roads]
            end = 0 if pos[0] < pos[1] else 1
            room = round_diagonal(moves, self.features, st, conn, loop, zs)
            out[end] = max(out[end], corner + room)
        return out[0], out[1]


def round_diagonal(moves: Movements, features: Mapping[str, RampFeatures], st: LayoutSettings,
                   ramp: str, loop: str, zs: list[float]) -> float:
    """How far from the corner of the two roads a loop joins the outer connector
    ``ramp`` must leave (join) the road it shares with ``loop`` to go round it: a loop of
    radius ``R`` (or, if its climb between its roads at heights ``zs`` at its slope is
    longer than its turn, the radius of a loop turning that length) in the corner of
    the two roads reaches ``sqrt(2) R + R`` out along the corner's diagonal (beyond the
    room ``c`` between their centre lines); a connector running along that diagonal
    outside it meets the road ``2 R + sqrt(2) (R + c)`` from the corner, and leaves it
    about half its own radius earlier (a 45° turn), after a taper (``gap_m``)."""

    def built(r: float) -> float:
        return built_radius(r, st.fit.inf_reference_m)

    c = moves.round_gap(ramp, loop, st.ramp_lane_width_m)
    zs = zs or [0.0]  # its climb between its roads
    r_loop = loop_radius(built(features[loop].radius_m), max(zs) - min(zs),
                         features[loop].slope_pct, st.fit.transition_m)
    return 2 * r_loop + math.sqrt(2) * (r_loop + c) \
        + 0.5 * built(features[ramp].radius_m) + st.gap_m
