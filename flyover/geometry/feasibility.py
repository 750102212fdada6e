"""What the geometry stage knows up front about features no ramp of a kind can have.

Issue 5 asks the geometry stage to report *systematic* infeasibility, so that
sampling excludes it instead of asking for it again in every feature set. One
case is known from the topology alone, before anything is fitted:

**Level ramps.** A ramp whose start and end both attach to the same road (a
collector-distributor road, e.g. ``cA1`` of the catalog's ``cloverleaf_cd``,
which leaves a carriageway and rejoins it) is kept at that road's level by the
layout (:mod:`flyover.geometry.layout`): both ends at one height, nothing to
climb over. So is a collector road's second stub, which goes on at the height of
the first under (over) the road its loop goes to (Columbus I-70 / I-270's ``r13``;
:meth:`flyover.geometry.levels.LevelPlan.continues_level`; no catalog design has one). No sampled maximum slope (1..5 % in the paper's profile) can be
met on it, so the slope of such a ramp is not a parameter of the covering
array: it is *fixed* at 0 in every feature set (:func:`fixed_features`, used
as ``fixed=`` of :func:`flyover.sampling.sample.sample_topology`).

A slope target of **0** means *a level ramp*: its maximum longitudinal slope
is 0, with the same tolerance as any other target (0.2 percentage points;
:attr:`flyover.geometry.fit.RampFit.slope_ok` compares
``|achieved - 0| <= 0.2``). The fit (:func:`flyover.geometry.fit.fit_ramp`)
treats a target of 0 as "the ends must be at one height", which a same-road
ramp always satisfies; a level ramp that had to be lifted over something
would miss it and be reported as usual.

Examples
--------
>>> from flyover.topology.catalog import catalog_topologies
>>> sorted(level_ramps(catalog_topologies()["cloverleaf_cd"]))
['cA1', 'cA2', 'cB1', 'cB2']
>>> level_ramps(catalog_topologies()["j1"])
frozenset()
>>> fixed_features(catalog_topologies()["cloverleaf_cd"])[("cA1", Feature.SLOPE_PCT)]
0.0

**Ramps that must turn.** A ramp between two roads whose headings differ
(a right turn, a left turn, a loop), or between two ramps whose chains connect
such roads (a stack's right turn between two stubs), turns by that much
whatever the sample. A radius target of ``inf`` means "no curve to match: the
gentlest curve the ends allow"; on such a ramp that curve is a 140–250 m arc
and the feature row would promise a straight ramp that is not built. So ``inf``
is *forbidden* on every turning ramp (:func:`forbidden_features`, used as
``extra=`` of :func:`flyover.sampling.sample.sample_topology`): the covering
array covers only radii that are built. Stubs (one free end), collector-
distributor roads and straight-on ramps keep ``inf``.

**Ramps that would be too long.** A ramp between two roads turns by its movement
at its radius and climbs from its start to its crest (a flyover's planned level,
:mod:`flyover.geometry.levels`, else the higher end) and down to its end at its
slope; what it needs is the longer of the two and a taper at each end
(:func:`ramp_need_m`). A (radius, slope) whose need exceeds ``max_ramp_length_m``
(1.5 km, about the longest real ramp of ../shared/osm) would be built only as a
ramp longer than any real one: it is forbidden on that ramp too.

>>> sorted(turning_ramps(catalog_topologies()["j1"]))
['r1', 'r2', 'r3', 'r4']
>>> sorted(turning_ramps(catalog_topologies()["turbine"]))[:3]
['lA1', 'lA2', 'lB1']

**Outer connectors round their loops.** A cloverleaf's or parclo's outer connector and
the loop that joins the same two roads the other way round, on the road they share or
with their chains through stubs (Columbus's ``r11`` round ``r6``) or collector-distributor
roads (``cloverleaf_cd``'s ``oA1`` round ``lB1``:
:meth:`flyover.geometry.chains.Movements.is_outer_connector`, the rule the layout
keeps them apart by), lie in one quadrant, the connector outside: real ones are two
nearly concentric curves, the connector's the wider. A connector sampled tighter than
its loop can go round it only by an S-bend or a corner that no real one has, and the
fit often takes it over or under the loop instead (a bridge the design does not have).
So the connector's radius must exceed its loop's by the room between their centre
lines (:attr:`RoundLoop.margin_m`: the connector's width, half the loop's and 1 m, as
the layout keeps them apart, :meth:`flyover.geometry.loop_room.LoopRoom.round_loop`); every
(connector radius, loop radius) that does not is forbidden (:func:`round_loops`;
``inf`` counts as ``inf_reference_m``, the radius it is built with). The pairs are
read from the topology and the road layout, not from a design's name, so an OSM
cloverleaf gets them too.

>>> [(p.connector, p.loop) for p in round_loops(catalog_topologies()["cloverstack"])]
[('oA1', 'lB1'), ('oA2', 'lB2')]
>>> round_loops(catalog_topologies()["cloverstack"])[0].allows(60.0, 40.0)
True
>>> round_loops(catalog_topologies()["cloverstack"])[0].allows(60.0, 60.0)
False
>>> [(p.connector, p.loop) for p in round_loops(catalog_topologies()["cloverleaf_cd"])][:2]
[('oA1', 'lB1'), ('oA2', 'lB2')]

**Shifts their room holds.** A level ramp whose both windows the road layout fixes before
any fit (:func:`fixed_window_ramps`: a ramp straight on from one expressway to the next
that continues it, DC's ``r3`` / ``r4``, attached by the one's end and within ``gap_m / 2``
beyond ``gap_m`` from the other's start; no catalog design has one) shifts sideways
between them, within a run the layout fixes. An S-shift of lateral offset ``d`` with two
arcs of radius ``R`` takes a run of ``2 R sin(θ)`` with ``d = 2 R (1 - cos θ)``: no radius
above ``(L² + d²) / (4 d)`` fits in a run ``L``, and a ramp drawn one goes round a loop
or misses it. So every radius whose shortest path between the windows (at 0.95 × it, as
:meth:`flyover.geometry.specs.RampSpecs.least_m` bounds the fit) exceeds the length the
ramp may attach within, ``(1 + length_margin)`` × what it needs
(:meth:`flyover.geometry.specs.RampSpecs.need_m`), is forbidden on it, and ``inf`` where it
must shift (it cannot be straight). The shift follows from the lanes of the road it
leaves or joins (the next expressway runs in its partner's median, beside its lanes), so
a rule names the (radius, lanes) it cannot build (:func:`shift_rooms`). None where no
radius is excluded.

>>> shift_rooms(catalog_topologies()["j1"])
()
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from flyover.geometry.chains import Movements, continuations, wrap
from flyover.geometry.chains import ends as _ends
from flyover.geometry.levels import LevelPlan
from flyover.geometry.profile import climb_distance
from flyover.geometry.roads import layout_roads
from flyover.geometry.settings import LayoutSettings, RampFeatures
from flyover.geometry.state import LayoutState
from flyover.geometry.straight import SHIFT_M, TURNING_RAD
from flyover.sampling.model import (
    ElementCondition, Feature, FeatureModel, ForbidRule, Profile, Relation, default_profile,
    feature_model,
)
from flyover.topology.model import Kind, Label, Topology

__all__ = ["LEVEL_SLOPE_PCT", "TURNING_RAD", "level_ramps", "straight_connectors",
           "fixed_features", "turning_ramps",
           "RoundLoop", "round_loops", "forbidden_features", "ramp_need_m",
           "SHIFT_M", "fixed_window_ramps", "ShiftRoom", "shift_rooms", "sampling_model"]

#: the slope target of a level ramp (percent)
LEVEL_SLOPE_PCT = 0.0



def _movements(topology: Topology, settings: LayoutSettings | None = None) -> Movements:
    """The ramps' kinds on the road layout of :mod:`flyover.geometry.roads` with no lanes
    or slopes (it does not depend on the sample): what every rule here reads."""
    st = settings or LayoutSettings()
    return Movements(topology, layout_roads(topology, {}, st))


def level_ramps(topology: Topology, moves: Movements | None = None) -> frozenset[str]:
    """The ramps the layout necessarily keeps level: both ends on one road, a ramp
    between two expressways that continue one another (on one line, one level:
    :func:`flyover.geometry.chains.continuations`), a collector road's second stub (:meth:`flyover.geometry.levels.LevelPlan.continues_level`,
    on the road layout of :mod:`flyover.geometry.roads`, which does not depend on the
    sample), and a right turn (leaves and joins on the right) by at most 90° between two
    roads on one level without a planned crest (two expressways that end here: DC's
    ``r14``), which stays in the corner of its legs and is fitted at that level.

    Parameters
    ----------
    topology
        The interchange topology.
    moves
        Its ramps' kinds (:func:`_movements`), if already at hand.

    Returns
    -------
    frozenset of str
        Ramp ids whose start (``Out-*``) and end (``In-*``) attach to the same
        road, e.g. collector-distributor roads, ramps straight on from one expressway
        to the next, split stubs that go on level, and right turns between two roads
        on one level.
    """
    g = topology.graph
    out = set()
    stubs = []
    for ramp in topology.ramps:
        start, end = _ends(topology, ramp)
        if start and end is None and g.nodes[start[0]]["kind"] is Kind.RAMP:
            stubs.append(ramp)
        if start and end and start[0] == end[0] and g.nodes[start[0]]["kind"] is Kind.ROAD:
            out.add(ramp)
    # a ramp from an expressway to one it continues runs along their line, on their level
    out |= {ramp for c in continuations(topology) for ramp in c.ramps}
    st = LayoutSettings()
    moves = moves or _movements(topology, st)
    roads = moves.roads
    plan = LevelPlan(moves, {}, st)
    # a collector road's second stub goes on level
    out |= {ramp for ramp in stubs if plan.continues_level(ramp)}
    # a right turn (leaving and joining on the right) by at most 90° between two roads on
    # one level (two expressways ending here: DC's r14) stays in the corner of its two legs,
    # crosses nothing and is fitted at that level; one turning farther goes round a leg
    # and over the reverse movement's ramp (DC's r5, 135°, over r14)
    for ramp in topology.ramps:
        start, end = _ends(topology, ramp)
        if start and end and start[0] in roads and end[0] in roads \
                and start[1].side == end[1].side == "right" \
                and -math.pi / 2 - 1e-9 <= (moves.movement(ramp) or 0.0) < 0.0 \
                and roads[start[0]].z == roads[end[0]].z and ramp not in plan.crests:
            out.add(ramp)
    return frozenset(out)


def straight_connectors(topology: Topology, moves: Movements | None = None) -> frozenset[str]:
    """The ramps between two ramps that run straight on: both ends on ramps (no stub, no
    collector-distributor road, no loop) and the roads their chain connects differ in
    heading by less than :data:`TURNING_RAD` (Columbus I-70 / I-270's ``r12``, from the
    collector road ``r13``'s end beside I-270 North into ``r11``, which joins I-270 North:
    real, a 570 m ramp with a 1,066 m radius). No catalog design has one. ``moves``: its
    ramps' kinds (:func:`_movements`), if already at hand."""
    g = topology.graph
    moves = moves or _movements(topology)
    out = set()
    for ramp in topology.ramps:
        start, end = _ends(topology, ramp)
        if start is None or end is None or moves.is_loop(ramp) \
                or g.nodes[start[0]]["kind"] is not Kind.RAMP \
                or g.nodes[end[0]]["kind"] is not Kind.RAMP:
            continue
        turn = moves.movement(ramp)
        if turn is not None and abs(turn) < TURNING_RAD:
            out.add(ramp)
    return frozenset(out)


def fixed_features(topology: Topology) -> dict[tuple[str, Feature], float]:
    """The feature values geometry imposes on ``topology`` whatever the sample.

    Returns
    -------
    dict
        ``(element, feature) → value``: slope 0 for every level ramp
        (:func:`level_ramps`) and radius ``inf`` for every ramp that runs straight on
        between two ramps (:func:`straight_connectors`: it has no turn to hold a radius
        on, and a finite target could be met only by a bend no real one has; Columbus's
        ``r12`` missed 30 m as 22–27 m on 2 of 8 drawn sets). Sampling writes these
        values into every feature row instead of covering them.
    """
    moves = _movements(topology)  # the roads laid out once for both rules
    out = {(r, Feature.SLOPE_PCT): LEVEL_SLOPE_PCT
           for r in sorted(level_ramps(topology, moves))}
    out.update({(r, Feature.RADIUS_M): math.inf
                for r in sorted(straight_connectors(topology, moves))})
    return out


def turning_ramps(topology: Topology) -> frozenset[str]:
    """The ramps that must turn: both ends attached, not a collector-distributor road,
    and the roads their chain connects (:meth:`flyover.geometry.chains.Movements.movement`,
    on the road layout of :mod:`flyover.geometry.roads`, which does not depend on the
    sample) differ in heading by at least :data:`TURNING_RAD`, or a loop."""
    roads = layout_roads(topology, {}, LayoutSettings())
    moves = Movements(topology, roads)
    out = set()
    for ramp in topology.ramps:
        if moves.is_stub(ramp) or moves.same_road(ramp):
            continue
        turn = moves.movement(ramp)
        if moves.is_loop(ramp) or (turn is not None and abs(turn) >= TURNING_RAD):
            out.add(ramp)
    return frozenset(out)


@dataclass(frozen=True)
class RoundLoop:
    """An outer connector and the loop it goes round (:func:`round_loops`).

    Attributes
    ----------
    connector, loop
        Ramp ids.
    margin_m
        How much wider than the loop's radius the connector's must be: the room between
        their centre lines (the connector's width, half the loop's, 1 m).
    inf_reference_m
        The radius a target of ``inf`` is built with.
    """

    connector: str
    loop: str
    margin_m: float
    inf_reference_m: float = 250.0

    def allows(self, connector_radius_m: float, loop_radius_m: float) -> bool:
        """Whether a connector of this radius target can go round a loop of that one."""
        def built(r: float) -> float:
            return r if math.isfinite(r) else self.inf_reference_m

        return built(connector_radius_m) >= built(loop_radius_m) + self.margin_m


def round_loops(topology: Topology, settings: LayoutSettings | None = None
                ) -> tuple[RoundLoop, ...]:
    """Every outer connector of ``topology`` and the loop it goes round: the loop joining
    the same two roads the other way round, on a road they share or through stubs
    (:meth:`flyover.geometry.chains.Movements.is_outer_connector`, on the road layout of
    :mod:`flyover.geometry.roads`, which does not depend on the sample), a loop joining a
    collector road included (Columbus's ``r2`` round ``r5``: the real ``r2`` turns right
    round the outside of ``r5``; with ``r2`` sampled wider, the workflow's Columbus sets
    lost their one same-level conflict); in ramp id order."""
    st = settings or LayoutSettings()
    roads = layout_roads(topology, {}, st)
    moves = Movements(topology, roads)
    out = []
    for ramp in topology.ramps:
        for loop in topology.ramps:
            if moves.is_outer_connector(ramp, loop, collectors=True):
                out.append(RoundLoop(ramp, loop, moves.round_gap(ramp, loop, st.ramp_lane_width_m),
                                     st.fit.inf_reference_m))
    return tuple(out)


def ramp_need_m(topology: Topology, settings: LayoutSettings | None = None
                ) -> dict[str, "Callable[[float, float], float]"]:
    """Ramp → ``need(radius_m, slope_pct)``: the length (m) a ramp between two roads needs
    for a radius and slope target: the longer of its turn (the movement at the radius,
    ``inf_reference_m`` for ``inf``) and its climb (start → crest → end at the slope),
    plus a taper (``gap_m``) at each end. Ramps attached to ramps are not in it (their
    ends' heights follow from their parents' fits)."""
    st = settings or LayoutSettings()
    roads = layout_roads(topology, {}, st)
    moves = Movements(topology, roads)
    crests = LevelPlan(moves, {}, st).crests
    out = {}
    for ramp in topology.ramps:
        start, end = _ends(topology, ramp)
        if start is None or end is None or start[0] not in roads or end[0] not in roads \
                or moves.same_road(ramp):
            continue
        za, zb = roads[start[0]].z, roads[end[0]].z
        top = max(crests.get(ramp, -math.inf), za, zb)
        turn = abs(moves.movement(ramp) or 0.0)
        if moves.is_loop(ramp):
            turn = 2 * math.pi - turn

        def need(radius_m: float, slope_pct: float, up=top - za, down=top - zb,
                 turn=turn) -> float:
            g = max(slope_pct, 0.5) / 100.0
            r = radius_m if math.isfinite(radius_m) else st.fit.inf_reference_m
            climb = float(climb_distance(up, g, st.fit.transition_m)
                          + climb_distance(down, g, st.fit.transition_m))
            return max(turn * r, climb) + 2.0 * st.gap_m

        out[ramp] = need
    return out


def forbidden_features(topology: Topology, profile: Profile | None = None,
                       settings: LayoutSettings | None = None) -> tuple[ForbidRule, ...]:
    """The feature values geometry cannot build on ``topology``: radius ``inf`` on every
    turning ramp (:func:`turning_ramps`), on a ramp between two roads every (radius,
    slope) of ``profile``'s domain whose need (:func:`ramp_need_m`) exceeds
    ``max_ramp_length_m`` (the ``settings``, else the defaults), and every (connector
    radius, loop radius) of an outer connector and its loop (:func:`round_loops`) that
    :meth:`RoundLoop.allows` does not, and every (radius, lanes of the road that sets its
    shift) a level ramp between two fixed windows cannot hold (:func:`shift_rooms`). For
    ``extra=`` of :func:`flyover.sampling.sample.sample_topology`."""
    st = settings or LayoutSettings()
    domain = profile.domain(Kind.RAMP) if profile is not None else {}
    radii = domain.get(Feature.RADIUS_M, (math.inf,))
    rules = []
    if any(math.isinf(v) for v in radii):
        inf = ((Feature.RADIUS_M, frozenset({math.inf})),)
        rules += [ForbidRule((ElementCondition(Kind.RAMP, inf, ramp),))
                  for ramp in sorted(turning_ramps(topology))]
    slopes = domain.get(Feature.SLOPE_PCT, ())
    needs = ramp_need_m(topology, st)
    for ramp in sorted(needs):
        for r in radii:
            long = frozenset(g for g in slopes if needs[ramp](r, g) > st.max_ramp_length_m)
            if long:
                cond = ((Feature.RADIUS_M, frozenset({r})), (Feature.SLOPE_PCT, long))
                rules.append(ForbidRule((ElementCondition(Kind.RAMP, cond, ramp),)))
    for pair in round_loops(topology, st):
        for r in radii:
            tight = frozenset(v for v in radii if not pair.allows(r, v))
            if tight:
                rules.append(ForbidRule(
                    (ElementCondition(Kind.RAMP, ((Feature.RADIUS_M, frozenset({r})),),
                                      pair.connector),
                     ElementCondition(Kind.RAMP, ((Feature.RADIUS_M, tight),), pair.loop)),
                    Relation.ANY))
    if profile is not None:
        for room in shift_rooms(topology, profile, st):
            for lanes, radii_out in room.excluded:
                ramp_cond = ElementCondition(Kind.RAMP, ((Feature.RADIUS_M, radii_out),),
                                             room.ramp)
                if room.road is None:
                    rules.append(ForbidRule((ramp_cond,)))
                else:
                    rules.append(ForbidRule(
                        (ramp_cond, ElementCondition(
                            Kind.ROAD, ((Feature.LANES, frozenset({float(lanes)})),),
                            room.road)), Relation.ANY))
    return tuple(rules)


def fixed_window_ramps(topology: Topology, moves: Movements | None = None) -> frozenset[str]:
    """The ramps both of whose windows the road layout fixes before any fit: both ends on
    roads, each held by the road's end (a ramp straight on to the next expressway,
    :func:`flyover.geometry.chains.continuations`; an ``Out-M`` / ``In-M`` end, or a
    ``pos`` at 0 / 1 on a road that ends there), as
    :meth:`flyover.geometry.rails.RoadWindows.road_rail` places them. Only DC's
    ``r3`` / ``r4`` of the 11 designs and 14 OSM interchanges."""
    g = topology.graph
    moves = moves or _movements(topology)
    roads = moves.roads

    def held(ramp: str, end, is_start: bool) -> bool:
        node, label = end
        r = roads[node]
        pos = g.edges[(node, ramp) if is_start else (ramp, node)].get("pos")
        return ramp in moves.continuing \
            or label in (Label.OUT_M, Label.IN_M) \
            or (pos is not None and pos >= 0.99 and math.isfinite(r.t_hi)) \
            or (pos is not None and pos <= 0.01 and math.isfinite(r.t_lo))

    out = set()
    for ramp in topology.ramps:
        start, end = _ends(topology, ramp)
        if start is not None and end is not None and start[0] in roads and end[0] in roads \
                and held(ramp, start, True) and held(ramp, end, False):
            out.add(ramp)
    return frozenset(out)


@dataclass(frozen=True)
class ShiftRoom:
    """The radii a level ramp between two fixed windows cannot be built with
    (:func:`shift_rooms`).

    Attributes
    ----------
    ramp
        Ramp id.
    road
        The road whose lanes set the shift between its windows (``None``: no sampled
        lanes do).
    excluded
        ``(lanes, radii)``: for each lanes of ``road`` (``None`` without one), the radius
        targets its room cannot hold.
    """

    ramp: str
    road: str | None
    excluded: tuple[tuple[int | None, frozenset[float]], ...]

    def allows(self, radius_m: float, lanes: int | None = None) -> bool:
        """Whether a radius target can be built with ``lanes`` on :attr:`road`."""
        return radius_m not in dict(self.excluded).get(
            None if self.road is None else int(lanes), frozenset())


def _shift_excluded(state: LayoutState, ramp: str, radii: tuple[float, ...]
                    ) -> frozenset[float]:
    """The radii of ``radii`` that ``ramp``'s fixed windows cannot hold on ``state``'s
    layout: a shortest path between them (at 0.95 × the radius,
    :meth:`flyover.geometry.specs.RampSpecs.least_m`) longer than ``(1 + length_margin)``
    × what it needs (``max_ramp_length_m`` without a margin); ``inf`` where it must shift.
    The windows are held by the roads' ends (:func:`fixed_window_ramps`): laid out before
    any target is read, they are the same for every radius, so one spec gives them and
    each radius is tested against them alone."""
    st = state.st
    start, end = _ends(state.topo, ramp)
    radii = tuple(radii)
    if not radii:
        return frozenset()
    spec = state.spec(ramp, RampFeatures(radii[0], LEVEL_SLOPE_PCT))
    out = set()
    for r in radii:
        feat = RampFeatures(r, LEVEL_SLOPE_PCT)
        if math.isinf(r):
            pa, ha, _ = spec.start.at(np.linspace(spec.start.lo, spec.start.hi, 24))
            pb, hb, _ = spec.end.at(np.linspace(spec.end.lo, spec.end.hi, 24))
            d = pb[None, :, :] - pa[:, None, :]
            side = np.abs(np.cos(ha)[:, None] * d[..., 1] - np.sin(ha)[:, None] * d[..., 0])
            turn = np.abs(wrap(hb[None, :] - ha[:, None]))
            if float(side.min()) >= SHIFT_M or float(turn.min()) >= 1e-3:
                out.add(r)
            continue
        need = state.specs.need_m(spec.turn_rad, feat, start, end)
        bound = st.max_ramp_length_m if st.length_margin is None \
            else (1.0 + st.length_margin) * need
        least = 0.0 if state.moves.same_road(ramp) else \
            state.specs.least_m(spec.start, spec.end, None, spec.turn_rad, feat)
        if least > bound:
            out.add(r)
    return frozenset(out)


def shift_rooms(topology: Topology, profile: Profile | None = None,
                settings: LayoutSettings | None = None) -> tuple[ShiftRoom, ...]:
    """Every level ramp with both windows fixed by the layout (:func:`fixed_window_ramps`,
    :func:`level_ramps`) whose room cannot hold some radius of ``profile``'s domain (the
    default profile without one), for each lanes of the road that sets its shift: its
    windows on the layout of :class:`flyover.geometry.state.LayoutState` (nothing
    fitted; the shift does not depend on the slopes, which move both terminals alike),
    each lanes of its two roads tried; a road whose lanes change nothing is not named,
    and where both do, a radius is excluded for one's lanes only if no lanes of the other
    hold it. In ramp id order; ramps with nothing excluded are left out."""
    st = settings or LayoutSettings()
    prof = profile or default_profile()
    radii = tuple(prof.domain(Kind.RAMP).get(Feature.RADIUS_M, ()))
    choices = tuple(int(v) for v in prof.domain(Kind.ROAD).get(Feature.LANES, ())) or (None,)
    moves = _movements(topology, st)
    level = level_ramps(topology, moves)
    out = []
    states: dict[tuple[tuple[str, int], ...], LayoutState] = {}
    for ramp in sorted(fixed_window_ramps(topology, moves) & level):
        (a, _), (b, _) = _ends(topology, ramp)
        ex = {}
        for na in choices:
            for nb in choices:
                lanes = {k: v for k, v in ((a, na), (b, nb)) if v is not None}
                key = tuple(sorted(lanes.items()))
                if key not in states:  # one layout per lanes combination, for every ramp
                    states[key] = LayoutState(topology, lanes, {}, st, 0)
                ex[na, nb] = _shift_excluded(states[key], ramp, radii)
        by_a = {na: frozenset.intersection(*(ex[na, nb] for nb in choices)) for na in choices}
        by_b = {nb: frozenset.intersection(*(ex[na, nb] for na in choices)) for nb in choices}
        if len(set(ex.values())) == 1:
            road, excluded = None, {None: next(iter(ex.values()))}
        elif all(ex[na, nb] == by_a[na] for na in choices for nb in choices):
            road, excluded = a, by_a
        elif all(ex[na, nb] == by_b[nb] for na in choices for nb in choices):
            road, excluded = b, by_b
        else:  # both matter: only what no lanes of the other hold
            road, excluded = a, by_a
        if any(excluded.values()):
            out.append(ShiftRoom(ramp, road, tuple(sorted(
                ((k, v) for k, v in excluded.items() if v), key=lambda kv: kv[0] or 0))))
    return tuple(out)


def sampling_model(topology: Topology, profile: Profile,
                   settings: LayoutSettings | None = None) -> FeatureModel:
    """The feature model sampling covers for ``topology`` under ``profile``: its domains and
    rules, every feature value geometry cannot build (:func:`forbidden_features`, with the
    ``settings``) and the features it fixes (:func:`fixed_features`), as rule
    ``sample_class`` gives them to :func:`flyover.sampling.sample.sample_topology`. The
    geometry stage's resampler (:class:`flyover.geometry.tables.DomainResampler`) draws
    only what it allows."""
    return feature_model(topology, profile, forbidden_features(topology, profile, settings),
                         fixed_features(topology))
