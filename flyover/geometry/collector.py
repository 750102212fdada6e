"""Collector-distributor roads, built as real ones are, without a search.

Decides the plan of a ramp that leaves a carriageway and rejoins the same one
(a C-D road); reads its spec (rails, width, target radius), the radii of the
ramps attached to it, the room its outer connectors need to go round their loops
(:meth:`flyover.geometry.levels.LevelPlan.collector_room`) and the settings.
"""

from __future__ import annotations

import math
from typing import Iterable

import numpy as np

from flyover.geometry.chains import wrap
from flyover.geometry.fit import Obstacles, RampFit, RampSpec, measure_spline
from flyover.geometry.settings import LayoutSettings

__all__ = ["arc", "collector_fit"]


def arc(p: np.ndarray, heading: float, turn: float, radius: float) -> tuple[np.ndarray,
                                                                        np.ndarray, float]:
    """A circular arc from ``p`` at ``heading`` turning ``turn`` rad (left positive) at
    ``radius`` as one cubic (tangents 4/3 tan(|turn| / 4) r long); its end and heading."""
    k = 4.0 / 3.0 * radius * math.tan(abs(turn) / 4.0)
    chord = 2.0 * radius * math.sin(abs(turn) / 2.0)
    h1 = heading + turn
    q = p + chord * np.array([math.cos(heading + turn / 2), math.sin(heading + turn / 2)])
    ctrl = np.stack([p, p + k * np.array([math.cos(heading), math.sin(heading)]),
                     q - k * np.array([math.cos(h1), math.sin(h1)]), q])
    return ctrl, q, h1


def collector_fit(spec: RampSpec, kid_radii: Iterable[float], obstacles: Obstacles,
                  st: LayoutSettings, round_m: tuple[float, float] = (0.0, 0.0)
                  ) -> RampFit | None:
    """A collector-distributor road: it leaves its carriageway on a reverse curve, runs
    straight beside it ``cd_offset_m`` from its edge, and rejoins it on a reverse curve
    (plan: two pairs of circular arcs at the target radius on the lane centre, or
    ``inf_reference_m`` for an ``inf`` target, and a straight). It reaches from the
    crossing's room (the rails' inner ends) far enough for the ramps attached to it
    (radii ``kid_radii``) to turn at their radii; an end where an outer connector leaves
    (joins) it to go round a loop attached to it instead runs straight as far from the
    crossing as that connector needs (``round_m``, before and after the crossing, 0 where
    there is none: :meth:`flyover.geometry.levels.LevelPlan.collector_room`).
    ``None`` when the rails leave no room for it."""
    a, e = spec.start, spec.end
    r_lane = spec.target_radius_m
    if math.isinf(r_lane):
        r_lane = st.fit.inf_reference_m
    half = 0.5 * spec.width_m
    d = st.cd_offset_m
    theta = math.acos(max(-1.0, 1.0 - d / (2.0 * r_lane)))
    s_curve = 2.0 * r_lane * math.sin(theta)  # along the carriageway
    r_kids = max([min(r, st.fit.inf_reference_m) for r in kid_radii] or [0.0])
    room = s_curve + 2.0 * (r_kids + st.gap_m)
    sa, sb = a.hi - room, e.lo + room
    if round_m[0] > 0:  # the rails' stations run along the carriageway from the crossing
        sa = -(round_m[0] + s_curve)  # the connector's need, longer or shorter
    if round_m[1] > 0:
        sb = round_m[1] + s_curve
    sa, sb = float(np.clip(sa, a.lo, a.hi)), float(np.clip(sb, e.lo, e.hi))
    (pa, ha, _), (pb, hb, _) = a.at(np.array([sa])), e.at(np.array([sb]))
    pa, pb, h = pa[0], pb[0], float(ha[0])
    along = float(np.dot(pb - pa, [math.cos(h), math.sin(h)]))
    straight = along - 2.0 * s_curve
    if straight < 1.0 or abs(wrap(float(hb[0]) - h)) > 1e-6:
        return None
    pieces = []
    p, head = np.asarray(pa, float), h
    # right arcs have the lane centre inside (its radius r - half), left arcs outside
    for turn in (-theta, theta):
        c, p, head = arc(p, head, turn, r_lane + (half if turn < 0 else -half))
        pieces.append(c)
    q = p + straight * np.array([math.cos(head), math.sin(head)])
    pieces.append(np.stack([p + (q - p) * f for f in (0.0, 1 / 3, 2 / 3, 1.0)]))
    p = q
    for turn in (theta, -theta):
        c, p, head = arc(p, head, turn, r_lane + (half if turn < 0 else -half))
        pieces.append(c)
    return measure_spline(spec, np.stack(pieces), sa, sb, obstacles, st.fit)
