"""Room beside a road for a child: a ramp whose child attaches on the side facing its road.

J1's r3 joins R4 on the right and r2 joins r3 on the left: r2 comes in between r3 and R4.
Fitted on its own, r3 turns early and runs along R4's edge to its merge, so nowhere
between leaving R2 and that run is there room beside it at its level for r2
(:func:`flyover.geometry.rails.room_beside` then found only a few
metres of r3's start, low beside R2: r2 had to cross R1/R2 and drop into it, and met
them or missed its radius). Mirrored, r1 leaves R1 on the right and r2 leaves r1 on the
left. :func:`child_room_fences` keeps such a ramp a child's lane (and 1 m) off its road's
edge everywhere beyond (before) its window on that road, so that it merges (diverges)
within its window and not by running along the road first: the child then finds room
beside it where it is at that road's level. The fence is a band at every height
(:attr:`flyover.geometry.fit.Obstacles.lines` rows without their height); the build loop
drops it when the ramp cannot meet its targets within it, as the loop fences of
:mod:`flyover.geometry.loop_room`. A stub's children fork at its free end, not beside
it: stubs get none.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Mapping

import numpy as np

from flyover.geometry.chains import Movements, ends
from flyover.geometry.fit import Rail, RampSpec
from flyover.geometry.roads import RoadLine
from flyover.geometry.settings import LayoutSettings
from flyover.geometry.straight import built_radius
from flyover.topology.model import Label

if TYPE_CHECKING:
    from flyover.geometry.fitted import FittedRamps

__all__ = ["RUN_SLACK_M", "beside_run", "child_room_fences", "joins_straight_on",
           "merge_window", "run_slacks"]


@dataclass(frozen=True)
class _Side:
    """Where a ramp meets its road, with children attached on the side facing that road."""

    road: RoadLine
    edge: float  #: the road's right edge, metres right of its reference line (+ 0.5 m)
    rail: Rail  #: the ramp's window on the road
    leaving: bool  #: the ramp leaves the road (else joins it)
    kids: tuple[str, ...]


def child_room_fences(moves: Movements, width: Mapping[str, float], st: LayoutSettings,
                      spec: RampSpec, fitted: FittedRamps | None = None,
                      run: tuple[float, float] | None = None,
                      slack: float = 0.0, to_end: bool = False) -> list[tuple[float, ...]]:
    """Fences (road-frame bands ``x0, y0, dx, dy, t_lo, t_hi, lat_lo, lat_hi``) keeping the
    ramp of ``spec`` off the strip along its road's right edge, as wide as itself and its
    widest child attached on its left and 1 m, beyond its start window (leaving the road
    on the right, children leaving it on the left) or before its end window (joining on
    the right, children joining it on the left). Empty for any other ramp and for stubs.

    A child whose other end is the free end of a stub already fitted (``fitted``, the
    :class:`flyover.geometry.fitted.FittedRamps`: Columbus's ``r12`` from the collector
    road ``r13``'s end, beside I-270 North, into ``r11``) starts (ends) there, away from
    the edge: the strip then reaches out to that end (its lane and 1 m beyond it), from
    its station to the window (``r11``, fitted round the loop ``r6``, passed just beyond
    ``r13``'s end and left ``r12`` no way north but a tight turn into it). ``run``: the
    ramp's run beside its road for such a child (:func:`beside_run`, as
    :func:`merge_window` took it; with ``fitted`` only); ``slack``: the room (m) across
    that run beyond its own width and :data:`RUN_SLACK_M`, ``to_end``: off the edge to
    the run's end, not only over its first ``gap_m`` (:func:`run_slacks`)."""
    ramp, g = spec.id, moves.g
    if moves.is_stub(ramp):
        return []
    out = []
    for end, rail, leaving in zip(ends(moves.topo, ramp), (spec.start, spec.end), (True, False)):
        if end is None or end[0] not in moves.roads or rail is None:
            continue
        if end[1] is not (Label.OUT_R if leaving else Label.IN_R):
            continue
        if leaving:
            kids = [v for _, v, d in g.out_edges(ramp, data=True) if d["label"] is Label.OUT_L]
        else:
            kids = [u for u, _, d in g.in_edges(ramp, data=True) if d["label"] is Label.IN_L]
        if not kids:
            continue
        road = moves.roads[end[0]]
        side = _Side(road, road.lanes * st.lane_width_m + 0.5, rail, leaving, tuple(kids))
        strip = max(width[k] for k in kids) + 1.0  # the fit widens it by the ramp's half width
        along = (rail.hi, 1e4) if leaving else (-1e4, rail.lo)
        beside = None if fitted is None or leaving else run
        if beside is not None:  # off the edge until the child has joined it (a taper)
            along = (-1e4, beside[1] if to_end else beside[0] + st.gap_m)
        frame = (road.origin[0], road.origin[1], math.cos(road.heading), math.sin(road.heading))
        out.append((*frame, *along, -side.edge - strip, -side.edge))
        if beside is not None:  # and no farther off than its own width and a lane
            out.append((*frame, *beside, -1e4,
                        -side.edge - strip - spec.width_m - RUN_SLACK_M - slack))
        if fitted is not None:
            out += _free_end_room(moves, width, fitted, side)
    return out


#: the room (m) a ramp running beside its road for a child (:func:`beside_run`) has
#: across, beyond its own width: it runs within a lane's width of straight
RUN_SLACK_M = 4.0


def run_slacks(run: tuple[float, float] | None) -> tuple[tuple[bool, float], ...]:
    """How a ramp with a run beside its road (:func:`beside_run`) tries to keep it, in
    turn (:func:`child_room_fences`' ``to_end`` and ``slack``): off the road's edge over
    the whole run, within a slot :data:`RUN_SLACK_M` across (it runs straight there),
    then within one twice as wide; then off the edge over the run's first ``gap_m``
    only, in the narrow slot, then in the wide one. Columbus's ``r11`` (100-280 m) kept to the run's band
    but still turned over the part not held off the edge (97.4 -> 94.0° on drawn set
    16, the road at 90°), and ``r12`` straight on from ``r13``'s end got 25-44 m of it
    and met ``r11`` (sets 5, 16, 29, 31). ``r11`` at 60 m, round ``r6`` and in from
    40-55° off I-270 North, grazed the 4 m slot in 1-5 samples on every try (sets 8, 14,
    18, 21) and was fitted without the child's room, merging before its run. ``((False,
    0.0),)`` without a run."""
    if run is None:
        return ((False, 0.0),)
    return ((True, 0.0), (True, RUN_SLACK_M), (False, 0.0), (False, RUN_SLACK_M))


def joins_straight_on(moves: Movements, fitted: FittedRamps, kid: str, label: Label) -> bool:
    """Whether ``kid``, attached to its parent by ``label``, joins it on its left straight
    on from a fitted stub's free end (Columbus's ``r12`` from ``r13`` into ``r11``)."""
    far = ends(moves.topo, kid)[0]
    return label is Label.IN_L and far is not None and far[0] in fitted.stations \
        and moves.is_stub(far[0]) and ends(moves.topo, far[0])[1] is None


def _straight_kids(moves: Movements, fitted: FittedRamps, ramp: str) -> list[str]:
    """The children joining ``ramp`` on its left that come from a fitted stub's free end
    (:func:`joins_straight_on`): they run straight on."""
    return [k for k, _, d in moves.g.in_edges(ramp, data=True)
            if joins_straight_on(moves, fitted, k, d["label"])]


def beside_run(moves: Movements, width: Mapping[str, float], st: LayoutSettings,
               spec: RampSpec, fitted: FittedRamps) -> tuple[float, float] | None:
    """Where (stations along its road) a ramp joining its road on the right runs beside
    it, its child's lane and 1 m off its edge, before it merges, so that a child joining
    it on the left straight on from a fitted stub's free end joins it there straight
    (Columbus's ``r11``, which merges into I-270 North, and ``r12`` from the collector road
    ``r13``'s end: real, ``r11`` runs 750 m beside I-270 North, ``r12`` joins it 200 m
    in). It begins its radius target beyond its window's start (the window leaves room
    to come in at 45°: :meth:`flyover.geometry.loop_room.LoopRoom.round_loop`; ``r11``
    fitted into a run beginning ``r sin 45°`` beyond it was still turning there) and runs
    ``2 × gap_m`` (the child's taper and the ramp's own); farther along by the ramp's
    :attr:`flyover.geometry.fitted.FittedRamps.run_shift` once moved for a child that
    missed its targets there (``build._moved_run``); ``None`` for any other ramp."""
    ends_ = ends(moves.topo, spec.id)
    if spec.end is None or ends_[1] is None or ends_[1][1] is not Label.IN_R \
            or ends_[1][0] not in moves.roads or not _straight_kids(moves, fitted, spec.id):
        return None
    lo = spec.end.lo + built_radius(spec.target_radius_m, st.fit.inf_reference_m) \
        + fitted.run_shift.get(spec.id, 0.0)
    return lo, lo + 2.0 * st.gap_m


def merge_window(moves: Movements, width: Mapping[str, float], st: LayoutSettings,
                 spec: RampSpec, fitted: FittedRamps,
                 run: tuple[float, float] | None) -> RampSpec:
    """``spec`` with its end window reaching far enough beyond its run beside its road
    (:func:`beside_run`) to merge after it: a reverse curve across the child's lane, 1 m
    and :data:`RUN_SLACK_M` at its radius target, and two tapers (``gap_m``), and coming
    down (up) to its road's height first (:attr:`flyover.geometry.fit.RampSpec.end_z_first`):
    the child joins it in that run from a stub's free end at about that height (Columbus's
    ``r12`` from ``r13``'s end at 0.5 m; ``r11`` kept ``r1``'s 7 m until just before its
    end); unchanged for any other ramp (``run``: :func:`beside_run` of ``spec``)."""
    if run is None:
        return spec
    road = moves.roads[ends(moves.topo, spec.id)[1][0]]
    r = built_radius(spec.target_radius_m, st.fit.inf_reference_m)
    shift = max(width[k] for k in _straight_kids(moves, fitted, spec.id)) + 1.0
    hi = run[1] + 2.0 * math.sqrt(r * (shift + RUN_SLACK_M)) + 2.0 * st.gap_m
    hi = min(max(spec.end.hi, hi), road.t_hi - st.gap_m)
    return replace(spec, end=replace(spec.end, hi=float(hi)), end_z_first=True)


def _free_end_room(moves: Movements, width: Mapping[str, float], fitted: FittedRamps,
                   side: _Side) -> list[tuple[float, ...]]:
    """The wider strips of :func:`child_room_fences` out to the children's far ends at a
    fitted stub's free end."""
    out = []
    road, edge, leaving = side.road, side.edge, side.leaving
    d = np.array([math.cos(road.heading), math.sin(road.heading)])
    n = np.array([-d[1], d[0]])
    for k in side.kids:
        far = ends(moves.topo, k)[1 if leaving else 0]
        if far is None or far[0] not in fitted.stations or not moves.is_stub(far[0]):
            continue
        p_start, p_end = ends(moves.topo, far[0])
        if (p_start if leaving else p_end) is not None:
            continue  # not where the stub is free
        xy = fitted.stations[far[0]]["xy"][0 if leaving else -1] - np.array(road.origin)
        t, out_m = float(xy @ d), float(-(xy @ n)) - edge
        if out_m <= 0.0:
            continue
        along = (side.rail.hi, t) if leaving else (t, side.rail.lo)
        if along[1] - along[0] < 1.0:
            continue
        out.append((road.origin[0], road.origin[1], d[0], d[1], *along,
                    -edge - out_m - 0.5 * width[k] - 1.0, -edge))
    return out
