"""Attachment windows (rails): where along its parent a ramp may leave or join it.

Decides, for each end of a ramp, the parent line, the lateral offset and the
window ``lo..hi`` along it (a :class:`flyover.geometry.fit.Rail`); reads the road
layout, the ramps' kinds and ``pos``, the ramps fitted so far (their stations,
widths, fits and attachments), the room round fitted loops
(:mod:`flyover.geometry.loop_room`) and the ramp's targets.

:class:`AttachmentWindows` is what callers use (:meth:`AttachmentWindows.rail`, and
its ``loops``): it hands an end on a road to :class:`RoadWindows` and an end on a
fitted ramp to :class:`RampWindows`.

On a road (:class:`RoadWindows`):

* *Which side of the centre* follows from the movement: right turns and direct
  left turns exit before the crossing and merge after it; loops do the opposite;
  stubs that split exit before, those that merge join after. A ramp keeps
  ``crossing_margin_m`` (and the room ``extra`` its climb or children need) from
  the crossing; a collector-distributor road ``cd_clear_m`` more.
* The order of attachments on one road follows ``pos``: attachments placed
  later keep ``gap_m`` from earlier ones, from the whole length a stub runs
  along the road or a loop reaches along it.
* A cloverleaf's outer connector, which goes round the loop joining the same two
  roads, attaches where it clears every point of the loop turning at its target
  radius to 45° and running straight on
  (:meth:`flyover.geometry.loop_room.LoopRoom.round_loop`); so does one whose chain reaches
  the loop's roads through stubs on a road the loop does not attach to (Columbus's ``r11``
  joining I-270 North round ``r6``). On a collector-distributor
  road a loop attaches near the crossing, as on a road, and its outer connector where
  that rule clears the loop along the carriageway
  (:meth:`flyover.geometry.loop_room.LoopRoom.on_collector`). A ramp joining a road after a loop leaves it, and not coming from the
  road the loop goes to (a trumpet), passes over the loop's exit branch and
  keeps room after it to descend.
* A loop whose outer connector leaves (joins) a stub fitted before it keeps, on the
  road they share, the connector's turn at its radius away from the stub's free end:
  its window there begins beyond it, and a fence at every height keeps its body off
  (:meth:`flyover.geometry.loop_room.LoopRoom.fences`; the build loop drops the fence if the loop cannot
  meet its targets within it).
* A ramp straight on from one expressway to the next that continues it
  (:func:`flyover.geometry.chains.continuations`) attaches within ``gap_m / 2`` beyond
  ``gap_m`` from where its road ends (begins), as short as real ones are; the other
  ramps on that road keep ``gap_m`` beyond that window, fitted first or not
  (:func:`beyond_continuation`). Held by the road's end, it neither orders the others
  by its ``pos`` nor is ordered by theirs (DC's r4, ``pos`` 0.24 on I-66 South, was held
  before r10, 0.46, which leaves it beyond E Street's junction: 1,158 m long for 61 m).
* A ramp between a road and a T that meets the road's line at a junction of its own
  (:func:`flyover.geometry.roads.tee_junctions`) keeps its room from that junction, not
  from the centre (:meth:`RoadWindows.crossing_s`).
* Whatever the fall-backs above give, a window on a road keeps ``gap_m`` from where the
  ramps fitted so far attach to it, on either side (:func:`clear_of_others`): the writer's
  junctions take up to a third of the distance between two attachments.
* A stub attaches within ``stub_window_m`` beyond the room it leaves toward the
  crossing; any other ramp within what it needs (``bound``, from
  :meth:`flyover.geometry.specs.RampSpecs.need_m` and ``length_margin``), so
  that a long detour is never cheaper for the search than a conflict.

On a fitted ramp (:class:`RampWindows`):

* At a stub's free end a child takes over the stub's outer lanes (a fork or join);
  anywhere else along its parent it adds a lane beside it, in the order ``pos`` gives
  the children there, a gap apart (:meth:`RampWindows.in_order`).
* A ramp leaving (joining) a loop does so before (after) the loop turns. A ramp
  attached on the side of a parent that faces a road (J1's r2 joins r3 on the
  left where r3 runs along R4's edge) attaches only where its lane is clear of
  that road. A ramp attached to a ramp does so where its parent is level, if its window
  holds a level part, else where its parent is no steeper than the ramp's slope target:
  it starts (ends) at its parent's grade there (:mod:`flyover.geometry.profile`), so
  that grade counts toward its slope.
* A child joining its parent on the left straight on from a fitted stub's free end
  (:func:`flyover.geometry.beside.joins_straight_on`: Columbus's ``r12`` from ``r13``
  into ``r11``) joins it within the parent's run beside its road
  (:meth:`RampWindows.reach_run`, :meth:`RampWindows.beside_part`), else where the
  parent heads within :data:`STRAIGHT_ON_RAD` of that end (:meth:`RampWindows.straight_on`).
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

from flyover.geometry.beside import beside_run, joins_straight_on
from flyover.geometry.chains import Movements, ends
from flyover.geometry.fit import Rail
from flyover.geometry.fitted import FittedRamps
from flyover.geometry.loop_room import LoopRoom
from flyover.geometry.quadrant import CollectorQuadrant
from flyover.geometry.settings import LayoutSettings, RampFeatures
from flyover.topology.model import Label

__all__ = ["AttachmentWindows", "LEVEL_GRADE", "LEVEL_RUN_M", "RampWindows", "RoadWindows",
           "STRAIGHT_ON_RAD", "beyond_continuation",
           "clear_of_others", "level_part", "room_beside"]

#: the largest grade of a parent ramp (a fraction) at which a child may attach to it
LEVEL_GRADE = 0.003
#: the shortest level part of a parent's window that a child is held to (m)
LEVEL_RUN_M = 5.0
#: a child straight on from a stub's free end joins its parent where the parent heads
#: within this much (rad) of that end (:meth:`RampWindows.straight_on`)
STRAIGHT_ON_RAD = 0.15
#: a child may attach where its parent is this much (a fraction) steeper than the
#: child's slope target: within the target's tolerance (0.2 pp)
GENTLE_MARGIN = 0.001


class AttachmentWindows:
    """The rails of a ramp's ends, given what is fitted so far (see the module doc): on
    a road from :class:`RoadWindows`, on a fitted ramp from :class:`RampWindows`."""

    def __init__(self, moves: Movements, fitted: FittedRamps, st: LayoutSettings,
                 features: Mapping[str, RampFeatures] | None = None):
        self.moves, self.fitted, self.st = moves, fitted, st
        self.roads, self.g, self.topo = moves.roads, moves.g, moves.topo
        self.features = dict(features or {})
        self.loops = LoopRoom(moves, fitted, st, self.features,
                              CollectorQuadrant(moves, fitted, st, self.features))
        self.on_roads = RoadWindows(moves, fitted, st, self.loops)
        self.on_ramps = RampWindows(moves, fitted, st, self.loops)

    def rail(self, ramp: str, feat: RampFeatures, end, is_start: bool, loop: bool,
             width: float, extra: float = 0.0, bound: float | None = None,
             level: bool = True) -> Rail:
        """The rail of one end (``end`` = ``(parent, label)``) of ``ramp``; on a road, no
        farther than ``bound`` beyond the room it keeps from the crossing; on a ramp,
        where that ramp is level if ``level`` and it can, else where it is no steeper than
        ``feat``'s slope target if it can (:func:`level_part`)."""
        node, label = end
        if node in self.roads:
            pos = self.g.edges[(node, ramp) if is_start else (ramp, node)].get("pos")
            return self.on_roads.road_rail(node, ramp, feat, label, is_start, loop, pos,
                                           width, extra, bound)
        return self.on_ramps.ramp_rail(node, ramp, label, is_start, width, level,
                                       feat.slope_pct / 100.0 + GENTLE_MARGIN, feat)


class RoadWindows:
    """The windows on a road: the side of its crossing, the room kept from it, the order
    among the ramps fitted there and the room round a fitted loop (the module doc,
    "On a road"). Reads the road layout, the ramps' kinds and ``pos``, the ramps
    fitted so far (where they attach) and, for a loop's outer connector,
    :class:`flyover.geometry.loop_room.LoopRoom`."""

    def __init__(self, moves: Movements, fitted: FittedRamps, st: LayoutSettings,
                 loops: LoopRoom):
        self.moves, self.fitted, self.st, self.loops = moves, fitted, st, loops
        self.roads, self.topo = moves.roads, moves.topo

    def road_rail(self, road: str, ramp: str, feat: RampFeatures, label: Label,
                  is_start: bool, loop: bool, pos: float | None, width: float,
                  extra: float = 0.0, bound: float | None = None) -> Rail:
        """The rail of ``ramp``'s end on ``road``: at the road's end for a ramp that
        continues it (a main label, or ``pos`` at 0 or 1 on a half line), else
        :meth:`window`; beside the road's lanes on its side (``width`` out on the left)."""
        r = self.roads[road]
        if label is Label.OUT_M or (pos is not None and pos >= 0.99 and np.isfinite(r.t_hi)):
            lo = hi = r.t_hi
        elif label is Label.IN_M or (pos is not None and pos <= 0.01 and np.isfinite(r.t_lo)):
            lo = hi = r.t_lo
        else:
            lo, hi = self.window(road, ramp, feat, is_start, loop, pos, width, extra, bound)
        if hi - lo < 1e-3:
            hi = lo + 1e-3
        return Rail.line(road, label.value, r.origin, r.heading, r.z,
                         self.offset(road, label, width), lo, hi)

    def offset(self, road: str, label: Label, width: float) -> float:
        """The lateral offset of a rail on ``road``: on its line for a main label, beyond
        its lanes on the right, ``width`` out on the left."""
        if label in (Label.OUT_M, Label.IN_M):
            return 0.0
        if label.side == "right":
            return -self.roads[road].lanes * self.st.lane_width_m
        return width

    def room(self, road: str, ramp: str, extra: float) -> float:
        """The room (m) ``ramp`` keeps on ``road`` from the crossing: the other roads'
        half width, ``crossing_margin_m`` and ``extra``; ``cd_clear_m`` more for a
        collector-distributor road."""
        r, st = self.roads[road], self.st
        other = max([x.half_width for x in self.roads.values() if x.expressway != r.expressway]
                    or [0.0])
        tz = other + st.crossing_margin_m + extra
        if self.moves.same_road(ramp):  # collector-distributor: leave room for what attaches to it
            tz += st.cd_clear_m
        return tz

    def window(self, road: str, ramp: str, feat: RampFeatures, is_start: bool, loop: bool,
               pos: float | None, width: float, extra: float, bound: float | None
               ) -> tuple[float, float]:
        """``lo..hi`` (stations on ``road``) of an end off its line: on its side of the
        crossing beyond the room it keeps, within what it needs; by the road's end for a
        continuation, else clear of one; in order among the ramps fitted there
        (:meth:`in_order`, :meth:`round_far_loops`); never beyond the carriageway's ends
        nor within ``gap_m`` of another attachment (:func:`clear_of_others`)."""
        r, st, moves = self.roads[road], self.st, self.moves
        tz = self.room(road, ramp, extra)
        at = self.crossing_s(road, ramp, is_start)
        before = is_start != loop
        reach = max(st.reach_m, tz + st.gap_m)
        if moves.is_stub(ramp):  # a stub attaches just beyond the room it leaves
            if (quad := self.loops.quadrant.reach(ramp)) is not None:
                # and beyond the room a loop and its connector need in the quadrant
                tz = max(tz, quad[4] + 1.5 * st.gap_m)
            reach = tz + st.stub_window_m
        elif bound is not None:  # no farther out than the ramp needs
            reach = max(tz + st.gap_m, min(reach, tz + bound))
        if before and r.t_lo > at - tz:  # the road begins here: everything is after
            before = False
        elif not before and r.t_hi < at + tz:  # it ends here: everything is before
            before = True
        lo, hi = (at - reach, at - tz) if before else (at + tz, at + reach)
        lo, hi = max(lo, r.t_lo + st.gap_m), min(hi, r.t_hi - st.gap_m)
        if lo > hi - 1.0:  # a half line begins (ends) beyond the room: as far again
            lo, hi = (hi - (reach - tz), hi) if before else (lo, lo + reach - tz)
        if ramp in moves.continuing:  # straight on to the next expressway: by its end
            lo, hi = (r.t_hi - 1.5 * st.gap_m, r.t_hi - st.gap_m) if is_start else \
                (r.t_lo + st.gap_m, r.t_lo + 1.5 * st.gap_m)
        else:  # clear of where a ramp straight on attaches by this road's end
            lo, hi = beyond_continuation(moves, st, road, ramp, lo, hi)
        if pos is not None and ramp not in moves.continuing:
            lo, hi = self.in_order(road, ramp, feat, pos, width, lo, hi)
        lo, hi = self.round_far_loops(road, ramp, feat, is_start, width, lo, hi)
        if lo > hi - 1.0:  # no room left between the others: keep the side's order
            lo, hi = (hi - st.stub_window_m, hi) if before else (lo, lo + st.stub_window_m)
        # never beyond the carriageway's ends (a half line's, a T's terminal)
        lo = float(np.clip(lo, r.t_lo + st.gap_m, r.t_hi - st.gap_m))
        hi = float(np.clip(hi, r.t_lo + st.gap_m, r.t_hi - st.gap_m))
        return clear_of_others(self.fitted, st, road, ramp, lo, hi, before)

    def in_order(self, road: str, ramp: str, feat: RampFeatures, pos: float, width: float,
                 lo: float, hi: float) -> tuple[float, float]:
        """``lo..hi`` kept ``gap_m`` after (before) the ramps fitted on ``road`` with a
        lower (higher) ``pos``, beyond a loop's exit branch it passes over, round a loop it
        goes round (:meth:`flyover.geometry.loop_room.LoopRoom.round_loop`); ramps straight
        on to the next expressway are held by the road's end and not ordered."""
        st, moves = self.st, self.moves
        for p, t_min, t_max, other, t_other in self.fitted.attached.get(road, []):
            if other in moves.continuing:
                continue  # held by the road's end, beyond the others: no order
            round_loop = moves.goes_round_loop(ramp, other, road)
            room = self.loops.room_round(ramp, other)
            if p < pos:
                lo = max(lo, t_max + st.gap_m, t_max + room)
                if moves.crosses_loop_exit(ramp, other, road):
                    # it passes over the loop's exit branch, then descends
                    g = max(feat.slope_pct, 0.5) / 100.0
                    lo = max(lo, t_other + st.fit.clearance_m / g
                             + st.fit.transition_m + st.gap_m)
                if round_loop:
                    lo = max(lo, self.loops.round_loop(other, road, width, +1, feat))
            elif p > pos:
                hi = min(hi, t_min - st.gap_m, t_min - room)
                if round_loop:
                    hi = min(hi, self.loops.round_loop(other, road, width, -1, feat))
        return lo, hi

    def round_far_loops(self, road: str, ramp: str, feat: RampFeatures, is_start: bool,
                        width: float, lo: float, hi: float) -> tuple[float, float]:
        """``lo..hi`` for an outer connector of a fitted loop not on ``road`` (its chain
        reaches the loop's roads through stubs: Columbus's r11 onto I-270 North round r6):
        it leaves (joins) ``road`` where it goes round the loop, as on a shared road."""
        for other in sorted(self.loops.round_loops(ramp)):
            if road in {e[0] for e in self.moves.ends(other) if e is not None}:
                continue
            if is_start:
                hi = min(hi, self.loops.round_loop(other, road, width, -1, feat))
            else:
                lo = max(lo, self.loops.round_loop(other, road, width, +1, feat))
        return lo, hi

    def crossing_s(self, road: str, ramp: str, is_start: bool) -> float:
        """The station on ``road`` of the crossing ``ramp``'s end there keeps its room
        from: the centre (0), or the junction of a T meeting the line at one of its own
        (:func:`flyover.geometry.roads.tee_junctions`) for a ramp on that T's roads or
        whose chain runs only to (from) them."""
        r = self.roads[road]
        j = r.junction
        if j is None:
            far = {self.roads[x].junction for x in _far_roads(self.topo, ramp, is_start)
                   if x in self.roads}
            j = far.pop() if len(far) == 1 else None
        if j is None:
            return 0.0
        return float((j[0] - r.origin[0]) * np.cos(r.heading)
                     + (j[1] - r.origin[1]) * np.sin(r.heading))


class RampWindows:
    """The windows on a fitted parent ramp for its children: at a stub's free end, in
    ``pos`` order, before (after) a loop turns, where the child's lane is clear of the
    roads, where the parent is level or gentle, and for a child straight on from a
    stub's free end within the parent's run beside its road (the module doc, "On a
    fitted ramp"). Reads the fitted parent's stations, width, fit and attachments, the ramps'
    kinds and ``pos``, and on a C-D road :class:`flyover.geometry.loop_room.LoopRoom`."""

    def __init__(self, moves: Movements, fitted: FittedRamps, st: LayoutSettings,
                 loops: LoopRoom):
        self.moves, self.fitted, self.st, self.loops = moves, fitted, st, loops
        self.roads, self.g, self.topo = moves.roads, moves.g, moves.topo

    def ramp_rail(self, parent: str, ramp: str, label: Label, is_start: bool,
                  width: float, level: bool = True, gentle: float | None = None,
                  feat: RampFeatures | None = None) -> Rail:
        """The rail of ``ramp``'s end on the fitted ``parent``: at a stub's free end the
        child takes over the stub's outer lanes (a fork or join); anywhere else along a
        ramp it adds a lane beside it, within :meth:`window`."""
        st = self.fitted.stations[parent]
        length = st["s"][-1]
        pw = self.fitted.width[parent]
        p_start, p_end = ends(self.topo, parent)
        at_free_end = (is_start and p_end is None) or (not is_start and p_start is None)
        if label.side == "right":
            off = -(pw - width) if at_free_end else -pw
        else:
            off = 0.0 if at_free_end else width
        if is_start and p_end is None:
            lo = hi = length
        elif not is_start and p_start is None:
            lo = hi = 0.0
        else:
            lo, hi = self.window(parent, ramp, label, is_start, width, off, level, gentle,
                                 feat)
        if hi - lo < 1e-3:
            hi = lo + 1e-3
        return Rail(parent, label.value, st["s"], st["xy"], st["heading"], st["z"], off, lo, hi)

    def window(self, parent: str, ramp: str, label: Label, is_start: bool, width: float,
               off: float, level: bool, gentle: float | None, feat: RampFeatures | None
               ) -> tuple[float, float]:
        """``lo..hi`` (stations on ``parent``) of an end along it: in ``pos`` order
        (:meth:`in_order`), else before (after) a loop turns (:meth:`off_loop`), else
        15-60 % (a diverge) or 40-85 % (a merge, :meth:`reach_run`) of it; then where the
        child's lane is clear of the roads (:func:`room_beside`), where the parent is
        level or no steeper than ``gentle`` (:func:`level_part`), and for a merge straight
        on from a stub's free end, :meth:`straight_on`."""
        st = self.fitted.stations[parent]
        length = st["s"][-1]
        key = (parent, ramp) if is_start else (ramp, parent)
        pos = self.g.edges[key].get("pos")
        if pos is not None:
            lo, hi = self.in_order(parent, ramp, pos, width, feat)
        elif self.moves.is_loop(parent):  # leave a loop before it turns, join it after
            lo, hi = self.off_loop(parent, is_start)
        elif is_start:
            lo, hi = 0.15 * length, 0.6 * length
        else:
            lo, hi = self.reach_run(parent, ramp, label, 0.4 * length, 0.85 * length)
            if feat is not None and self.moves.is_loop(ramp) and self.moves.collects(parent):
                lo, hi = self.loops.quadrant.window(parent, ramp, feat, lo, hi)
        lo, hi = room_beside(self.fitted, self.st.fit.clearance_m, parent, off, width,
                             lo, hi)
        for limit in ((LEVEL_GRADE,) if level else ()) + ((gentle,) if gentle else ()):
            part = level_part(self.fitted, parent, lo, hi, limit)
            if part is not None:
                lo, hi = part
                break
        if not is_start:
            lo, hi = self.straight_on(parent, ramp, label, lo, hi)
        return lo, hi

    def in_order(self, parent: str, ramp: str, pos: float, width: float,
                 feat: RampFeatures | None) -> tuple[float, float]:
        """``lo..hi`` within 0.15 of ``pos`` along ``parent`` (5-95 % of it), a gap apart
        from the children attached to it so far in ``pos`` order; on a C-D road, near
        the crossing for a loop and round it for its outer connector
        (:meth:`flyover.geometry.loop_room.LoopRoom.on_collector`)."""
        length = self.fitted.stations[parent]["s"][-1]
        lo, hi = max(0.05, pos - 0.15) * length, min(0.95, pos + 0.15) * length
        # diverges and merges keep the order ``pos`` gives them on this parent, a
        # gap apart from those already attached (a merge just before a diverge
        # leaves no room for lane changes: movements become unroutable)
        gap = min(self.st.gap_m, 0.05 * length)
        wlo, whi = lo, hi
        for p_other, _, _, _, t_other in self.fitted.attached.get(parent, []):
            if p_other < pos:
                lo = max(lo, t_other + gap)
            elif p_other > pos:
                hi = min(hi, t_other - gap)
        if lo > hi - 1.0:
            lo, hi = wlo, whi
        if feat is not None and self.moves.same_road(parent):
            # on a C-D road a loop keeps near the crossing, and its outer connector
            # goes round it, as on a road
            lo, hi = self.loops.on_collector(parent, ramp, pos, width, feat, lo, hi)
        return lo, hi

    def off_loop(self, parent: str, is_start: bool) -> tuple[float, float]:
        """``lo..hi`` on the fitted loop ``parent``: a child leaves it before it turns
        (0.35 rad off its first heading), joins it after (off its last)."""
        st = self.fitted.stations[parent]
        length = st["s"][-1]
        head = st["heading"]
        if is_start:
            turned = np.abs(head - head[0]) > 0.35
            lo, hi = 0.05 * length, float(st["s"][np.argmax(turned)]) if turned.any() \
                else 0.6 * length
        else:
            turned = np.abs(head - head[-1]) > 0.35
            last = len(head) - 1 - np.argmax(turned[::-1])
            lo = float(st["s"][last]) if turned.any() else 0.4 * length
            hi = 0.95 * length
        return min(lo, hi), max(lo, hi)

    def straight_on(self, parent: str, ramp: str, label: Label, lo: float, hi: float
                    ) -> tuple[float, float]:
        """A child joining ``parent`` on its left straight on from a fitted stub's free end
        (Columbus's ``r12`` from ``r13`` into ``r11``: radius ``inf``) joins it within its
        run beside its road (:meth:`beside_part`, where ``lo..hi``, where it has room and
        is level, reaches into it); else where it heads within :data:`STRAIGHT_ON_RAD` of
        that end: the part of ``lo..hi`` in such a run of stations, else the longest such
        run; ``lo..hi`` unchanged for any other child or when there is none. Until
        GEOMETRY_VERSION 39 the heading alone chose: ``r11`` still turns in its run (6-10°
        off I-270 North on drawn set 2, ``r13`` ending 5° off the other way), so ``r12``
        joined past it, where ``r11`` merges along the road's edge with no room on its
        left."""
        if not joins_straight_on(self.moves, self.fitted, ramp, label):
            return lo, hi
        far = ends(self.topo, ramp)[0]
        st = self.fitted.stations[parent]
        run = self.beside_part(parent)
        if run is not None:  # where the parent runs beside its road for it
            cut = (max(lo, run[0]), min(hi, run[1]))
            if cut[1] - cut[0] >= LEVEL_RUN_M:
                return cut
        h0 = float(self.fitted.stations[far[0]]["heading"][-1])
        s = st["s"]
        near = np.abs((st["heading"] - h0 + np.pi) % (2 * np.pi) - np.pi) <= STRAIGHT_ON_RAD
        near &= (s >= 0.05 * s[-1]) & (s <= 0.95 * s[-1])
        edges = np.flatnonzero(np.diff(np.concatenate([[0], near.astype(int), [0]])))
        runs = [(float(s[a]), float(s[b - 1])) for a, b in zip(edges[::2], edges[1::2])]
        runs = [r for r in runs if r[1] - r[0] >= LEVEL_RUN_M]
        if not runs:
            return lo, hi
        cut = [(max(lo, a), min(hi, b)) for a, b in runs]
        cut = [r for r in cut if r[1] - r[0] >= LEVEL_RUN_M]
        return max(cut or runs, key=lambda r: r[1] - r[0])

    def reach_run(self, parent: str, ramp: str, label: Label, lo: float, hi: float
                  ) -> tuple[float, float]:
        """``lo..hi`` (stations on ``parent``) widened to take in the parent's run beside
        its road (:meth:`beside_part`) for a child joining it straight on
        (:func:`flyover.geometry.beside.joins_straight_on`), within 5-95 % of the parent;
        unchanged for any other child. Columbus's ``r11`` goes round the loop ``r6`` and runs
        beside I-270 North near its end: its run lay beyond 85 % of it (drawn sets 11, 31:
        1,414 m of 1,631 m, 1,639 m of 1,881 m) or straddled it (sets 21, 25: 14-23 m of the
        80 m run left), so ``r12`` joined past the run or had to turn into a few metres of
        it (radius 45-219 m for an ``inf`` target)."""
        if not joins_straight_on(self.moves, self.fitted, ramp, label):
            return lo, hi
        run = self.beside_part(parent)
        if run is None:
            return lo, hi
        length = float(self.fitted.stations[parent]["s"][-1])
        return max(min(lo, run[0]), 0.05 * length), min(max(hi, run[1]), 0.95 * length)

    def beside_part(self, parent: str) -> tuple[float, float] | None:
        """The stations of the fitted ``parent`` level with its run beside its road
        (:func:`flyover.geometry.beside.beside_run`, stations along the road), where it
        is off the road's edge by a child's lane for a child joining it straight on;
        ``None`` when it has no such run or none of it lies there."""
        fit = self.fitted.fits.get(parent)
        if fit is None:
            return None
        run = beside_run(self.moves, self.fitted.width, self.st, fit.spec, self.fitted)
        if run is None:
            return None
        road = self.roads[ends(self.topo, parent)[1][0]]
        st = self.fitted.stations[parent]
        d = np.array([np.cos(road.heading), np.sin(road.heading)])
        t = (st["xy"] - np.array(road.origin)) @ d
        inside = (t >= run[0]) & (t <= run[1])
        if not inside.any():
            return None
        s = st["s"][inside]
        return float(s.min()), float(s.max())


def beyond_continuation(moves: Movements, st: LayoutSettings, road: str, ramp: str,
                        lo: float, hi: float) -> tuple[float, float]:
    """``lo..hi`` on ``road`` kept ``gap_m`` beyond the window of a ramp straight on to
    (from) the next expressway that attaches by the road's start (end) beside it,
    fitted or not: that window is fixed by the road's end
    (:meth:`RoadWindows.road_rail`), so a ramp fitted before it there would leave it
    no room (DC's r14 on I-66 North, fitted before r3, at 40.13 m of it: r3 ended 0.45 m
    from it, too close for the writer's junctions)."""
    r, gap = moves.roads[road], st.gap_m
    for c in sorted(moves.continuing - {ramp}):
        start, end = ends(moves.topo, c)
        if end is not None and end[0] == road and end[1] is not Label.IN_M \
                and np.isfinite(r.t_lo):
            lo = max(lo, r.t_lo + 2.5 * gap)
        if start is not None and start[0] == road and start[1] is not Label.OUT_M \
                and np.isfinite(r.t_hi):
            hi = min(hi, r.t_hi - 2.5 * gap)
    return lo, hi


def _far_roads(topo, ramp: str, forward: bool) -> set[str]:
    """Every road the chains from ``ramp`` lead to (``forward``) or come from: through its
    other end, or a stub's children there."""
    g, out, todo, seen = topo.graph, set(), [ramp], set()
    while todo:
        node = todo.pop()
        if node in seen:
            continue
        seen.add(node)
        if g.nodes[node]["kind"] == "road":
            out.add(node)
            continue
        start, end = ends(topo, node)
        nxt = end if forward else start
        if nxt is not None:
            todo.append(nxt[0])
        elif forward:
            todo += [v for _, v in g.out_edges(node)]
        else:
            todo += [u for u, _ in g.in_edges(node)]
    return out


def clear_of_others(fitted: FittedRamps, st: LayoutSettings, road: str, ramp: str,
                    lo: float, hi: float, before: bool) -> tuple[float, float]:
    """``lo..hi`` on ``road`` without the stretches within ``gap_m`` of where the ramps
    fitted so far attach to it, whatever their side or order: the writer cuts a
    junction of up to a third of the distance to the next attachment on either side
    (:func:`flyover.opendrive.writer._plan_pieces`; under 0.5 m it cannot export), and
    the fall-backs above (no room between the others, a continuation's fixed window)
    may otherwise end on one. Unchanged when it holds no such stretch; else the
    longest free part; else (none is 1 m long) the nearest free stretch beyond the
    window, ``stub_window_m`` long at most, toward the side's order on a tie."""
    r, gap = fitted.roads[road], st.gap_m
    zones = sorted((t - gap, t + gap) for _, _, _, other, t in
                   fitted.attached.get(road, []) if other != ramp)

    def free(a: float, b: float) -> list[tuple[float, float]]:
        out, s = [], a
        for z0, z1 in zones:
            if z1 <= s:
                continue
            if z0 >= b:
                break
            if z0 > s:
                out.append((s, z0))
            s = max(s, z1)
        if s < b:
            out.append((s, b))
        return out

    parts = free(lo, hi)
    if parts == [(lo, hi)]:
        return lo, hi
    parts = [p for p in parts if p[1] - p[0] >= 1.0]
    if parts:
        return max(parts, key=lambda p: p[1] - p[0])
    a_min = max(r.t_lo + gap, -1e5)
    a_max = min(r.t_hi - gap, 1e5)
    best = None
    for a, b in free(a_min, a_max):
        if b - a < 1.0:
            continue
        if b <= lo:
            cand, d = (max(a, b - st.stub_window_m), b), lo - b
        else:
            a = max(a, lo)
            cand, d = (a, min(b, a + st.stub_window_m)), a - hi
        key = (round(max(d, 0.0), 6), (cand[0] >= hi) == before)
        if best is None or key < best[0]:
            best = (key, cand)
    return best[1] if best else (lo, hi)


def level_part(fitted: FittedRamps, parent: str, lo: float, hi: float,
               limit: float = LEVEL_GRADE) -> tuple[float, float] | None:
    """The part of ``lo..hi`` on a fitted parent where its grade is at most ``limit``
    (:data:`LEVEL_GRADE`: where it is level); ``None`` when no such run of stations
    overlaps it.

    A ramp leaving or joining its parent on a grade starts or ends at that grade
    (:mod:`flyover.geometry.profile`; until they did, one leaving its parent on the
    parent's climb started 4 pp flatter than the lane it shared there, J1's r2 leaving
    r1); it reads best where the parent is level, and its own slope target holds only
    where the parent is no steeper. The window becomes the run of such stations that
    overlaps it most; unchanged when it is within the limit throughout (moving the
    window to the nearest level run instead, when none overlaps, cost 50 % more CPU
    on J1 for one jump fewer in 24)."""
    st = fitted.stations[parent]
    s, z = st["s"], st["z"]
    if len(s) < 2:
        return lo, hi
    level = np.abs(np.gradient(z, s)) <= limit
    inside = (s >= lo) & (s <= hi)
    if level[inside].all():
        return lo, hi
    edges = np.flatnonzero(np.diff(np.concatenate([[0], level.astype(int), [0]])))
    runs = [(max(lo, s[a]), min(hi, s[b - 1])) for a, b in zip(edges[::2], edges[1::2])]
    runs = [r for r in runs if r[1] - r[0] >= LEVEL_RUN_M]
    if not runs:
        return None
    a, b = max(runs, key=lambda r: r[1] - r[0])
    return float(a), float(b)

def room_beside(fitted: FittedRamps, clearance: float, parent: str, off: float, width: float,
                lo: float, hi: float) -> tuple[float, float]:
    """The part of ``lo..hi`` on a fitted parent where a child ``width`` wide, beside it
    at ``off``, is clear of the roads at its level.

    A ramp that joins a road runs along its edge for a while (and one that leaves a
    road starts along it): a child on the side facing that road has no room there,
    whatever its shape (J1's r2 joins r3 on the left, between r3 and R4). When some
    stations of ``lo..hi`` lack that room, the window becomes the run of stations
    with room (within 5..95 % of the parent) that overlaps it most, else the longest;
    unchanged when every station has room or none has."""
    st = fitted.stations[parent]
    s, xy, head, z = st["s"], st["xy"], st["heading"], st["z"]
    left = np.stack([-np.sin(head), np.cos(head)], -1)
    clear = np.ones(len(s), bool)
    for k in np.linspace(off - width + 0.5, off + 1.0, 5):  # across the child's lane
        q = xy + k * left
        for x0, y0, dx, dy, t_lo, t_hi, lat_lo, lat_hi, zr in fitted.bands:
            rel = q - (x0, y0)
            along, lat = rel @ (dx, dy), rel @ (-dy, dx)
            clear &= ~((along >= t_lo) & (along <= t_hi) & (lat >= lat_lo) & (lat <= lat_hi)
                       & (np.abs(z - zr) < clearance))
    inside = (s >= lo) & (s <= hi)
    if clear[inside].all() or not clear.any():
        return lo, hi
    length = s[-1]
    ok = clear & (s >= 0.05 * length) & (s <= 0.95 * length)
    edges = np.flatnonzero(np.diff(np.concatenate([[0], ok.astype(int), [0]])))
    runs = [(s[a], s[b - 1]) for a, b in zip(edges[::2], edges[1::2]) if b - 1 > a]
    if not runs:
        return lo, hi
    a, b = max(runs, key=lambda r: (max(0.0, min(hi, r[1]) - max(lo, r[0])), r[1] - r[0]))
    return float(a), float(b)
