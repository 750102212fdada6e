"""What "straight" and a radius target of ``inf`` mean, in one place.

A ramp whose radius target is ``inf`` has no turn to hold a radius on: it runs straight
on, or as gently as its ends allow. Every stage reads that the same way:

* the fit (:attr:`flyover.geometry.fit.RampFit.radius_ok`, and the search's radius
  term, whose floor is :attr:`flyover.geometry.fit.RampSpec.inf_floor_m`) and the
  benchmark (``benchmarks/geometry.py``, the radius re-measured from the exported
  ``.xodr``) count an ``inf`` target met when the ramp is nowhere tighter than
  ``(1 - RADIUS_TOLERANCE)`` × the radius an ``inf`` ramp is built with
  (``inf_reference_m``, 250 m: :attr:`flyover.geometry.fit.FitSettings.inf_reference_m`),
  as a finite target is met within :data:`RADIUS_TOLERANCE` of itself
  (:func:`inf_met`, :func:`radius_met`). Until session 37 the fit accepted an ``inf``
  target at 0.95 × 30 m (``geometry.inf_min_radius_m``, the tightest radius of the
  domain): Columbus's ``r12`` was "ok" with a 29–117 m reverse bend, which the benchmark
  (0.95 × 250 m) counted as a miss.
* A ramp whose chain connects roads at least :data:`TURNING_RAD` apart in heading must
  turn: it is never given ``inf`` (:func:`flyover.geometry.feasibility.turning_ramps`);
  one between two ramps that differ by less runs straight on and is given ``inf``
  (:func:`flyover.geometry.feasibility.straight_connectors`).
* A level ramp between two windows fixed by the layout that lie at least
  :data:`SHIFT_M` apart sideways must shift (an S-bend), so sampling does not offer it
  ``inf`` (:func:`flyover.geometry.feasibility.shift_rooms`).
"""

from __future__ import annotations

import math

__all__ = ["INF_REFERENCE_M", "RADIUS_TOLERANCE", "SHIFT_M", "TURNING_RAD", "built_radius",
           "inf_met", "radius_met"]

#: the radius (m) an ``inf`` ramp is built with and held to (the default of
#: :attr:`flyover.geometry.fit.FitSettings.inf_reference_m`)
INF_REFERENCE_M = 250.0

#: a radius target is met within this fraction of itself (``inf``: of ``inf_reference_m``,
#: from below)
RADIUS_TOLERANCE = 0.05

#: a ramp whose chain connects roads at least this far apart in heading (rad) must turn
TURNING_RAD = 0.5

#: a ramp whose windows lie this far apart sideways (m) or more must shift: not straight
SHIFT_M = 0.5


def built_radius(target_m: float, reference_m: float = INF_REFERENCE_M) -> float:
    """The radius (m) a ramp is built with for a radius target ``target_m``: the target, or
    ``reference_m`` (``inf_reference_m``) where it is ``inf``.

    >>> built_radius(60.0), built_radius(math.inf)
    (60.0, 250.0)
    """
    return target_m if math.isfinite(target_m) else reference_m


def inf_met(radius_m: float, reference_m: float = INF_REFERENCE_M) -> bool:
    """Whether a ramp nowhere tighter than ``radius_m`` meets a radius target of ``inf``:
    ``radius_m`` at least ``(1 - RADIUS_TOLERANCE)`` × ``reference_m``.

    >>> inf_met(240.0), inf_met(117.0)
    (True, False)
    """
    return bool(radius_m >= (1.0 - RADIUS_TOLERANCE) * reference_m)


def radius_met(radius_m: float, target_m: float, reference_m: float = INF_REFERENCE_M) -> bool:
    """Whether a held radius ``radius_m`` meets ``target_m``: within
    :data:`RADIUS_TOLERANCE` of it, or, for ``inf``, :func:`inf_met`.

    >>> radius_met(204.0, 210.0), radius_met(240.0, math.inf)
    (True, True)
    """
    if math.isinf(target_m):
        return inf_met(radius_m, reference_m)
    return bool(abs(radius_m - target_m) <= RADIUS_TOLERANCE * target_m)
