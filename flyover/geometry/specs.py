"""Ramp specs: what one ramp is asked to be before it is fitted.

Decides a ramp's turn, number of Bézier pieces, free end (for a stub), the room
its ends keep from the crossing, its crest and its straight leads (a
:class:`flyover.geometry.fit.RampSpec`); reads the ramp's kind, the level plan,
the attachment windows and the ramps fitted so far.

* A ramp attached to other ramps (e.g. a loop on collector-distributor roads)
  turns by the parents' local heading difference, on the branch nearest the
  movement of the roads its chain connects. Direct left turns are splines of
  three pieces (climb along the road, turn, descend along it), loops and
  straight-on ramps of two, other ramps one.
* A stub ramp with no end (it splits into other ramps) or no start (formed by
  merging ramps) gets a free end; it climbs a third of the height between its
  road and its children's roads, so every ramp of a chain climbs, over a free
  end far enough out to reach that height at its slope, and keeps the room its
  children need (:meth:`flyover.geometry.levels.LevelPlan.kids_room`).
* A ramp that climbs may run straight along its parent's heading at either end
  for as long as the climb from that end takes (its leads).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from flyover.geometry.chains import Movements, ends, road_of, wrap
from flyover.geometry.fit import FreeEnd, RampSpec
from flyover.geometry.fitted import FittedRamps
from flyover.geometry.levels import LevelPlan
from flyover.geometry.profile import climb_distance
from flyover.geometry.rails import AttachmentWindows
from flyover.geometry.settings import GeometryError, LayoutSettings, RampFeatures

__all__ = ["RampSpecs"]


class RampSpecs:
    """Makes the :class:`RampSpec` of a ramp for given targets (see the module doc)."""

    def __init__(self, moves: Movements, levels: LevelPlan, fitted: FittedRamps,
                 windows: AttachmentWindows, st: LayoutSettings):
        self.moves, self.levels, self.fitted, self.windows, self.st = \
            moves, levels, fitted, windows, st
        self.topo, self.roads, self.g = moves.topo, moves.roads, moves.g

    def spec(self, ramp: str, feat: RampFeatures, level: bool = True) -> RampSpec:
        """The spec of ``ramp`` for targets ``feat``; ``level``: an end on a ramp attaches
        where that ramp is level, if it can (else, and with ``level`` False, where it is no
        steeper than the slope target: :meth:`flyover.geometry.rails.AttachmentWindows.level_part`)."""
        start, end = ends(self.topo, ramp)
        width = self.fitted.width[ramp]
        st, plan = self.st, self.levels.crests
        if start is None and end is None:
            raise GeometryError("ramp has neither a start nor an end", source=self.topo.source,
                                element=ramp)
        # headings of the ends (nominal) → raw turn
        h_a = self._nominal_heading(ramp, start, True) if start else None
        h_b = self._nominal_heading(ramp, end, False) if end else None
        free = None
        if start is None or end is None:
            raw, loop = 0.0, False
            fixed = start or end
            side = fixed[1].side
            sgn = -1.0 if side == "right" else (1.0 if side == "left" else 0.0)
            lat = (sorted((sgn * 3.0, sgn * 40.0)) if sgn else (-10.0, 10.0))
            if end is None:  # split stub: free end
                z0 = self._end_z(start)
                zf = self.levels.stub_z(ramp, z0, z0 + (self._goal_z(ramp, True) - z0) / 3.0)
            else:
                z1 = self._end_z(end)
                zf = self.levels.stub_z(ramp, z1, z1 + (self._goal_z(ramp, False) - z1) / 3.0)
            # the free end is far enough out for the stub to climb to it at its slope
            z_fix = self._end_z(start or end)
            g = max(feat.slope_pct, 0.5) / 100.0
            climb = float(climb_distance(zf - z_fix, g, st.fit.transition_m)) + 60.0
            free = FreeEnd((60.0, max(400.0, climb)), lat, (-np.pi / 4, np.pi / 4), zf)
            stub_extra = self.levels.kids_room(self.moves.kids(ramp), zf)
            if stub_extra > 0:  # the free end keeps that room from the crossing
                free = replace(free, forward=(60.0, max(250.0, climb)))
                stub_extra += free.forward[1]
        else:
            raw = wrap(h_b - h_a)
            loop = self.moves.is_loop(ramp)
            mov = self.moves.movement(ramp)
            if mov is not None:  # the branch of the local turn nearest the roads' movement
                if loop:
                    mov -= 2 * np.pi
                raw = mov + wrap(raw - mov)
        turn = raw
        pieces = 2 if (abs(turn) > 2.2 or abs(turn) < 0.3) else 1
        if start is not None and end is not None and not loop and turn > 1.0:
            pieces = 3  # a left turn over the roads: climb along its road, turn, descend along
        # a direct left turn crosses the other roads: leave room to climb / descend a level
        extra = stub_extra if free is not None else 0.0
        extra_b = extra
        if start is not None and end is not None and not loop and turn > 1.0:
            g = max(feat.slope_pct, 0.5) / 100.0
            crest = plan.get(ramp)
            if crest is not None:  # the whole climb before the crossing, descent after
                extra, extra_b = (max(st.level_height_m, crest - self._end_z(e)) / g
                                  + st.fit.transition_m for e in (start, end))
            else:
                extra = extra_b = st.level_height_m / g + st.fit.transition_m
        if free is None:  # room for the planned ramps leaving / joining this one
            g_ = self.g
            outs = [v for _, v, d in g_.out_edges(ramp, data=True) if d["label"].is_out]
            ins = [u for u, _, d in g_.in_edges(ramp, data=True) if not d["label"].is_out]
            extra = max(extra, self.levels.kids_room(outs, self._end_z(start), turning=False))
            extra_b = max(extra_b, self.levels.kids_room(ins, self._end_z(end), turning=False))
        w = self.windows
        bound = None
        if st.length_margin is not None and start is not None and end is not None \
                and not self.moves.same_road(ramp):
            bound = (1.0 + st.length_margin) * self.need_m(turn, feat, start, end)
        a = w.rail(ramp, feat, start, True, loop, width, extra, bound, level) if start else None
        b = w.rail(ramp, feat, end, False, loop, width, extra_b, bound, level) if end else None
        crest = plan.get(ramp)
        return RampSpec(ramp, a, b, free, float(turn), pieces, width, float(feat.radius_m),
                        float(feat.slope_pct), crest, self._leads(start, end, crest, free, feat),
                        inf_floor_m=float(st.inf_min_radius_m))

    def need_m(self, turn: float, feat: RampFeatures, start, end) -> float:
        """What a ramp between two attached ends needs beyond the room it keeps from the
        crossing (which holds a flyover's climb): its turn at its target radius (an
        ``inf`` target: at ``inf_reference_m``) or the climb between its ends at its
        slope, whichever is longer, and a taper (``gap_m``) at each end."""
        st = self.st
        r = feat.radius_m if np.isfinite(feat.radius_m) else st.fit.inf_reference_m
        g = max(feat.slope_pct, 0.5) / 100.0
        climb = float(climb_distance(self._end_z(end) - self._end_z(start), g,
                                     st.fit.transition_m))
        return max(abs(turn) * r, climb) + 2.0 * st.gap_m

    def _leads(self, start, end, crest, free, feat: RampFeatures) -> tuple:
        """Longest straight leads of a ramp that climbs: each attached end may run
        straight along its parent's heading for as long as it takes to climb from
        that end to the ramp's top at its slope (at least ``lead_min_m``), so that
        a flyover can gain height beside its road before it turns over what it
        crosses. Level ramps get none (their geometry is as without leads)."""
        st = self.st
        if not st.leads:
            return (None, None)
        g = max(feat.slope_pct, 0.5) / 100.0
        za = self._end_z(start) if start else None
        zb = self._end_z(end) if end else None
        top = max(z for z in (crest, za, zb, free.z if free else None) if z is not None)
        climbs = [float(climb_distance(top - z, g, st.fit.transition_m)) if z is not None
                  else 0.0 for z in (za, zb)]
        if max(climbs) <= 0:
            return (None, None)
        return tuple(max(st.lead_min_m, c) for c in climbs)

    def _goal_z(self, ramp: str, forward: bool) -> float:
        g = self.g
        if forward:
            kids = [v for _, v, d in g.out_edges(ramp, data=True) if d["label"].is_out]
        else:
            kids = [u for u, _, d in g.in_edges(ramp, data=True) if not d["label"].is_out]
        zs = [self.roads[r].z for r in (road_of(self.topo, k, forward) for k in kids) if r]
        return float(np.mean(zs)) if zs else 0.0

    def _nominal_heading(self, ramp: str, end, is_start: bool) -> float:
        node, label = end
        if node in self.roads:
            return self.roads[node].heading
        st = self.fitted.stations[node]
        p_start, p_end = ends(self.topo, node)
        pos = self.g.edges[(node, ramp) if is_start else (ramp, node)].get("pos")
        if is_start:
            s = st["s"][-1] if p_end is None else (0.4 if pos is None else pos) * st["s"][-1]
        else:
            s = 0.0 if p_start is None else (0.6 if pos is None else pos) * st["s"][-1]
        return float(np.interp(s, st["s"], st["heading"]))

    def _end_z(self, end) -> float:
        node, _ = end
        if node in self.roads:
            return self.roads[node].z
        st = self.fitted.stations[node]
        return float(np.mean(st["z"]))  # refined per candidate by the rail
