"""Approaches: the room a flyover not fitted yet needs where its ends are already fixed.

Decides what a direct left turn fitted earlier keeps clear of, for the sake of the
direct left turns fitted after it; reads the spec of the later ramp (its rails, crest
and slope target) and the settings.

A four-level stack's left turns start and end on the free ends of stubs, fitted
before any of them: those ends are points. The left turns of the lower flyover
level are fitted first; one that crosses its road near the end of the stub that an
upper left turn starts from (or joins) passes there at about the stub's height, where
that upper turn has not climbed yet: no shape of the upper turn between its fixed
ends can clear it (1,493 of 1,536 stack4 ramps first try on the workflow's feature
sets, 34 of the 43 misses on the upper level's ``lB1``/``lB2``). Real stacks cross
their flyovers near the centre, where each is at its own level: the upper turn first
climbs along its stub's heading. So each fixed end of a planned ramp not fitted yet
reserves its *approach*: the straight lead it may climb on
(:meth:`flyover.geometry.specs.RampSpecs._leads`), at the heights of its profile
climbing from that end at its slope target to its crest. An earlier left turn is
first fitted with the approaches as obstacles and at its planned level (lifted, it
would be on the upper turns' level: they then met it in the middle); the build loop
falls back to a fit without either when it cannot meet its targets so. Only left
turns with both ends on stubs reserve anything
(:meth:`flyover.geometry.state.LayoutState.approaches`): one with an end on a road
still chooses where it attaches there.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from flyover.geometry._kernels import STEP_M
from flyover.geometry.bezier import heading_vec
from flyover.geometry.fit import RampSpec
from flyover.geometry.profile import climb_distance, heights

__all__ = ["Approach", "approaches"]

#: a rail whose window is shorter than this (m) is a fixed end (a stub's free end)
FIXED_M = 0.01


@dataclass(frozen=True, eq=False)
class Approach:
    """The lane-centre points ``xy`` ``(n, 2)`` and heights ``z`` of one reserved lead of
    ramp ``ramp``, ``half_width_m`` wide on either side of them."""

    ramp: str
    xy: np.ndarray
    z: np.ndarray
    half_width_m: float


def approaches(spec: RampSpec, transition_m: float) -> list[Approach]:
    """The approaches of a planned ramp (``spec.z_crest`` set) at its fixed ends: from each
    end attached to a point of a fitted ramp, straight along the end's heading (away from
    the ramp's body: forward at its start, backward at its end) for as long as its climb
    from that end to its crest takes at its slope target, at the heights of that climb."""
    if spec.z_crest is None:
        return []
    g = max(spec.target_slope_pct, 0.5) / 100.0
    out = []
    for rail, sign in ((spec.start, 1.0), (spec.end, -1.0)):
        if rail is None or rail.straight or rail.hi - rail.lo > FIXED_M:
            continue
        xy, h, z = rail.at(np.array([rail.lo]))
        z0, heading = float(z[0]), float(h[0])
        rise = spec.z_crest - z0
        if rise <= 0:
            continue
        length = float(climb_distance(rise, g, transition_m))
        d = np.linspace(0.0, length, int(math.ceil(length / (0.5 * STEP_M))) + 1)
        u = heading_vec(heading)
        right = np.array([u[1], -u[0]])
        centre = xy[0] + 0.5 * spec.width_m * right  # the lane centre, right of the reference
        pts = centre + sign * d[:, None] * u
        zs = heights(d[None], np.array([length]), z0, spec.z_crest, spec.z_crest, g,
                     transition_m)[0]
        out.append(Approach(spec.id, pts, np.asarray(zs, float), 0.5 * spec.width_m))
    return out
