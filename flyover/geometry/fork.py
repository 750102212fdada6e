"""Room at a stub's fork: the way out the child fitted second needs, kept by the first.

A stub with no end splits into its children at its free end, side by side (the one
leaving on the left on the stub's left lanes, the one on the right on its right
lanes, :meth:`flyover.geometry.rails.RampWindows.ramp_rail`); a stub with no
start is formed where its children join, the same way round. The children are fitted
one after the other, and the first knew nothing of the second: a turbine's left turn
``lB2``, fitted before its sibling right turn ``rB2``, swung right across ``rB2``'s
start 20-30 m after the fork at about the fork's height, so that ``rB2`` either
grazed it (turbine sample 75: 3.3 m apart 17-34 m after the fork, where 3.5 m is
needed) or turned tighter than its radius target to get past (samples 4, 8, 31).

:func:`way_out` reserves the sibling's way: its lane centre from its fixed end,
turning by its turn at its radius target (the tightest it may: any gentler way lies
between that and straight on), at the heights of its climb from the fork at its slope
target, as an obstacle the first child keeps clear of exactly as it will keep clear
of the sibling once fitted (an :class:`flyover.geometry.approaches.Approach`: the
search's measure, the two half widths, the same clearance in height). It runs until the two are a
clearance apart in height at their slope targets (as the fence of a T's terminal,
:mod:`flyover.geometry.terminals`) or the sibling has turned its turn, whichever
comes first; the first child may pass over or under it beyond that, as over any
ramp. The build loop fits the first child so
(:meth:`flyover.geometry.state.LayoutState.fork_room`) and drops the reservation
when it cannot meet its targets within it, as the fences.
"""

from __future__ import annotations

import math

import numpy as np

from flyover.geometry._kernels import STEP_M
from flyover.geometry.approaches import Approach
from flyover.geometry.bezier import heading_vec
from flyover.geometry.fit import RampSpec
from flyover.geometry.profile import heights, parting_distance
from flyover.geometry.settings import LayoutSettings

__all__ = ["departure_grade", "way_out"]


def _top(spec: RampSpec) -> float:
    """The highest a ramp's profile gets: its crest, or its higher end."""
    ends = [float(r.at(np.array([r.lo]))[2][0]) for r in (spec.start, spec.end) if r is not None]
    return max([*ends, spec.z_crest if spec.z_crest is not None else -math.inf,
                spec.free.z if spec.free is not None else -math.inf])


def departure_grade(spec: RampSpec, z_fork: float) -> float:
    """The grade at which a ramp leaves the height ``z_fork`` of one of its ends: its slope
    target if it climbs from there to its crest (its profile climbs from each end to its
    top), else 0 (level there; it descends at its other end, if at all)."""
    return spec.target_slope_pct / 100.0 if _top(spec) > z_fork + 1e-6 else 0.0


def way_out(sibling: RampSpec, at_start: bool, grade: float,
            st: LayoutSettings) -> Approach | None:
    """The way ``sibling`` (a stub's child not fitted yet) takes out of its fork
    (``at_start``; else into its join, backward from its end): its lane centre turning
    at its radius target (``inf``: straight) by its turn, from its fixed end on the
    stub, at the heights of its climb from there at its slope target, for as long as a
    child leaving that fork at ``grade`` and it need to be a clearance apart in height
    (:attr:`FitSettings.clearance_m` over the sum of their grades, at least 0.5 %, and a
    grade transition), and no longer than its turn. ``None`` for an end that is not
    fixed (not on a stub's free end)."""
    rail = sibling.start if at_start else sibling.end
    if rail is None or rail.hi - rail.lo > 0.01:
        return None
    xy, head, z = rail.at(np.array([rail.lo]))
    z0 = float(z[0])
    g = departure_grade(sibling, z0)
    reach = parting_distance(grade + g, st.fit.clearance_m, st.fit.transition_m)
    radius = sibling.target_radius_m
    length = min(reach, abs(sibling.turn_rad) * radius) if math.isfinite(radius) else reach
    sign = 1.0 if at_start else -1.0  # forward from a fork, backward from a join
    d = np.linspace(0.0, length, int(math.ceil(length / (0.5 * STEP_M))) + 1)
    kappa = math.copysign(1.0 / radius, sibling.turn_rad) if math.isfinite(radius) else 0.0
    theta = float(head[0]) + sign * kappa * d
    u = heading_vec(theta)
    steps = np.diff(d)[:, None] * 0.5 * (u[1:] + u[:-1])  # trapezoid: exact enough at 1 m
    u0 = heading_vec(float(head[0]))
    centre = xy[0] + 0.5 * sibling.width_m * np.array([u0[1], -u0[0]])
    pts = centre + sign * np.vstack([np.zeros((1, 2)), np.cumsum(steps, axis=0)])
    top = max(_top(sibling), z0)
    zs = heights(d[None], np.array([length]), z0, top, top, max(g, 1e-3),
                 st.fit.transition_m)[0]
    return Approach(sibling.id, pts, np.asarray(zs, float), 0.5 * sibling.width_m)
