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
  children need (:meth:`flyover.geometry.levels.LevelPlan.kids_room`). A stub splitting
  off a fitted ramp into a loop to a road ahead ends past that road by the loop's room
  (:meth:`RampSpecs.loop_room`), and a stub splitting off a fitted ramp keeps its free end
  beside the road its chain comes from (Columbus's collector road ``r13``).
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
from flyover.geometry.settings import Z_MARGIN, GeometryError, LayoutSettings, RampFeatures

__all__ = ["RampSpecs", "COLLECTOR_TURN_RAD"]

#: how far (rad) the end of a collector road's first stub may turn from its start's heading
COLLECTOR_TURN_RAD = 0.1


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
            past = None
            if end is None:  # split stub: free end
                z0 = self._end_z(start)
                zf = self.levels.stub_z(ramp, z0, z0 + (self._goal_z(ramp, True) - z0) / 3.0)
                past = self.loop_room(ramp, start)
                zq = self.levels.loop_road_z(ramp)
                if zq is not None and self.levels.continues_level(ramp):
                    # a collector road under (over) it: on at its parent's height there
                    at = self.fitted.stations[start[0]]
                    zf = float(np.interp(self._start_s(ramp, start), at["s"], at["z"]))
                elif zq is not None:  # its chain passes under (over) that road first
                    clear = st.fit.clearance_m + Z_MARGIN
                    zf = min(zf, zq - clear) if zq > z0 else max(zf, zq + clear)
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
            if past is not None:  # beyond the road its loop goes to, by the loop's room
                lo = max(free.forward[0], past)
                free = replace(free, forward=(lo, max(free.forward[1], lo + st.stub_window_m)))
            if any(self.levels.continues_level(k) for k in self.moves.kids(ramp)):
                # the first stub of a collector road: it ends along its road
                free = replace(free, turn=(-COLLECTOR_TURN_RAD, COLLECTOR_TURN_RAD))
            if start is not None and start[0] not in self.roads:  # a split of a split
                free = replace(free, lateral=self._beside_road(ramp, start, free, width))
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

    def loop_room(self, ramp: str, start) -> float | None:
        """How far out (m) a split stub's free end must be when it splits on a fitted ramp
        and one of its children is a loop to a road ahead of it (Columbus I-70/I-270's
        collector road ``r13`` leaves the stub ``r8`` beside I-270 before I-70 and splits
        into the loop ``r6`` to I-70 West beyond it): the loop turns three quarters round on the far side of that road, so
        the split is the road's distance ahead, its half width and the loop's room beyond
        it (its radius, or that of a loop as long as its climb at its slope, as
        :meth:`flyover.geometry.levels.LevelPlan.round_room`; and the stub's and half the
        loop's width). ``None`` otherwise: the stub's end is then placed as before."""
        if start[0] in self.roads:
            return None
        p, h = self._start_pose(ramp, start)
        u = np.array([np.cos(h), np.sin(h)])
        z0 = self._end_z(start)
        out = None
        for kid in self.moves.kids(ramp):
            a, b = ends(self.topo, kid)
            if kid not in self.levels.features or not self.moves.is_loop(kid) or a is None \
                    or a[0] != ramp or b is None or b[0] not in self.roads:
                continue
            q = self.roads[b[0]]
            d = np.array([np.cos(q.heading), np.sin(q.heading)])
            across = float(u[0] * d[1] - u[1] * d[0])
            if abs(across) < 0.5:  # (nearly) along it: not a road it passes
                continue
            rel = np.array(q.origin) - p
            t = float(rel[0] * d[1] - rel[1] * d[0]) / across  # to its centre line
            if t <= 0:
                continue
            r_kid = self.levels.features[kid].radius_m
            r_kid = r_kid if np.isfinite(r_kid) else self.st.fit.inf_reference_m
            g = max(self.levels.features[kid].slope_pct, 0.5) / 100.0
            climb = float(climb_distance(abs(q.z - z0), g, self.st.fit.transition_m))
            r_loop = max(r_kid, climb / (1.5 * np.pi))
            c = (self.moves.lanes(ramp) + self.moves.lanes(kid) / 2) \
                * self.st.ramp_lane_width_m + 1.0
            need = t + q.half_width / abs(across) + r_loop + c
            out = need if out is None else max(out, need)
        return out

    def _beside_road(self, ramp: str, start, free: FreeEnd, width: float) -> tuple:
        """The lateral range of the free end of a stub that splits off a fitted ramp, kept
        beside the road its chain comes from when it runs along it on its right. The range
        is in the frame of where the stub starts (its parent's end, whose heading is the
        parent's fit), so ``3..40`` m to the left of a stub leaving its parent on the left
        can lie across that road (Columbus's ``r13``, leaving ``r8`` toward I-270 North): it
        slides away from the road, at its width, until the free end is clear of the road's
        band by half the stub's width and 1 m anywhere in the forward range."""
        lat = tuple(free.lateral)
        src = road_of(self.topo, ramp, False)
        if not src or src not in self.roads:
            return lat
        q = self.roads[src]
        p, h = self._start_pose(ramp, start)
        delta = h - q.heading
        n = np.array([-np.sin(q.heading), np.cos(q.heading)])
        lat_p = float((p - np.array(q.origin)) @ n)
        edge = -q.lanes * self.st.lane_width_m - 0.5 * width - 1.0  # right of its band
        if np.cos(delta) < 0.5 or lat_p > edge:
            return lat
        worst = max(d * np.sin(delta) for d in free.forward)
        e_max = (edge - lat_p - worst) / np.cos(delta)
        hi = min(lat[1], e_max)
        return (float(min(lat[0], hi - (lat[1] - lat[0]))), float(hi))

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
        s = self._start_s(ramp, end) if is_start else self._end_s(ramp, end)
        return float(np.interp(s, st["s"], st["heading"]))

    def _start_pose(self, ramp: str, start) -> tuple[np.ndarray, float]:
        """Nominal point and heading of ``ramp``'s start on the fitted ramp it leaves."""
        st = self.fitted.stations[start[0]]
        s = self._start_s(ramp, start)
        xy = np.array([np.interp(s, st["s"], st["xy"][:, k]) for k in (0, 1)])
        return xy, float(np.interp(s, st["s"], st["heading"]))

    def _start_s(self, ramp: str, start) -> float:
        """Nominal station of ``ramp``'s start on the fitted ramp it leaves."""
        node = start[0]
        length = self.fitted.stations[node]["s"][-1]
        pos = self.g.edges[(node, ramp)].get("pos")
        return length if ends(self.topo, node)[1] is None else \
            (0.4 if pos is None else pos) * length

    def _end_s(self, ramp: str, end) -> float:
        """Nominal station of ``ramp``'s end on the fitted ramp it joins."""
        node = end[0]
        length = self.fitted.stations[node]["s"][-1]
        pos = self.g.edges[(ramp, node)].get("pos")
        return 0.0 if ends(self.topo, node)[0] is None else \
            (0.6 if pos is None else pos) * length

    def _end_z(self, end) -> float:
        node, _ = end
        if node in self.roads:
            return self.roads[node].z
        st = self.fitted.stations[node]
        return float(np.mean(st["z"]))  # refined per candidate by the rail
