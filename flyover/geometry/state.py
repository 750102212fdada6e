"""The state of one interchange while it is built: its parts, wired together.

Decides nothing of its own: it lays out the roads (:mod:`flyover.geometry.roads`),
classifies the ramps (:mod:`flyover.geometry.chains`), fixes the level plan
(:mod:`flyover.geometry.levels`) and connects the attachment windows
(:mod:`flyover.geometry.rails`) and the ramp specs (:mod:`flyover.geometry.specs`)
to the ramps fitted so far (:mod:`flyover.geometry.fitted`). Reads a topology,
its lanes and targets, and the settings. The build loop
(:mod:`flyover.geometry.build`) asks it for specs and obstacles and records fits.
"""

from __future__ import annotations

from typing import Mapping

import numpy as np

from flyover.geometry.approaches import Approach, approaches
from flyover.geometry.chains import Movements, ends
from flyover.geometry.fit import Obstacles, RampFit, RampSpec
from flyover.geometry.fitted import FittedRamps
from flyover.geometry.fork import departure_grade, way_out
from flyover.geometry.levels import LevelPlan
from flyover.geometry.rails import AttachmentWindows
from flyover.geometry.roads import layout_roads
from flyover.geometry.settings import GeometryError, LayoutSettings, RampFeatures
from flyover.geometry.specs import RampSpecs
from flyover.topology.model import Topology

__all__ = ["LayoutState"]


class LayoutState:
    """Roads, ramp kinds, level plan, fitted ramps, windows and specs of one build."""

    def __init__(self, topo: Topology, lanes: Mapping[str, int],
                 features: Mapping[str, RampFeatures], st: LayoutSettings, seed: int,
                 quadrant: bool = True):
        self.topo, self.st, self.seed = topo, st, seed
        self.features = dict(features)
        # a T's terminal is far enough out for its ramps to climb one level there: those
        # to a road on another level and the planned flyovers (the crests follow from
        # the roads' headings, which this room does not change)
        slopes = {r: f.slope_pct for r, f in self.features.items()}
        roads = layout_roads(topo, lanes, st, slopes)
        climbing = frozenset(LevelPlan(Movements(topo, roads), self.features, st).crests)
        self.roads = layout_roads(topo, lanes, st, slopes, climbing)
        self.g = topo.graph
        self.moves = Movements(topo, self.roads)
        self.moves.quadrant = quadrant
        width = {r: self.moves.lanes(r) * st.ramp_lane_width_m for r in topo.ramps}
        self.fitted = FittedRamps(self.moves, width, st)
        self.levels = LevelPlan(self.moves, self.features, st)
        self.windows = AttachmentWindows(self.moves, self.fitted, st, self.features)
        self.specs = RampSpecs(self.moves, self.levels, self.fitted, self.windows, st)

    @property
    def plan(self) -> dict[str, float]:
        """Planned crests: ramp → z (:attr:`LevelPlan.crests`)."""
        return self.levels.crests

    @property
    def fits(self) -> dict[str, RampFit]:
        return self.fitted.fits

    @property
    def width(self) -> Mapping[str, float]:
        return self.fitted.width

    def spec(self, ramp: str, feat: RampFeatures, level: bool = True) -> RampSpec:
        return self.specs.spec(ramp, feat, level)

    def obstacles(self, keep_out: frozenset[str] = frozenset(), fences: tuple = (),
                  approaches: tuple = ()) -> Obstacles:
        return self.fitted.obstacles(keep_out, fences, approaches)

    def approaches(self, ramp: str) -> tuple[Approach, ...]:
        """The approaches (:func:`flyover.geometry.approaches.approaches`) of the planned
        ramps other than ``ramp`` not fitted yet that start and end on fitted ramps (a
        four-level stack's left turns, between two stubs' free ends), when ``ramp`` is a
        planned ramp itself (a direct left turn fitted before them). A left turn with an
        end on a road (a turbine's, a cloverstack's) still chooses where it attaches
        there: none."""
        if ramp not in self.plan:
            return ()
        out = []
        for other in self.topo.ramps:
            if other == ramp or other not in self.plan or other in self.fits \
                    or other not in self.features:
                continue
            if not all(e is not None and e[0] not in self.roads and e[0] in self.fits
                       for e in ends(self.topo, other)):
                continue
            out += approaches(self.spec(other, self.features[other]), self.st.fit.transition_m)
        return tuple(out)

    def fork_room(self, spec: RampSpec) -> tuple[Approach, ...]:
        """The ways (:func:`flyover.geometry.fork.way_out`) of the ramps not fitted yet that
        leave (join) a stub at the free end that the ramp of ``spec`` leaves (joins) too:
        its siblings at a fork (join), which it leaves room for; none for a sibling whose
        other end lies on a ramp not fitted yet (OSM Columbus's ``r11``: its spec needs
        that ramp)."""
        out = []
        for end, rail, at_start in zip(ends(self.topo, spec.id), (spec.start, spec.end),
                                       (True, False)):
            if end is None or end[0] in self.roads or rail is None:
                continue
            stub = end[0]
            if ends(self.topo, stub)[1 if at_start else 0] is not None:
                continue  # not at the stub's free end
            z0 = float(rail.at(np.array([rail.lo]))[2][0])
            grade = departure_grade(spec, z0)
            for sib in self.moves.kids(stub):
                here = ends(self.topo, sib)
                if sib == spec.id or sib in self.fits or sib not in self.features \
                        or here[0 if at_start else 1] is None \
                        or here[0 if at_start else 1][0] != stub:
                    continue
                if any(e is not None and e[0] not in self.roads and e[0] not in self.fits
                       for e in here):
                    continue  # its other end is on a ramp not fitted yet: no spec to go by
                way = way_out(self.spec(sib, self.features[sib]), at_start, grade, self.st)
                if way is not None:
                    out.append(way)
        return tuple(out)

    def loop_room(self, ramp: str) -> tuple[tuple[float, ...], ...]:
        """Where a connector between two stubs' free ends (:meth:`LevelPlan.low_connector`)
        keeps off, at every height, so that a loop fitted after it can leave (join) its
        road near the crossing (Columbus's ``r2``, climbing at 1 % beside I-70 East, met
        the loop ``r5`` where it leaves I-70 East at its height): on the loop's side of
        each road it attaches to, from the start of its window 1.5 × the loop's depth
        along the road, and from the road's edge that depth out: the diameter of a circle
        as long as the loop needs (its least, or its drop at its slope target), no less
        than twice its radius, and its width and 1 m. Empty for any other ramp
        (:attr:`flyover.geometry.fit.Obstacles.lines` rows without their height)."""
        if not self.levels.low_connector(ramp) or self.moves.is_loop(ramp):
            return ()
        out = []
        for loop in self.topo.ramps:
            if not self.moves.is_loop(loop) or loop in self.fits or loop not in self.features:
                continue
            if any(e is not None and e[0] not in self.roads and e[0] not in self.fits
                   for e in ends(self.topo, loop)):
                continue  # its other end is on a ramp not fitted yet: no spec to go by
            spec = self.spec(loop, self.features[loop])
            radius, g = spec.target_radius_m, spec.target_slope_pct / 100.0
            if not np.isfinite(radius) or spec.start is None or spec.end is None:
                continue
            za = float(spec.start.at(np.array([spec.start.lo]))[2][0])
            zb = float(spec.end.at(np.array([spec.end.lo]))[2][0])
            need = max(float(spec.least_m), abs(za - zb) / g if g > 0 else 0.0)
            depth = max(2.0 * radius, need / np.pi) + self.width[loop] + 1.0
            for end, rail in zip(ends(self.topo, loop), (spec.start, spec.end)):
                if end is None or end[0] not in self.roads:
                    continue
                r = self.roads[end[0]]
                edge = r.lanes * self.st.lane_width_m + 0.5
                lat = (-edge - depth, -edge) if end[1].side == "right" else (edge, edge + depth)
                out.append((r.origin[0], r.origin[1], float(np.cos(r.heading)),
                            float(np.sin(r.heading)), rail.lo - radius,
                            min(rail.hi, rail.lo + 1.5 * depth), *lat))
        return tuple(out)

    def record(self, ramp: str, fit: RampFit) -> None:
        self.fitted.record(ramp, fit)

    def unrecord(self, ramp: str) -> None:
        self.fitted.unrecord(ramp)

    def order(self) -> list[str]:
        """The order ramps are fitted in: parents first; in one round, stubs and
        road-to-road ramps in id order, a low connector between two ramps (a stack's
        right turn: no freedom where it attaches) before the flyovers, which then pass
        over it, and a collector road's second stub (:meth:`LevelPlan.continues_level`:
        level, at its parent's height, beside its road) before those: it has neither a
        height nor a side to give way with, and a connector forking off its parent beside
        it has both (Columbus's ``r2`` beside ``r13``). An outer connector
        (:meth:`Movements.goes_round`) comes after the loop it goes round if the loop can
        come first, so that it is fitted round it: on a road they share, their windows
        keep it round the fitted loop (:meth:`flyover.geometry.rails.RoadWindows.in_order`;
        the catalog's loops ``l*`` come before their connectors ``o*`` by id anyway, the
        Bangor cloverleaf's loops ``r5``-``r8`` came after their ``r1``-``r4``, which then
        went over or under them); on none (it reaches the loop's roads through stubs:
        Columbus's ``r11`` round ``r6``, which leaves a stub fitted in ``r11``'s round) so
        does the stub it leaves (joins), whose free end then keeps the room the connector
        needs to go round the fitted loop
        (:meth:`flyover.geometry.loop_room.LoopRoom.fences`: Columbus's ``r1``)."""
        done: set[str] = set()
        out = []
        todo = list(self.topo.ramps)
        on = {r: {e[0] for e in ends(self.topo, r) if e and e[0] in self.roads} for r in todo}
        # on a shared road only where the loop's id comes later (else id order has it first
        # and the other ramps keep their rounds: the catalog's parclos)
        rounds = {r: [k for k in todo if self.moves.goes_round(r, k) and (not on[r] & on[k]
                                                                          or k > r)]
                  for r in todo}
        for r in todo:  # a stub whose child goes round a loop on no road they share so
            if self.moves.is_stub(r):  # waits for that loop too
                rounds[r] = sorted({k for c in self.moves.kids(r) if c in rounds
                                    for k in rounds[c] if not on[c] & on[k]})
        for r in todo:  # a connector round a loop joining a collector road waits for it
            if not self.moves.is_stub(r):  # (Columbus's r2 round r5); its stubs do not
                rounds[r] += [k for k in todo if k not in rounds[r] and not on[r] & on[k]
                              and self.moves.round_by_collector(r, k)]
        while todo:
            ready, waiting = [], []
            for r in todo:
                start, end = ends(self.topo, r)
                deps = [e[0] for e in (start, end) if e and e[0] not in self.roads]
                if all(d in done for d in deps):
                    (ready if all(k in done for k in rounds[r]) else waiting).append(r)
            ready = ready or waiting  # no loop that can come first: as before
            if not ready:
                raise GeometryError("ramps attach to each other in a cycle",
                                    source=self.topo.source, element=", ".join(todo))
            for r in sorted(ready, key=lambda r: (not self.levels.continues_level(r),
                                                  not self.levels.low_connector(r))):
                done.add(r)
                out.append(r)
                todo.remove(r)
        return out
