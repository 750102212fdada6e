"""Free ends: where a stub ramp ends on the side where it has no parent.

Decides the free end of a stub (a ramp with no end, which splits into other ramps, or
no start, which is formed by merging ramps): its height, how far out it lies and how
far to the side, how far it may turn, and the room it keeps from the crossing
(a :class:`flyover.geometry.fit.FreeEnd`). Reads the ramps' kinds
(:class:`flyover.geometry.chains.Movements`), the level plan
(:class:`flyover.geometry.levels.LevelPlan`), the ramps fitted so far
(:class:`flyover.geometry.fitted.FittedRamps`) and the settings. The ramp specs
(:mod:`flyover.geometry.specs`) ask it for a stub's free end.

* A stub climbs a third of the height between its road and its children's roads, so
  every ramp of a chain climbs, over a free end far enough out to reach that height
  at its slope, and keeps the room its children need
  (:meth:`flyover.geometry.levels.LevelPlan.kids_room`).
* A stub splitting off a fitted ramp into a loop to a road ahead ends past that road
  by the loop's room (:meth:`FreeEnds.loop_room`), and a stub splitting off a fitted
  ramp keeps its free end beside the road its chain comes from (:meth:`FreeEnds.beside_road`;
  Columbus's collector road ``r13``).
* The first stub of a collector road (one whose child goes on level) ends along its
  road (:data:`COLLECTOR_TURN_RAD`); a collector road's second stub goes on at its
  parent's height under (over) the road its loop goes to.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from flyover.geometry.chains import Movements, ends, road_of
from flyover.geometry.fit import FreeEnd
from flyover.geometry.fitted import FittedRamps
from flyover.geometry.levels import LevelPlan
from flyover.geometry.profile import climb_distance, loop_radius
from flyover.geometry.settings import Z_MARGIN, LayoutSettings, RampFeatures

__all__ = ["FreeEnds", "COLLECTOR_TURN_RAD"]

#: how far (rad) the end of a collector road's first stub may turn from its start's heading
COLLECTOR_TURN_RAD = 0.1


class FreeEnds:
    """The free end of a stub ramp, given the ramps fitted so far (see the module doc)."""

    def __init__(self, moves: Movements, levels: LevelPlan, fitted: FittedRamps,
                 st: LayoutSettings):
        self.moves, self.levels, self.fitted, self.st = moves, levels, fitted, st
        self.topo, self.roads, self.g = moves.topo, moves.roads, moves.g

    def free_end(self, ramp: str, start, end, feat: RampFeatures,
                 width: float) -> tuple[FreeEnd, float]:
        """The free end of the stub ``ramp`` (one of ``start``, ``end`` is ``None``) for
        targets ``feat``, and the room (m) it keeps from the crossing for its children
        (0 if none)."""
        st, fitted = self.st, self.fitted
        fixed = start or end
        side = fixed[1].side
        sgn = -1.0 if side == "right" else (1.0 if side == "left" else 0.0)
        lat = (sorted((sgn * 3.0, sgn * 40.0)) if sgn else (-10.0, 10.0))
        past = self.loop_room(ramp, start) if end is None else None
        zf = self.free_z(ramp, start, end)
        # the free end is far enough out for the stub to climb to it at its slope
        z_fix = fitted.end_z(start or end)
        g = max(feat.slope_pct, 0.5) / 100.0
        climb = float(climb_distance(zf - z_fix, g, st.fit.transition_m)) + 60.0
        free = FreeEnd((60.0, max(400.0, climb)), lat, (-np.pi / 4, np.pi / 4), zf)
        stub_extra = max(self.levels.kids_room(self.moves.kids(ramp), zf),
                         self.connector_room(ramp, zf))
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
            free = replace(free, lateral=self.beside_road(ramp, start, free, width))
        return free, stub_extra

    def free_z(self, ramp: str, start, end) -> float:
        """The height of the free end of the stub ``ramp`` (one of ``start``, ``end`` is
        ``None``): a third of the way from its fixed end toward its children's roads, or
        the clearance toward its planned children's crest
        (:meth:`flyover.geometry.levels.LevelPlan.stub_z`); under (over) the road a loop
        of its chain goes to, and a collector road's second stub at its parent's height."""
        st, fitted = self.st, self.fitted
        if end is None:  # split stub: free end
            z0 = fitted.end_z(start)
            zf = self.levels.stub_z(ramp, z0, z0 + (self._goal_z(ramp, True) - z0) / 3.0)
            zq = self.levels.loop_road_z(ramp)
            if zq is not None and self.levels.continues_level(ramp):
                # a collector road under (over) it: on at its parent's height there
                at = fitted.stations[start[0]]
                zf = float(np.interp(fitted.start_s(ramp, start), at["s"], at["z"]))
            elif zq is not None:  # its chain passes under (over) that road first
                clear = st.fit.clearance_m + Z_MARGIN
                zf = min(zf, zq - clear) if zq > z0 else max(zf, zq + clear)
            return zf
        z1 = fitted.end_z(end)
        return self.levels.stub_z(ramp, z1, z1 + (self._goal_z(ramp, False) - z1) / 3.0)

    def stub_free_z(self, stub: str) -> float | None:
        """The height of the free end of ``stub``: its fit's, once fitted, else where
        :meth:`free_z` puts it if its fixed end is on a road (that needs no fit); ``None``
        for a ramp that is no stub, or a stub on a ramp not fitted yet."""
        start, end = ends(self.topo, stub)
        if (start is None) == (end is None):
            return None
        fit = self.fitted.fits.get(stub)
        if fit is not None:
            return float(fit.end_pose[3] if end is None else fit.start_pose[3])
        if (start or end)[0] not in self.roads:
            return None
        return float(self.free_z(stub, start, end))

    def connector_room(self, ramp: str, zf: float) -> float:
        """Room (m) the free end of the stub ``ramp`` (at height ``zf``) keeps from the
        crossing for a child that runs from it to another stub's free end without a
        planned crest (:meth:`flyover.geometry.levels.LevelPlan.low_connector`), so that
        the two free ends lie as far apart as that child needs to climb between them at
        its slope target. With room for its turn alone (``turn_room`` times its radius)
        OSM Columbus's ``r2``, from ``r8``'s free end at 0.5 m to ``r14``'s at 12 m, had
        544-549 m between them (its least, 60 and 150 m targets) for 1,190 m of climb at
        1 %: it came out at its least, 2.1-2.2 % steep.

        Each stub keeps half that climb, but a stub with a collector road among its
        children (:meth:`flyover.geometry.levels.LevelPlan.continues_level`) keeps none:
        its free end lies where the collector road needs it, which runs on level from it
        past the road ahead, its loop counted from there (:meth:`loop_room`). With half
        the climb (595 m) Columbus's ``r8`` ended 644 m out instead of 348 m on drawn set
        6, ``r13`` then at the nearest point its loop room allowed, 97 m past I-70, and
        the loop ``r6`` beside I-70 left ``r11`` no room to go round it (``r1``, which
        ``r11`` leaves, kept out of where it turns and ended 4 m off I-70 West, ``r3``
        meeting I-70 from there). 0 if there is none."""
        if self._feeds_collector(ramp):
            return 0.0
        out = 0.0
        for kid, other in self._connector_ends(ramp):
            z = self.stub_free_z(other)
            if z is None:
                continue
            g = max(self.levels.features[kid].slope_pct, 0.5) / 100.0
            climb = float(climb_distance(abs(z - zf), g, self.st.fit.transition_m))
            out = max(out, 0.5 * climb)
        return out

    def _connector_ends(self, ramp: str) -> list[tuple[str, str]]:
        """(child, other stub) for each child of the stub ``ramp`` that runs from its free
        end to another stub's free end without a planned crest
        (:meth:`flyover.geometry.levels.LevelPlan.low_connector`)."""
        out = []
        for kid in self.moves.kids(ramp):
            if kid not in self.levels.features or not self.levels.low_connector(kid):
                continue
            for other, at_start in zip(ends(self.topo, kid), (True, False)):
                if other is None or other[0] == ramp:
                    continue
                o_start, o_end = ends(self.topo, other[0])
                if (o_end if at_start else o_start) is not None:
                    continue  # not at that ramp's free end
                out.append((kid, other[0]))
        return out

    def _feeds_collector(self, stub: str) -> bool:
        """Whether a child of ``stub`` is a collector road (goes on level)."""
        return any(self.levels.continues_level(k) for k in self.moves.kids(stub))

    def loop_room(self, ramp: str, start) -> float | None:
        """How far out (m) a split stub's free end must be when it splits on a fitted ramp
        and one of its children is a loop to a road ahead of it (Columbus I-70/I-270's
        collector road ``r13`` leaves the stub ``r8`` beside I-270 before I-70 and splits
        into the loop ``r6`` to I-70 West beyond it): the loop turns three quarters round
        on the far side of that road, so the split is the road's distance ahead, its half
        width and the loop's room beyond it (its radius, or that of a loop as long as its
        climb at its slope, as :meth:`flyover.geometry.levels.LevelPlan.round_room`; and
        the stub's and half the loop's width). ``None`` otherwise: the stub's end is then
        placed as before."""
        if start[0] in self.roads:
            return None
        p, h = self.fitted.start_pose(ramp, start)
        u = np.array([np.cos(h), np.sin(h)])
        z0 = self.fitted.end_z(start)
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
            r_loop = loop_radius(r_kid, abs(q.z - z0), self.levels.features[kid].slope_pct,
                                 self.st.fit.transition_m)
            c = self.moves.round_gap(ramp, kid, self.st.ramp_lane_width_m)
            need = t + q.half_width / abs(across) + r_loop + c
            out = need if out is None else max(out, need)
        return out

    def beside_road(self, ramp: str, start, free: FreeEnd, width: float) -> tuple:
        """The lateral range of the free end of a stub that splits off a fitted ramp, kept
        beside the road its chain comes from when it runs along it on its right. The range
        is in the frame of where the stub starts (its parent's end, whose heading is the
        parent's fit), so ``3..40`` m to the left of a stub leaving its parent on the left
        can lie across that road (Columbus's ``r13``, leaving ``r8`` toward I-270 North): it
        slides away from the road, at its width, until the free end is clear of the road's
        band by half the stub's width and 1 m anywhere in the forward range. A parent ending
        right of the band but within that margin slides so too (Columbus drawn set 15:
        ``r8`` ended 4.7 m right of I-270 North's band, 0.3 m inside the 5 m margin, heading
        0.1 rad toward it; ``r13``'s free end kept 3..40 m to its left, across I-270, and
        ``r13`` met both carriageways); one ending on or left of the band keeps its range."""
        lat = tuple(free.lateral)
        src = road_of(self.topo, ramp, False)
        if not src or src not in self.roads:
            return lat
        q = self.roads[src]
        p, h = self.fitted.start_pose(ramp, start)
        delta = h - q.heading
        n = np.array([-np.sin(q.heading), np.cos(q.heading)])
        lat_p = float((p - np.array(q.origin)) @ n)
        band = -q.lanes * self.st.lane_width_m  # the right edge of its band
        edge = band - 0.5 * width - 1.0  # clear of it by half the stub's width and 1 m
        if np.cos(delta) < 0.5 or lat_p > band:  # not along it, or not on its right
            return lat
        worst = max(d * np.sin(delta) for d in free.forward)
        e_max = (edge - lat_p - worst) / np.cos(delta)
        hi = min(lat[1], e_max)
        return (float(min(lat[0], hi - (lat[1] - lat[0]))), float(hi))

    def _goal_z(self, ramp: str, forward: bool) -> float:
        """Mean height of the roads the stub's children lead to (come from)."""
        g = self.g
        if forward:
            kids = [v for _, v, d in g.out_edges(ramp, data=True) if d["label"].is_out]
        else:
            kids = [u for u, _, d in g.in_edges(ramp, data=True) if not d["label"].is_out]
        zs = [self.roads[r].z for r in (road_of(self.topo, k, forward) for k in kids) if r]
        return float(np.mean(zs)) if zs else 0.0
