"""The build loop: every ramp of one feature set fitted, refitted, resampled or recorded.

Decides how hard to try and what to keep; reads the layout state
(:mod:`flyover.geometry.state`) and the resampler. Ramps are fitted one by one
(parents first, :meth:`flyover.geometry.state.LayoutState.order`) by
:func:`flyover.geometry.fit.fit_ramp`, avoiding same-level conflicts with roads
and the ramps already fitted:

0. a collector-distributor road is built without a search
   (:mod:`flyover.geometry.collector`); a cloverleaf's outer connector is first
   fitted with its loop as an obstacle at every height, and one more Bézier
   piece to bow out with: it goes round the loop, not over or under it (if it
   cannot meet its targets that way, it is fitted as any other ramp); a loop
   whose outer connector leaves a stub fitted before it is first fitted inside
   the fences that leave that connector room to go round it
   (:meth:`flyover.geometry.loop_room.LoopRoom.fences`; if it cannot meet
   its targets so, as any other ramp); so is each branch of a T's terminal, inside
   the fence that keeps it off its sibling's side until the two are levels apart
   (:func:`flyover.geometry.terminals.terminal_fences`), and a ramp whose child
   attaches on the side facing its road, inside the fence that keeps it a lane off that
   road's edge outside its window (:func:`flyover.geometry.beside.child_room_fences`);
   a direct left turn fitted before other direct left turns whose ends are
   already fixed (a four-level stack's lower level, on stubs) is first fitted at
   its planned level, not lifted, and clear of where those climb from their fixed
   ends (:mod:`flyover.geometry.approaches`; if it cannot meet its targets so, as
   any other ramp);
1. a ramp that still conflicts is lifted to the next level (a flyover);
2. one that misses its targets is fitted again with straight leads (a ramp
   that climbs may first run along its parent's heading, as long as the climb
   from that end takes: up beside its road before it turns over the other
   carriageway), then also with one more Bézier piece, then with one more
   piece but no leads, then with other seeds (``restarts`` fits in all; the last,
   for a ramp between two windows, from the shortest Dubins path between them at
   its radius target, :mod:`flyover.geometry.guess`); a
   ramp attached to a ramp is first held to where its parent is level
   (:func:`flyover.geometry.rails.level_part`; else where its
   parent is no steeper than its slope target) and, if it misses its targets
   there, fitted so again anywhere in its windows where its parent is no steeper;
3. one that still meets fitted ramps at its level makes way (rip-up and
   reroute): each ramp it meets, if nothing is attached to it yet and it is
   not its parent, is fitted again on its own targets with the new ramp's
   curve as an obstacle and kept only if it meets them without conflict;
   then the new ramp is counted again and, if it still conflicts, refitted; if it
   still misses its targets, the order is swapped (:func:`_swapped`): the ramps that
   can move (those it meets; with none met, all) are taken out, the new ramp is fitted
   without them, and those it then meets are fitted again round it (round a loop with
   the loop kept out at every height); all are kept only if all meet their targets;
4. a ramp that misses its targets after all that is resampled (Algorithm 1)
   through ``resampler``; what still misses is recorded with the reason;
5. an interchange in which a ramp still meets something at its level, or an outer
   connector goes over or under its loop (:func:`flyover.geometry.feasibility.round_loops`,
   :func:`flyover.geometry.check.ramp_crossings`), is built again from scratch with other
   seeds (``rebuilds`` times at most; if every build meets something, then with the same
   seeds without fitting a connector round a loop by a collector road first), and the
   build with the fewest conflicting ramps, then the fewest ramps missing their targets
   or across their loop, is kept.

Steps 1–3 of the first build are "the first try" as long as the targets are the sampled ones.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, replace
from typing import Callable, Mapping

import numpy as np

from flyover.geometry.assemble import assemble
from flyover.geometry.beside import (
    beside_run, child_room_fences, joins_straight_on, merge_window, run_slacks,
)
from flyover.geometry.collector import collector_fit
from flyover.geometry.check import ramp_crossings, same_level_conflicts
from flyover.geometry.feasibility import round_loops
from flyover.geometry.fit import (
    RampFit, RampSpec, bounds, conflicts_with, fit_ramp, ranked_starts, recount,
)
from flyover.geometry.guess import DETOUR_PIECES, can_guess, detour_guesses, dubins_guess
from flyover.geometry.model import InterchangeGeometry
from flyover.geometry.profile import climb_distance
from flyover.geometry.settings import GeometryError, LayoutSettings, RampFeatures
from flyover.geometry.state import LayoutState
from flyover.geometry.straight import built_radius
from flyover.geometry.terminals import terminal_fences
from flyover.topology.model import Topology

__all__ = ["RampOutcome", "Interchange", "build_interchange"]

log = logging.getLogger(__name__)

#: how far along its road a parent's run beside the road is moved, in turn, for a child
#: joining it there straight on that misses its targets, in the child's radii (``inf``:
#: ``inf_reference_m``; :func:`_moved_run`)
MOVED_RUN_RADII = (0.5, 1.0)


@dataclass(frozen=True)
class RampOutcome:
    """How one ramp came out: the fit, first-try success and resamples."""

    ramp: str
    fit: RampFit
    first_try_ok: bool
    resamples: int
    infeasible: str
    evaluations: int
    seconds: float
    #: the targets of the feature set (the fit's may be resampled ones)
    first_targets: RampFeatures


@dataclass(frozen=True)
class Interchange:
    """A built interchange: the geometry.json value and per-ramp outcomes."""

    geometry: InterchangeGeometry
    outcomes: tuple[RampOutcome, ...]


def _collector(b: LayoutState, ramp: str, spec: RampSpec) -> RampFit | None:
    """A collector-distributor road without a search (:func:`collector_fit`), long enough
    for its outer connectors to go round their loops
    (:meth:`flyover.geometry.levels.LevelPlan.collector_room`)."""
    kids = [b.features[k].radius_m for k in b.moves.kids(ramp) if k in b.features]
    return collector_fit(spec, kids, b.obstacles(), b.st, b.levels.collector_room(ramp))


def _fit_with_levels(b: LayoutState, spec: RampSpec, seed: int,
                     keep_out: frozenset[str] = frozenset(),
                     fences: tuple = (), approaches: tuple = (),
                     lift: bool = True) -> tuple[RampFit, int, float]:
    """Fit; while the ramp meets something at its level, lift its crest one level.

    The first fits have no leads; a ramp that still misses its targets is fitted
    again (``restarts`` times in all) with its straight leads
    (:meth:`flyover.geometry.specs.RampSpecs._leads`), then also with one more Bézier piece (a turn one
    cubic cannot bend evenly enough for its radius), then with one more piece
    but no leads, then with other seeds, the last of them (a ramp between two windows,
    :func:`can_guess`) started from the Dubins path between its windows
    (:func:`dubins_guess`: as many pieces as the path has arcs and straights; a right turn
    that must run on 2 km beyond its 90° at 40 m is not one cubic); of two that miss,
    :func:`_restart_rank` keeps one. ``keep_out``: fitted ramps it must not cross
    in plan at all, ``fences``: bands it must not enter at any height, ``approaches``:
    where ramps fitted later climb from their fixed ends
    (:meth:`flyover.geometry.fitted.FittedRamps.obstacles`); ``lift`` False: at its
    planned crest throughout."""
    st = b.st
    evals, secs = 0, 0.0
    obst = b.obstacles(keep_out, fences, approaches)
    tried = []
    more = replace(spec, pieces=spec.pieces + 1)
    plain_more = replace(more, lead_m=(None, None))
    restarts = [spec, more, plain_more] if any(spec.leads()) else [more]
    spec = replace(spec, lead_m=(None, None))
    while True:
        fit = fit_ramp(spec, obst, st.fit, seed=seed)
        evals += fit.evaluations
        secs += fit.seconds
        tried.append(fit)
        if fit.conflicts == 0:
            break
        # a level ramp (slope target 0) is never lifted: it would climb a wall
        higher = [z for z in st.levels_m if z > fit.z_crest + 1e-6
                  and spec.target_slope_pct > 0 and lift]
        if not higher or (len(tried) > 1 and fit.conflicts >= tried[-2].conflicts):
            break  # lifting does not help: the conflict is not a crossing
        spec = replace(spec, z_crest=higher[0])
    best = min(tried, key=lambda f: (f.conflicts, not f.ok, not f.slope_ok))
    # same targets, other shapes and seeds; the last, for a ramp between two windows, started
    # from the Dubins path between them (:func:`dubins_guess`)
    restarts += [spec] * st.restarts
    restarts = restarts[:st.restarts]
    guess = bool(restarts) and can_guess(spec)
    for k, again in enumerate(restarts):
        if best.ok or _systematic(best):
            break
        init = None
        if guess and k == len(restarts) - 1 and (
                found := dubins_guess(replace(spec, z_crest=best.spec.z_crest))) is not None:
            again, init = replace(spec, pieces=found.pieces), found.x[None]
        fit = fit_ramp(replace(again, z_crest=best.spec.z_crest), obst, st.fit,
                       seed=seed + 104_729 * (k + 1), init=init)
        evals += fit.evaluations
        secs += fit.seconds
        best = min([best, fit], key=_restart_rank)
    if guess and _slope_short(best, st.fit.transition_m):
        for fit in _detours(spec, best, obst, st, seed + 104_729 * (len(restarts) + 1)):
            evals += fit.evaluations
            secs += fit.seconds
            if fit.ok:
                return fit, evals, secs
    return best, evals, secs


#: random decision vectors a detour search picks its starts from (:func:`_detours`)
DETOUR_DRAWS = 2048
#: starts (population members) a detour search is given
DETOUR_STARTS = 8
#: a detour is no longer than this many times the least its ramp needs (its climb), and
#: its tapers (the spec's own bound, ``max_length_ratio``, if tighter)
DETOUR_LENGTH_RATIO = 2.0


def _slope_short(fit: RampFit, transition_m: float) -> bool:
    """A miss only by its slope: no conflict, too steep, shorter than its climb at its slope
    target needs (the shortest paths between its windows are too short for it)."""
    g = fit.spec.target_slope_pct
    return (not fit.ok and fit.conflicts == 0 and g > 0 and not fit.slope_ok
            and fit.max_slope_pct > g and fit.length_m < _climb_m(fit, transition_m))


def _climb_m(fit: RampFit, transition_m: float) -> float:
    """The run ``fit`` needs to climb from its start to its crest and down to its end at
    its slope target (vertical curves of ``transition_m`` included)."""
    g = fit.spec.target_slope_pct / 100.0
    za, zb = fit.start_pose[3], fit.end_pose[3]
    top = max(fit.z_crest, za, zb)
    return float(climb_distance(top - za, g, transition_m)
                 + climb_distance(top - zb, g, transition_m))


def _detours(spec: RampSpec, best: RampFit, obst, st, seed: int):
    """Searches for a ramp whose fits all missed only by their slope
    (:func:`_slope_short`: every restart started near the shortest path between its
    windows, shorter than its climb needs), each started from detours about as long as its
    climb at its slope target: two Dubins paths through a waypoint
    (:func:`flyover.geometry.guess.detour_guesses`, :data:`DETOUR_PIECES` pieces), then
    random shapes with one more piece (:data:`DETOUR_DRAWS` drawn); of each, the
    :data:`DETOUR_STARTS` long enough with the fewest conflicts and lowest energy
    (:func:`flyover.geometry.fit.ranked_starts`); each no longer than
    :data:`DETOUR_LENGTH_RATIO` times its climb (the search wanders from 1.2-1.7 km starts
    to 2.6-3 km for a 1 % climb of 1,190 m under the 2.5 of ``max_length_ratio``). Yields
    the fits, the first that meets its targets ends it."""
    at = replace(spec, z_crest=best.spec.z_crest,
                 length_ratio=min(spec.length_ratio, DETOUR_LENGTH_RATIO))
    need = _climb_m(best, st.fit.transition_m)
    wide = replace(at, pieces=DETOUR_PIECES)
    rows = ranked_starts(wide, obst, st.fit, detour_guesses(at, need), DETOUR_STARTS)
    if len(rows):
        yield fit_ramp(wide, obst, st.fit, seed=seed, init=rows)
    more = replace(at, pieces=spec.pieces + 1)
    b = np.array(bounds(more), float)
    rng = np.random.default_rng(seed)
    x = b[:, 0] + rng.random((DETOUR_DRAWS, len(b))) * (b[:, 1] - b[:, 0])
    yield fit_ramp(more, obst, st.fit, seed=seed + 1,
                   init=ranked_starts(more, obst, st.fit, x, DETOUR_STARTS))


def _restart_rank(fit: RampFit) -> tuple[bool, int, bool, bool]:
    """Which of two fits of one ramp's restarts is kept (the lower): one meeting its targets,
    else the one with fewer conflicting samples, then within its slope, then within its
    radius (a miss from the Dubins path that grazes what the one before it grazed too, but
    holds its radius, is kept: rip-up and reroute can clear the graze)."""
    return (not fit.ok, fit.conflicts, not fit.slope_ok, not fit.radius_ok)


def build_interchange(topology: Topology, lanes: Mapping[str, int],
                      features: Mapping[str, RampFeatures], *, class_id: str = "",
                      sample: int = 0, seed: int = 0, settings: LayoutSettings | None = None,
                      resampler: Callable[[str, int, Mapping[str, float]], RampFeatures | None]
                      | None = None) -> Interchange:
    """Lay out the roads and fit every ramp of one feature set.

    Parameters
    ----------
    topology
        The interchange topology.
    lanes
        Road id → number of lanes (missing roads get ``default_lanes``).
    features
        Ramp id → :class:`RampFeatures` (targets).
    resampler
        ``(ramp, attempt, radii) → RampFeatures`` drawing new targets for a ramp that
        misses its targets (Algorithm 1; ``radii``: ramp → the radius target in force,
        the feature set's or the one a ramp fitted so far was resampled to);
        ``None`` disables resampling. If it
        also has a method ``clearing(ramp, attempt, radii)`` (as
        :class:`flyover.geometry.tables.DomainResampler`), a ramp that still meets
        something at its level after that is resampled with its draws (the
        steepest slope), up to ``max_resamples`` times more.

    While a ramp still meets something at its level, or an outer connector goes over or
    under its loop, the interchange is built again with seeds derived from ``seed``
    (``settings.rebuilds`` times at most); the build with the fewest conflicting ramps,
    then the fewest ramps missing their targets or across their loop, is returned, with
    first-try success from the first build and the effort of all builds. If every build still
    meets something and an outer connector goes round a loop by a collector road
    (:meth:`flyover.geometry.chains.Movements.round_by_collector`), it is built again
    with the same seeds and that connector fitted before the loop, as any other.

    Raises
    ------
    GeometryError
        When the topology cannot be laid out (naming the element).
    """
    st = settings or LayoutSettings()
    pairs = {frozenset((p.connector, p.loop)) for p in round_loops(topology, st)}
    best = None
    effort: dict[str, tuple[int, float]] = {}
    first: dict[str, bool] = {}
    builds = [(seed if k == 0 else (seed * 2_654_435_761 + 97 * k) % (2**32), True)
              for k in range(st.rebuilds + 1)]
    for k, (ks, quadrant) in enumerate(builds):
        # a ramp meeting something at its level is never kept if it can be helped: the
        # whole interchange is built again with other seeds (every ramp's shape, hence
        # where the later ones find room, changes); so is one whose outer connector goes
        # over or under its loop (a bridge the design does not have, where the seeds put
        # the loop in the connector's way); the build with the fewest conflicts wins, then
        # the fewest ramps not as designed (missing targets, or a connector across its
        # loop); its effort includes the discarded builds'; if every one still meets
        # something, with the same seeds again and an outer connector round a loop by a
        # collector road fitted before the loop (``quadrant`` off,
        # :meth:`flyover.geometry.chains.Movements.round_by_collector`: on drawn Columbus
        # set 17, r12 met r11 in every build with r2 round r5, not in every build without)
        ic = _build_once(topology, lanes, features, class_id, sample, ks, st, resampler,
                         quadrant)
        for o in ic.outcomes:
            e, t = effort.get(o.ramp, (0, 0.0))
            effort[o.ramp] = (e + o.evaluations, t + o.seconds)
            first.setdefault(o.ramp, o.first_try_ok)
        conflicting = (sum(o.fit.conflicts > 0 for o in ic.outcomes),
                       sum(o.fit.conflicts for o in ic.outcomes))
        if conflicting[0] == 0 and (dense := same_level_conflicts(ic.geometry)):
            # the fits' own count is on their samples; the dense check (lane centres every
            # metre, as validation's clearance check) can still find a ramp at a road's or
            # another ramp's level: that build is no better than one the fits saw meet
            conflicting = (len({c.ramp for c in dense}), len(dense))
        across = len({frozenset((c.ramp, c.other))
                      for c in ramp_crossings(ic.geometry, pairs=pairs)}) if pairs else 0
        rank = (*conflicting, sum(not o.fit.ok for o in ic.outcomes) + across)
        log.debug("%s sample %s build %d (seed %d): %d ramps meeting something at their "
                  "level (%d samples), %d missing targets or across their loop", class_id,
                  sample, k, ks, *rank)
        if best is None or rank < best[0]:
            best = (rank, ic)
        if rank[0] == 0 and (not across or not quadrant):
            break
        if k == st.rebuilds and best[0][0] > 0 \
                and _has_collector_round(topology, lanes, features, st, seed):
            builds += [(ks, False) for ks, _ in builds]
    ic = best[1]
    outs = tuple(replace(o, first_try_ok=first[o.ramp], evaluations=effort[o.ramp][0],
                         seconds=effort[o.ramp][1]) for o in ic.outcomes)
    return Interchange(ic.geometry, outs)


def _has_collector_round(topology: Topology, lanes: Mapping[str, int],
                         features: Mapping[str, RampFeatures], st: LayoutSettings,
                         seed: int) -> bool:
    """Whether an outer connector goes round a loop by a collector road here."""
    moves = LayoutState(topology, lanes, features, st, seed).moves
    return any(moves.round_by_collector(c, k) for c in topology.ramps for k in topology.ramps)


def _kept_within(b: LayoutState, spec: RampSpec, seed: int, **within
                 ) -> tuple[RampFit | None, int, float]:
    """A fit of ``spec`` kept out of more than what is built (``within``: the fences or
    approaches of :func:`_fit_with_levels`), counted again against what is built; ``None``
    (with the search's cost) if it misses its targets or meets something so."""
    kept, evals, secs = _fit_with_levels(b, spec, seed, **within)
    if kept.ok and kept.conflicts == 0:
        return recount(kept, b.obstacles(), b.st.fit), evals, secs
    return None, evals, secs


@dataclass
class _Spent:
    """The search effort spent on one ramp, added up fit by fit."""

    evals: int = 0
    secs: float = 0.0

    def __call__(self, result: tuple[RampFit | None, int, float]) -> RampFit | None:
        """The fit of a ``(fit, evaluations, seconds)`` result, its effort counted."""
        fit, evals, secs = result
        self.evals, self.secs = self.evals + evals, self.secs + secs
        return fit

    def fit(self, fit: RampFit) -> RampFit:
        """One search's fit, its effort counted."""
        return self((fit, fit.evaluations, fit.seconds))


def _build_once(topology: Topology, lanes: Mapping[str, int],
                features: Mapping[str, RampFeatures], class_id: str, sample: int, seed: int,
                st: LayoutSettings, resampler, quadrant: bool = True) -> Interchange:
    """One build of :func:`build_interchange` with one seed (``quadrant``: as
    :attr:`flyover.geometry.chains.Movements.quadrant`)."""
    b = LayoutState(topology, lanes, features, st, seed, quadrant)
    outcomes = []
    radii = {r: f.radius_m for r, f in features.items()}  # the targets in force
    for k, ramp in enumerate(b.order()):
        if ramp not in features:
            raise GeometryError("no features for ramp", source=topology.source, element=ramp)
        feat = features[ramp]
        rseed = (seed * 1_000_003 + k * 7919) % (2**32)
        spent = _Spent()
        fit = _first_try(b, ramp, feat, rseed, outcomes, spent)
        first_ok = fit.ok
        fit, attempts = _resampled(b, ramp, fit, rseed, radii, resampler, outcomes, spent)
        met = conflicts_with(fit, b.obstacles(), st.fit) if fit.conflicts else {}
        reason = "" if fit.ok else _reason(fit, met)
        b.record(ramp, fit)
        radii[ramp] = fit.spec.target_radius_m
        outcomes.append(RampOutcome(ramp, fit, first_ok, attempts, reason, spent.evals,
                                    spent.secs, feat))
    return Interchange(assemble(b, class_id, sample, seed, outcomes), tuple(outcomes))


def _first_try(b: LayoutState, ramp: str, feat: RampFeatures, rseed: int,
               outcomes: list[RampOutcome], spent: _Spent, swap: bool = True) -> RampFit:
    """Steps 0–3 of the module's list on the sampled targets: the fit "the first try" is
    counted on (``swap``: with step 3's second half, :func:`_swapped`)."""
    spec = b.spec(ramp, feat)
    built = _collector(b, ramp, spec) if b.moves.same_road(ramp) else None
    fit = built if built is not None and built.ok else None
    if fit is None and (loops := b.windows.loops.round_loops(ramp)):
        fit = _round_fit(b, ramp, spec, loops, rseed, spent)
    run = None if fit is not None else beside_run(b.moves, b.width, b.st, spec, b.fitted)
    wide = spec if fit is not None else merge_window(b.moves, b.width, b.st, spec, b.fitted,
                                                     run)
    fences = () if fit is not None else tuple(b.windows.loops.fences(ramp)) + tuple(
        terminal_fences(b.moves, b.features, b.st, ramp)) + tuple(
        child_room_fences(b.moves, b.width, b.st, wide, b.fitted, run))
    room = () if fit is not None else b.fork_room(spec)
    held = None
    if fit is None and (loops := b.loop_room(ramp)):
        # a connector between two stubs' free ends keeps off where a loop fitted after it
        # leaves its road (:meth:`LayoutState.loop_room`); if it cannot meet its targets
        # so, it is fitted as before, and kept so only if that misses them too and ranks
        # no better (:func:`_restart_rank`): a miss either way, it leaves the loop room
        held = recount(spent(_fit_with_levels(b, wide, rseed, fences=fences + loops,
                                              approaches=room)), b.obstacles(), b.st.fit)
        fit = held if held.ok and held.conflicts == 0 else None
    if fit is None and (fences or room):
        # a loop whose outer connector leaves a fitted stub keeps off where that one
        # must turn round it (:meth:`LoopRoom.fences`), a branch of a T's
        # terminal off its sibling's side (:func:`terminal_fences`), a ramp whose child
        # attaches on its road's side off that road's edge (:func:`child_room_fences`),
        # the first of a stub's children out of its fork (into its join) off the way its
        # sibling needs (:meth:`LayoutState.fork_room`); if it cannot meet its targets
        # so, it is fitted as any other ramp
        fit = spent(_kept_within(b, wide, rseed, fences=fences, approaches=room))
    if fit is None and (ahead := b.approaches(ramp)):
        # a direct left turn keeps off where those fitted after it climb from their
        # fixed ends (:mod:`flyover.geometry.approaches`), at its planned level (lifted,
        # it would be on theirs); if it cannot meet its targets so, it is fitted as any
        # other ramp
        fit = spent(_kept_within(b, spec, rseed, approaches=ahead, lift=False))
    if fit is None:
        fit = spent(_fit_with_levels(b, spec, rseed))
        if not fit.ok and not _systematic(fit):  # held to where its parent is level:
            loose = b.spec(ramp, feat, level=False)  # then anywhere not too steep
            if _windows(loose) != _windows(spec):
                fit2 = spent(_fit_with_levels(b, loose, rseed + 3))
                fit = min([fit, fit2], key=lambda f: (not f.ok, f.conflicts, not f.slope_ok))
    if held is not None and not fit.ok and held.conflicts == 0 \
            and _restart_rank(held) <= _restart_rank(fit):
        fit = held
    if fit.conflicts:  # make way: refit the ramps it meets, then it again
        fit = spent(_reroute(b, ramp, fit, rseed, outcomes))
    if swap and not fit.ok:  # still: fit it first, then the ramps it meets
        fit = _swapped(b, ramp, feat, fit, rseed, outcomes, spent)
    if not fit.ok and not _systematic(fit):
        fit = _moved_run(b, ramp, feat, fit, rseed, outcomes, spent)
    return fit


def _swapped(b: LayoutState, ramp: str, feat: RampFeatures, fit: RampFit, rseed: int,
             outcomes: list[RampOutcome], spent: _Spent) -> RampFit:
    """Step 3's second half: the order swapped. ``ramp`` still meets fitted ramps at its
    level after they made way round its curve (:func:`_reroute`, which refits them round a
    curve bent to avoid them), or it misses its targets with none met (bent or steepened
    to keep off them). The fitted ramps that can move (nothing attached to them yet, not
    its parents), those it meets or, with none met, all of them, are taken out; ``ramp``
    is fitted as on its first try without them (another seed); those its new curve meets
    are fitted again, each as on its own first try on its own targets, round the new
    curve (round a loop first with the loop kept out at every height, as an outer
    connector: :func:`_round_fit`), the others put back. All are kept only if every one
    meets its targets with no conflict; else everything is put back as it was (``fit``
    returned)."""
    if fit.ok or _systematic(fit):
        return fit
    met = conflicts_with(fit, b.obstacles(), b.st.fit) if fit.conflicts else b.fits
    movable = _movable(b, fit, [m for m in b.fits if m in met])  # in fit order
    if not movable:
        return fit
    kept, before = b.fitted.saved(), list(outcomes)
    olds = {m: b.fits[m] for m in movable}
    for m in movable:
        b.unrecord(m)
    mine = _Spent()
    new = _first_try(b, ramp, feat, rseed + 19, outcomes, mine, swap=False)
    refits = {}
    if new.ok and not fit.conflicts:  # back, in their order, all it does not meet
        for m in movable:
            b.record(m, olds[m])
        hit = conflicts_with(new, b.obstacles(), b.st.fit)
        movable = [m for m in movable if m in hit]
        for m in movable:
            b.unrecord(m)
    if new.ok:
        b.record(ramp, new)
        for k, m in enumerate(movable):
            old = olds[m].spec
            targets = RampFeatures(old.target_radius_m, old.target_slope_pct)
            again = _round_fit(b, m, b.spec(m, targets), frozenset({ramp}), rseed + 29 + k,
                               mine) if b.moves.is_loop(ramp) else None
            if again is None:
                again = _first_try(b, m, targets, rseed + 23 + k, outcomes, mine, swap=False)
            if not again.ok:
                break
            b.record(m, again)
            refits[m] = again
        b.unrecord(ramp)
    spent.evals, spent.secs = spent.evals + mine.evals, spent.secs + mine.secs
    if new.ok and len(refits) == len(movable):
        by_ramp = {o.ramp: i for i, o in enumerate(outcomes)}
        for m, again in refits.items():
            o = outcomes[by_ramp[m]]
            outcomes[by_ramp[m]] = replace(o, fit=again, infeasible="")
        return new
    b.fitted.restore(kept)  # as they were, in their order
    outcomes[:] = before
    return fit


def _moved_run(b: LayoutState, ramp: str, feat: RampFeatures, fit: RampFit, rseed: int,
               outcomes: list[RampOutcome], spent: _Spent) -> RampFit:
    """A child joining its parent straight on from a stub's free end
    (:func:`flyover.geometry.beside.joins_straight_on`: Columbus's ``r12`` from ``r13``
    into ``r11``) that misses its targets: the parent, if nothing else is attached to it
    yet, is fitted again with its run beside its road half the child's radius farther
    along, then the whole of it (:data:`MOVED_RUN_RADII`; ``inf``: ``inf_reference_m``;
    :attr:`flyover.geometry.fitted.FittedRamps.run_shift`), each time followed by the
    child; both are kept only if the parent meets its targets with no conflict and the
    child then does too, else the parent is put back as it was (``fit`` returned). On
    drawn Columbus sets 17 and 21 ``r11`` still turned 4° in its run (98 -> 94° on set 17,
    I-270 North at 90°) and ``r13`` ended 3.7° and 12.6° off the road toward it, on set 21
    10 m off its edge: ``r12``, 240-630 m from ``r13``'s end to the run, swung away and
    back to come round to ``r11``'s heading (radius 226-233 m and 57 m for an ``inf``
    target); with ``r11``'s run 125 m (set 17) and 250 m (set 21) farther along, ``r12``
    came round at 904 m and 346 m. On set 14 ``r11`` (60 m) had not kept its run at all
    (``r12`` 52 m); moved 250 m, it kept it and ``r12`` joined at 750 m. On 32 drawn sets
    only those three sets change (``r12``'s only misses there); catalog bytes unchanged."""
    rail = fit.spec.end
    if rail is None or rail.parent not in b.fits or rail.parent in b.fitted.run_shift:
        return fit
    parent = rail.parent
    if not joins_straight_on(b.moves, b.fitted, ramp, b.g.edges[(ramp, parent)]["label"]):
        return fit
    old = b.fits[parent]
    if beside_run(b.moves, b.width, b.st, old.spec, b.fitted) is None \
            or parent in _attached_to(b):
        return fit
    kept = b.fitted.saved()
    radius = built_radius(feat.radius_m, b.st.fit.inf_reference_m)  # the child's
    mine = _Spent()
    for n, times in enumerate(MOVED_RUN_RADII):
        b.fitted.run_shift[parent] = times * radius
        b.unrecord(parent)
        spec = b.spec(parent, RampFeatures(old.spec.target_radius_m, old.spec.target_slope_pct))
        if loops := b.windows.loops.round_loops(parent):
            new = _round_fit(b, parent, spec, loops, rseed + 11 + n, mine)
        else:
            run = beside_run(b.moves, b.width, b.st, spec, b.fitted)
            wide = merge_window(b.moves, b.width, b.st, spec, b.fitted, run)
            new = mine(_kept_within(b, wide, rseed + 11 + n, fences=tuple(child_room_fences(
                b.moves, b.width, b.st, wide, b.fitted, run))))
        if new is not None and new.ok and new.conflicts == 0:
            b.record(parent, new)
            again = spent(_fit_with_levels(b, b.spec(ramp, feat), rseed + 13 + n))
            if again.ok and again.conflicts == 0:
                i = next(i for i, o in enumerate(outcomes) if o.ramp == parent)
                o = outcomes[i]
                outcomes[i] = replace(o, fit=new, evaluations=o.evaluations + mine.evals,
                                      seconds=o.seconds + mine.secs)
                return again
        b.fitted.restore(kept)  # as they were, in their order (its run not shifted)
    spent.evals, spent.secs = spent.evals + mine.evals, spent.secs + mine.secs
    return fit


def _round_fit(b: LayoutState, ramp: str, spec: RampSpec, loops: frozenset[str], rseed: int,
               spent: _Spent) -> RampFit | None:
    """A cloverleaf's outer connector round its loop, not over or under it: fitted with the
    loop as an obstacle at every height and one more Bézier piece to bow out with (without,
    then with its leads, then lifted a level with the restarts of any other ramp); the
    first fit that meets its targets with no conflict, or ``None`` (it is then fitted as
    any other ramp).

    A stub (Columbus's r1 round r6) also keeps out of where its child turns round the loop
    (:meth:`LoopRoom.connector_fences`), and a connector with a child on its road's side
    (Columbus's r11 with r12) off that road's edge before its window
    (:func:`child_room_fences`; over its run beside the road for a child joining it
    straight on, held off the edge all along it in a slot of
    :data:`flyover.geometry.beside.RUN_SLACK_M`, then in one twice as wide, then so
    only over its first ``gap_m``: :func:`flyover.geometry.beside.run_slacks`); if it
    cannot go round within the child's
    room, it goes round without it: a bridge over the loop is worse than a tight child.
    Each try is fitted without and with its leads, then lifted and restarted
    (:func:`_fit_with_levels`); in a run's slots other than the wide one to its end, fitted
    with a third seed instead: on 32 drawn Columbus sets ``r11``'s lifts and restarts there
    (7-8 searches, 1-2.6 s CPU a set) never met the fences, where the wide slot's did on
    4 sets. So is a stub: on the 32 drawn sets ``r1``'s five restarts round ``r6`` (1.9 of
    6.4 million evaluations, about 1 s CPU a set) ran on 31 sets and met its targets on 2
    (3 and 20); ``r1`` there is fitted as any other ramp, first time, as on the other 29."""
    own = tuple(b.windows.loops.connector_fences(ramp))
    # with the child's room, its end window reaches beyond where it runs beside its road
    run = beside_run(b.moves, b.width, b.st, spec, b.fitted)
    wide = merge_window(b.moves, b.width, b.st, spec, b.fitted, run)
    # lifted and restarted only in the wide slot to the run's end, without a run, and
    # without the child's room; a third seed in the other slots and for a stub
    whole = spec.free is None
    edges = [(wide, own + tuple(child_room_fences(b.moves, b.width, b.st, wide, b.fitted,
                                                  run, slack, to_end)),
              whole and (run is None or (to_end and slack > 0)))
             for to_end, slack in run_slacks(run)]
    edges += [(spec, own, whole)] if edges[0][1] != own else []
    for sp, edge, restarts in edges:
        more = replace(sp, pieces=sp.pieces + 1)
        plain = replace(more, lead_m=(None, None))
        for n, again in enumerate((plain, more) if restarts else (plain, more, plain)):
            kept = spent.fit(fit_ramp(again, b.obstacles(loops, edge), b.st.fit, seed=rseed + n))
            if kept.ok and kept.conflicts == 0:
                return kept
        if restarts:
            kept = spent(_fit_with_levels(b, more, rseed + 2, loops, edge))
            if kept.ok and kept.conflicts == 0:
                return kept
    return None


def _resampled(b: LayoutState, ramp: str, fit: RampFit, rseed: int, radii: dict[str, float],
               resampler, outcomes: list[RampOutcome], spent: _Spent) -> tuple[RampFit, int]:
    """Step 4: a ramp that missed its first try, fitted on new targets from ``resampler``
    (the fit with the fewest conflicts kept if none meets them); then, while it still meets
    something at its level, on the resampler's ``clearing`` draws (the steepest slope: a
    crossing is never acceptable). Returns the fit and the number of draws."""
    st = b.st
    attempts, tried = 0, [fit]
    while (not fit.ok and resampler is not None and attempts < st.max_resamples
           and not _systematic(fit)):
        attempts += 1
        new = resampler(ramp, attempts, radii)
        if new is None:
            break
        spec = b.spec(ramp, new)
        # on the new targets too, first off where a loop fitted after it leaves its road
        held = spent(_kept_within(b, spec, rseed + attempts, fences=loops)) if (
            loops := b.loop_room(ramp)) else None
        fit = held or spent(_fit_with_levels(b, spec, rseed + attempts))
        tried.append(fit)
    if not fit.ok:
        fit = min(tried, key=lambda f: (f.conflicts, not f.slope_ok, not f.radius_ok))
    if fit.conflicts and attempts:  # on the last targets too
        fit = spent(_reroute(b, ramp, fit, rseed + attempts, outcomes))
    clearing = getattr(resampler, "clearing", None)
    k = 0
    while fit.conflicts and clearing is not None and k < st.max_resamples:
        k += 1
        new = clearing(ramp, k, radii)
        if new is None:
            break
        fit2 = spent(_fit_with_levels(b, b.spec(ramp, new), rseed + 7 * k + 101))
        if fit2.conflicts:
            fit2 = spent(_reroute(b, ramp, fit2, rseed + 7 * k + 102, outcomes))
        attempts += 1
        fit = min([fit, fit2], key=lambda f: (f.conflicts, not f.ok))
    return fit, attempts


def _reroute(b: LayoutState, ramp: str, fit: RampFit, seed: int,
             outcomes: list[RampOutcome]) -> tuple[RampFit, int, float]:
    """Rip up and reroute: ``ramp`` still meets fitted ramps at its level, so each of
    them (one nothing is attached to yet, and not ``ramp``'s parent) is fitted again
    on its own targets with ``ramp``'s curve as an obstacle; a refit is kept only when
    it meets its targets with no conflict. Then ``ramp`` is measured against the new
    obstacles, and fitted again if it still meets something. Returns ``ramp``'s
    fit and the effort spent."""
    st = b.st
    evals, secs = 0, 0.0
    met = conflicts_with(fit, b.obstacles(), st.fit)
    by_ramp = {o.ramp: i for i, o in enumerate(outcomes)}
    # (a ramp being swapped in, :func:`_swapped`, is fitted but has no outcome yet: it stays)
    movable = [m for m in _movable(b, fit, met) if m in by_ramp]  # in the order met
    if not movable:
        return fit, evals, secs
    for k, other in enumerate(movable):
        old = b.fits[other]
        b.unrecord(other)
        b.record(ramp, fit)  # an obstacle while the other one is refitted
        spec = b.spec(other, RampFeatures(old.spec.target_radius_m, old.spec.target_slope_pct))
        new, e, t = _fit_with_levels(b, spec, seed + 7_368_787 * (k + 1))
        evals, secs = evals + e, secs + t
        b.unrecord(ramp)
        keep = new if (new.ok and new.conflicts == 0) else old
        b.record(other, keep)
        if keep is new:
            o = outcomes[by_ramp[other]]
            outcomes[by_ramp[other]] = replace(o, fit=new, infeasible="",
                                               evaluations=o.evaluations + e,
                                               seconds=o.seconds + t)
    fit = recount(fit, b.obstacles(), st.fit)
    if fit.conflicts:
        again, e, t = _fit_with_levels(b, replace(fit.spec, z_crest=b.plan.get(ramp)), seed + 1)
        evals, secs = evals + e, secs + t
        fit = min([fit, again], key=lambda f: (f.conflicts, not f.ok))
    return fit, evals, secs


def _movable(b: LayoutState, fit: RampFit, names) -> list[str]:
    """Those of ``names`` (in their order) that may be fitted again to make way for the
    ramp of ``fit``: fitted, not its parents, nothing attached to them yet."""
    parents = {r.parent for r in (fit.spec.start, fit.spec.end) if r is not None}
    used = _attached_to(b)
    return [m for m in names if m in b.fits and m not in parents and m not in used]


def _attached_to(b: LayoutState) -> set[str]:
    """The roads and ramps a fitted ramp is attached to."""
    return {r.parent for f in b.fits.values() for r in (f.spec.start, f.spec.end)
            if r is not None}


def _windows(spec: RampSpec) -> tuple:
    """The attachment windows ``lo, hi`` of a spec's attached ends."""
    return tuple((r.lo, r.hi) for r in (spec.start, spec.end) if r is not None)


def _systematic(fit: RampFit) -> bool:
    """A level ramp (ends at one height, nothing to pass over) cannot have any slope:
    resampling cannot help, the feature set is systematically infeasible."""
    za, zb = fit.start_pose[3], fit.end_pose[3]
    level = abs(za - zb) < 1e-6 and fit.z_crest <= max(za, zb) + 1e-6
    return level and fit.radius_ok and fit.conflicts == 0 and not fit.slope_ok


def _reason(fit: RampFit, met: Mapping[str, int] | None = None) -> str:
    parts = []
    sp = fit.spec
    za, zb = fit.start_pose[3], fit.end_pose[3]
    if not fit.slope_ok:
        if abs(za - zb) < 1e-6 and fit.z_crest <= max(za, zb) + 1e-6:
            parts.append(f"slope: level ramp (both ends at z={za:.1f} m) cannot have a "
                         f"{sp.target_slope_pct:g} % slope")
        else:
            parts.append(f"slope: {fit.max_slope_pct:.2f} % instead of {sp.target_slope_pct:g} %")
    if not fit.radius_ok and math.isinf(sp.target_radius_m):
        parts.append(f"radius: {min(fit.min_radius_m, fit.point_radius_m):.1f} m, tighter "
                     f"than 0.95 × the {sp.inf_floor_m:g} m an inf target is built with")
    elif not fit.radius_ok and abs(fit.min_radius_m - sp.target_radius_m) \
            <= 0.05 * sp.target_radius_m:
        parts.append(f"radius: {fit.point_radius_m:.1f} m at a point, tighter than 95 % of "
                     f"{sp.target_radius_m:g} m")
    elif not fit.radius_ok:
        parts.append(f"radius: {fit.min_radius_m:.1f} m instead of {sp.target_radius_m:g} m")
    if not fit.length_ok:
        parts.append(f"length {fit.length_m:,.0f} m over bound {fit.max_length_m:,.0f} m")
    if fit.conflicts:
        with_ = ", ".join(f"{k} ({n})" for k, n in sorted((met or {}).items()))
        parts.append(f"same-level conflict ({fit.conflicts} samples)"
                     + (f" with {with_}" if with_ else ""))
    return "; ".join(parts)
