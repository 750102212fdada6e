"""Ramp specs: what one ramp is asked to be before it is fitted.

Decides a ramp's turn, number of Bézier pieces, the room its ends keep from the
crossing, its crest, how long it may be and its straight leads (a
:class:`flyover.geometry.fit.RampSpec`); reads the ramp's kind, the level plan, the
attachment windows, the ramps fitted so far and, for a stub, its free end
(:mod:`flyover.geometry.free_end`).

* A ramp attached to other ramps (e.g. a loop on collector-distributor roads)
  turns by the parents' local heading difference, on the branch nearest the
  movement of the roads its chain connects. Direct left turns are splines of
  three pieces (climb along the road, turn, descend along it), loops and
  straight-on ramps of two, other ramps one.
* A stub ramp with no end (it splits into other ramps) or no start (formed by
  merging ramps) gets a free end (:class:`flyover.geometry.free_end.FreeEnds`: its
  height, how far out, beside which road, the room its children need).
* A ramp between two attached ends attaches to a road no farther than (1 +
  ``length_margin``) times what it needs (:meth:`RampSpecs.need_m`) beyond the room it
  keeps (its windows).
* A ramp that climbs may run straight along its parent's heading at either end
  for as long as the climb from that end takes (its leads).
* A ramp is no longer than ``max_length_ratio`` times the least it needs, and its two
  tapers (``gap_m`` each): the least is the longer of what its plan needs
  (:meth:`RampSpecs.least_m`: the shortest path between its windows at 0.95 × its radius,
  its turn at that radius; a stub: as far out as its free end may lie, which is where
  its children need it) and its climb to its crest and down at its slope target, which
  the search counts for each candidate (:meth:`flyover.geometry.fit.RampSpec.max_length_m`).
  A fit over it is not ok: it is resampled or recorded, never stretched.
"""

from __future__ import annotations

import numpy as np

from flyover.geometry.chains import Movements, ends, wrap
from flyover.geometry.dubins import shortest
from flyover.geometry.fit import Rail, RampSpec
from flyover.geometry.fitted import FittedRamps
from flyover.geometry.free_end import FreeEnds
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
        self.free_ends = FreeEnds(moves, levels, fitted, st)

    def spec(self, ramp: str, feat: RampFeatures, level: bool = True) -> RampSpec:
        """The spec of ``ramp`` for targets ``feat``; ``level``: an end on a ramp attaches
        where that ramp is level, if it can (else, and with ``level`` False, where it is no
        steeper than the slope target: :func:`flyover.geometry.rails.level_part`)."""
        start, end = ends(self.topo, ramp)
        width = self.fitted.width[ramp]
        st, plan = self.st, self.levels.crests
        if start is None and end is None:
            raise GeometryError("ramp has neither a start nor an end", source=self.topo.source,
                                element=ramp)
        # headings of the ends (nominal) → raw turn
        h_a = self.fitted.heading_at(ramp, start, True) if start else None
        h_b = self.fitted.heading_at(ramp, end, False) if end else None
        free = None
        if start is None or end is None:
            raw, loop = 0.0, False
            free, stub_extra = self.free_ends.free_end(ramp, start, end, feat, width)
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
                extra, extra_b = (max(st.level_height_m, crest - self.fitted.end_z(e)) / g
                                  + st.fit.transition_m for e in (start, end))
            else:
                extra = extra_b = st.level_height_m / g + st.fit.transition_m
        if free is None:  # room for the planned ramps leaving / joining this one
            g_ = self.g
            outs = [v for _, v, d in g_.out_edges(ramp, data=True) if d["label"].is_out]
            ins = [u for u, _, d in g_.in_edges(ramp, data=True) if not d["label"].is_out]
            z_a, z_b = self.fitted.end_z(start), self.fitted.end_z(end)
            extra = max(extra, self.levels.kids_room(outs, z_a, turning=False))
            extra_b = max(extra_b, self.levels.kids_room(ins, z_b, turning=False))
        w = self.windows
        # an end on a fitted ramp first (its window takes no bound): the climb that bounds
        # how far out the other end may attach to its road is read where it joins
        on_ramp = [w.rail(ramp, feat, e, k == 0, loop, width, x, None, level)
                   if e is not None and e[0] not in self.roads else None
                   for k, (e, x) in enumerate(((start, extra), (end, extra_b)))]
        bound = None
        if st.length_margin is not None and start is not None and end is not None \
                and not self.moves.same_road(ramp):
            bound = (1.0 + st.length_margin) * self.need_m(turn, feat, start, end, on_ramp,
                                                           loop)
        a, b = (r if r is not None else
                w.rail(ramp, feat, e, k == 0, loop, width, x, bound, level) if e else None
                for k, (r, e, x) in enumerate(zip(on_ramp, (start, end), (extra, extra_b))))
        crest = plan.get(ramp)
        cd = self.moves.same_road(ramp)  # a collector-distributor road: no search, no bound
        bounded = st.max_length_ratio is not None and not cd
        return RampSpec(ramp, a, b, free, float(turn), pieces, width, float(feat.radius_m),
                        float(feat.slope_pct), crest, self._leads(start, end, crest, free, feat),
                        inf_floor_m=float(st.fit.inf_reference_m),
                        least_m=0.0 if cd else self.least_m(a, b, free, turn, feat),
                        length_ratio=float(st.max_length_ratio) if bounded else np.inf,
                        tapers_m=2.0 * st.gap_m)

    def least_m(self, a: Rail | None, b: Rail | None, free, turn: float, feat: RampFeatures,
                n: int = 24) -> float:
        """The least a ramp's plan needs (m): the longer of the shortest path of curvature at
        most 1 / (0.95 × its radius target) (``inf``: ``inf_reference_m``) from a point of
        its start window heading along its parent to one of its end window
        (:func:`flyover.geometry.dubins.shortest`, each window sampled at ``n`` stations)
        and its turn at that radius; a stub: the farthest out its free end may lie (where
        :class:`flyover.geometry.free_end.FreeEnds` puts it for its children)."""
        r = 0.95 * (feat.radius_m if np.isfinite(feat.radius_m) else self.st.fit.inf_reference_m)
        arc = abs(turn) * r
        if free is not None:
            return max(arc, float(np.hypot(free.forward[1], max(map(abs, free.lateral)))))
        pa, ha, _ = a.at(np.linspace(a.lo, a.hi, n))
        pb, hb, _ = b.at(np.linspace(b.lo, b.hi, n))
        path = shortest(pa[:, None, :], ha[:, None], pb[None, :, :], hb[None, :], r)
        return max(arc, float(path.min()))

    def need_m(self, turn: float, feat: RampFeatures, start, end,
               rails: tuple | list = (None, None), loop: bool = False) -> float:
        """What a ramp between two attached ends needs beyond the room it keeps from the
        crossing (which holds a flyover's climb): its turn at its target radius (an
        ``inf`` target: at ``inf_reference_m``) or the climb between its ends at its
        slope, whichever is longer, and a taper (``gap_m``) at each end. An end on a
        fitted ramp with its window along it in ``rails`` is at that ramp's height within
        the window nearest the other end's (the least climb), else (none given, or a
        stub's free end) at its mean height
        (Columbus's ``r7`` onto ``r3``'s 19.5 m plateau, from I-70 East at 6.5 m: ``r3``'s
        mean of 13-15 m gave half the climb, and a start window on I-70 East too near
        the crossing for 210-280 m at 2-4 %). A ramp joining (leaving) a fitted ramp
        along it that is neither a loop (``loop``) nor straight-on (a turn under 0.3 rad)
        needs its turn and that climb, one after the other, not the longer: Columbus's
        ``r7`` on set 15 (210 m / 4 %, 2.24 rad: 471 m, 13 m up to ``r3``: 365 m) left
        I-70 East at most 865 m back, every start nearer the crossing met ``r3`` or
        I-70 East, and the one from 857 m back held 195.9 m; 1,412 m back it is first
        try. Loops and straight-on children keep
        the longer (Columbus's loop ``r5`` onto ``r13`` and ``r12`` onto ``r11``'s run
        missed on one set each with both counted)."""
        st = self.st
        r = feat.radius_m if np.isfinite(feat.radius_m) else st.fit.inf_reference_m
        g = max(feat.slope_pct, 0.5) / 100.0
        z = [self.fitted.end_z(start), self.fitted.end_z(end)]
        along = False
        for k, rail in enumerate(rails):
            if rail is not None and rail.hi - rail.lo > 1.0:  # a window along it, not at
                # its free end (one point: where it ends, its mean as before)
                zs = rail.at(np.linspace(rail.lo, rail.hi, 24))[2]
                z[k] = float(zs[np.argmin(np.abs(zs - z[1 - k]))])
                along = True
        climb = float(climb_distance(z[1] - z[0], g, st.fit.transition_m))
        if along and not loop and abs(turn) >= 0.3:  # it turns, then climbs along it
            return abs(turn) * r + climb + 2.0 * st.gap_m
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
        za = self.fitted.end_z(start) if start else None
        zb = self.fitted.end_z(end) if end else None
        top = max(z for z in (crest, za, zb, free.z if free else None) if z is not None)
        climbs = [float(climb_distance(top - z, g, st.fit.transition_m)) if z is not None
                  else 0.0 for z in (za, zb)]
        if max(climbs) <= 0:
            return (None, None)
        return tuple(max(st.lead_min_m, c) for c in climbs)
