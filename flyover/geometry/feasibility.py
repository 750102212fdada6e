"""What the geometry stage knows up front about features no ramp of a kind can have.

Issue 5 asks the geometry stage to report *systematic* infeasibility, so that
sampling excludes it instead of asking for it again in every feature set. One
case is known from the topology alone, before anything is fitted:

**Level ramps.** A ramp whose start and end both attach to the same road (a
collector-distributor road, e.g. ``cA1`` of the catalog's ``cloverleaf_cd``,
which leaves a carriageway and rejoins it) is kept at that road's level by the
layout (:mod:`flyover.geometry.layout`): both ends at one height, nothing to
climb over. No sampled maximum slope (1..5 % in the paper's profile) can be
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

>>> sorted(turning_ramps(catalog_topologies()["j1"]))
['r1', 'r2', 'r3', 'r4']
>>> sorted(turning_ramps(catalog_topologies()["turbine"]))[:3]
['lA1', 'lA2', 'lB1']
"""

from __future__ import annotations

import math

from flyover.geometry.chains import Movements
from flyover.geometry.chains import ends as _ends
from flyover.geometry.roads import layout_roads
from flyover.geometry.settings import LayoutSettings
from flyover.sampling.model import ElementCondition, Feature, ForbidRule, Profile
from flyover.topology.model import Kind, Topology

__all__ = ["LEVEL_SLOPE_PCT", "TURNING_RAD", "level_ramps", "fixed_features", "turning_ramps",
           "forbidden_features"]

#: the slope target of a level ramp (percent)
LEVEL_SLOPE_PCT = 0.0

#: a ramp whose chain connects roads at least this far apart in heading (rad) must turn
TURNING_RAD = 0.5


def level_ramps(topology: Topology) -> frozenset[str]:
    """The ramps the layout necessarily keeps level: both ends on one road.

    Parameters
    ----------
    topology
        The interchange topology.

    Returns
    -------
    frozenset of str
        Ramp ids whose start (``Out-*``) and end (``In-*``) attach to the same
        road, e.g. collector-distributor roads.
    """
    g = topology.graph
    out = set()
    for ramp in topology.ramps:
        start, end = _ends(topology, ramp)
        if start and end and start[0] == end[0] and g.nodes[start[0]]["kind"] is Kind.ROAD:
            out.add(ramp)
    return frozenset(out)


def fixed_features(topology: Topology) -> dict[tuple[str, Feature], float]:
    """The feature values geometry imposes on ``topology`` whatever the sample.

    Returns
    -------
    dict
        ``(element, feature) → value``: slope 0 for every level ramp
        (:func:`level_ramps`). Sampling writes these values into every
        feature row instead of covering them.
    """
    return {(r, Feature.SLOPE_PCT): LEVEL_SLOPE_PCT for r in sorted(level_ramps(topology))}


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


def forbidden_features(topology: Topology, profile: Profile | None = None
                       ) -> tuple[ForbidRule, ...]:
    """The feature values geometry cannot build on ``topology``: radius ``inf`` on every
    turning ramp (:func:`turning_ramps`). For ``extra=`` of
    :func:`flyover.sampling.sample.sample_topology`; with a ``profile`` whose radius
    domain has no ``inf``, none."""
    if profile is not None and not any(math.isinf(v) for v in
                                       profile.domain(Kind.RAMP).get(Feature.RADIUS_M, ())):
        return ()
    inf = ((Feature.RADIUS_M, frozenset({math.inf})),)
    return tuple(ForbidRule((ElementCondition(Kind.RAMP, inf, ramp),))
                 for ramp in sorted(turning_ramps(topology)))
