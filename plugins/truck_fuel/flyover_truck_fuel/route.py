"""A ramp as the route a truck drives: the lane centre line in 3D with its leads.

The ramp's lane centre line is its plan curve (the reference line, its left
edge) offset right by half its lane width (:func:`flyover.geometry.bezier.lane_centre`),
with heights and grades from its elevation profile
(:func:`flyover.geometry.profile.evaluate_polys`, which runs along the
reference line). It is sampled every ``spacing_m`` of lane-centre arc length
``s`` (``s = 0`` where the ramp leaves its parent) and extended by straight
leads: ``lead_in_m`` before the diverge and ``lead_out_m`` after the merge,
along the ramp's end tangents (a ramp leaves and joins its parent tangentially).

The road-aligned (Frenet) frame of the planner and the truck model is this
extended line; lateral offsets ``d`` are positive to the left. On the
lead-in the truck's lane is the parent's lane nearest to the ramp, so the
*preferred offset* ``d_pref`` there is that lane's offset; it becomes 0
(the ramp's lane) ``lane_change_by_m`` before the ramp starts, and the
target lane's offset after the merge.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from flyover.geometry.bezier import lane_centre, sample_spline
from flyover.geometry.model import Attachment, InterchangeGeometry, RampGeometry
from flyover.geometry.profile import evaluate_polys

from flyover_truck_fuel.params import RouteParams

__all__ = ["Route", "ramp_route", "straight_route"]


@dataclass(frozen=True)
class Route:
    """A route sampled uniformly in arc length.

    Attributes
    ----------
    s
        Stations (m), at most ``spacing_m`` apart (uniform on the leads and, slightly
        closer, on the ramp), ``s = 0`` at the ramp's start.
    x, y, z, heading, curvature, grade
        Lane-centre position, height, heading (rad, unwrapped), signed
        curvature (1/m, positive left) and grade (rise/run) at ``s``.
    d_pref
        Preferred lateral offset of the truck (m, positive left).
    ramp_length_m
        Lane-centre length of the ramp itself (stations ``0..ramp_length_m``).
    """

    s: np.ndarray
    x: np.ndarray
    y: np.ndarray
    z: np.ndarray
    heading: np.ndarray
    curvature: np.ndarray
    grade: np.ndarray
    d_pref: np.ndarray
    ramp_length_m: float

    @property
    def spacing_m(self) -> float:
        """The largest station spacing."""
        return float(np.diff(self.s).max())

    def on_ramp(self) -> np.ndarray:
        """Mask of the stations on the ramp itself."""
        return (self.s >= 0.0) & (self.s <= self.ramp_length_m)

    @property
    def min_radius_m(self) -> float:
        k = np.abs(self.curvature[self.on_ramp()]).max(initial=0.0)
        return math.inf if k == 0.0 else float(1.0 / k)

    @property
    def max_slope_pct(self) -> float:
        return float(100.0 * np.abs(self.grade[self.on_ramp()]).max(initial=0.0))

    @property
    def climb_m(self) -> float:
        """Height at the merge minus height at the diverge."""
        return float(np.interp(self.ramp_length_m, self.s, self.z) - np.interp(0.0, self.s, self.z))


def _lane_offsets(lanes: int, width: float) -> np.ndarray:
    """Lane-centre offsets from a left-edge reference line (positive left)."""
    return -(np.arange(lanes) + 0.5) * width


def _parent_lane_offset(g: InterchangeGeometry, ramp: RampGeometry, att: Attachment) -> float:
    """Offset (positive left, in the ramp's direction) of the parent's lane nearest the ramp's."""
    ramp_centre = att.offset_m - 0.5 * ramp.lanes * g.ramp_lane_width_m
    try:
        parent = g.road(att.parent)
        lanes = _lane_offsets(parent.lanes, g.lane_width_m)
    except KeyError:
        try:
            parent = g.ramp(att.parent)
        except KeyError:
            return 0.0
        lanes = _lane_offsets(parent.lanes, g.ramp_lane_width_m)
    nearest = lanes[np.argmin(np.abs(lanes - ramp_centre))]
    return float(nearest - ramp_centre)


def _resample(s_new: np.ndarray, s: np.ndarray, *cols: np.ndarray) -> list[np.ndarray]:
    return [np.interp(s_new, s, c) for c in cols]


def _assemble(s0: np.ndarray, x: np.ndarray, y: np.ndarray, z: np.ndarray, grade: np.ndarray,
              length: float, d_in: float, d_out: float, p: RouteParams) -> Route:
    """Resample a lane-centre polyline, add straight leads, derive heading and curvature."""
    ds = p.spacing_m
    n = max(2, int(math.ceil(length / ds)))
    s = np.linspace(0.0, length, n + 1)
    head0 = np.unwrap(np.arctan2(np.gradient(y, s0), np.gradient(x, s0)))
    xr, yr, zr, gr, hr = _resample(s, s0, x, y, z, grade, head0)
    hr = np.interp(s, s0, head0)
    n_in = int(math.ceil(p.lead_in_m / ds))
    n_out = int(math.ceil(p.lead_out_m / ds))
    si = -ds * np.arange(n_in, 0, -1)
    so = length + ds * np.arange(1, n_out + 1)
    h0, h1 = hr[0], hr[-1]
    xs = np.concatenate([xr[0] + si * math.cos(h0), xr, xr[-1] + (so - length) * math.cos(h1)])
    ys = np.concatenate([yr[0] + si * math.sin(h0), yr, yr[-1] + (so - length) * math.sin(h1)])
    zs = np.concatenate([zr[0] + si * gr[0], zr, zr[-1] + (so - length) * gr[-1]])
    gs = np.concatenate([np.full(n_in, gr[0]), gr, np.full(n_out, gr[-1])])
    hs = np.concatenate([np.full(n_in, h0), hr, np.full(n_out, h1)])
    ss = np.concatenate([si, s, so])
    # curvature = dθ/ds by central differences on the heading sampled on the lane centre
    k = np.gradient(hs, ss)
    k[: n_in] = 0.0
    k[n_in + len(s):] = 0.0
    d_pref = np.where(ss < -p.lane_change_by_m, d_in, 0.0)
    d_pref = np.where(ss > length, d_out, d_pref)
    return Route(ss, xs, ys, zs, hs, k, gs, d_pref, float(length))


def ramp_route(geometry: InterchangeGeometry, ramp: RampGeometry, p: RouteParams) -> Route:
    """The route of ``ramp``: its lane centre line in 3D with leads on its parents.

    Example
    -------
    >>> from flyover_truck_fuel.params import settings
    >>> r = straight_route(500.0, 0.02, settings({}).route)
    >>> round(r.ramp_length_m), round(r.climb_m, 1), r.max_slope_pct
    (500, 10.0, 2.0)
    """
    width = ramp.lanes * geometry.ramp_lane_width_m
    ctrl = np.array([pc.p for pc in ramp.plan], float)
    m = max(16, int(math.ceil(max(pc.length_m for pc in ramp.plan) / (0.5 * p.spacing_m))))
    smp = sample_spline(ctrl, m)
    keep = np.concatenate([[True], np.diff(smp.s) > 1e-9])  # pieces share their end points
    ref_xy, tan, s_ref = smp.xy[keep], smp.tangent[keep], smp.s[keep]
    x, y = lane_centre(ref_xy, tan, width)
    seg = np.hypot(np.diff(x), np.diff(y))
    s_lane = np.concatenate([[0.0], np.cumsum(seg)])
    z, g_ref = evaluate_polys(ramp.elevation, s_ref)
    # the profile's grade is per metre of reference line: per metre of lane centre it scales
    dref = np.gradient(s_ref)
    dlane = np.gradient(s_lane)
    grade = g_ref * dref / np.maximum(dlane, 1e-9)
    d_in = _parent_lane_offset(geometry, ramp, ramp.start)
    d_out = _parent_lane_offset(geometry, ramp, ramp.end)
    return _assemble(s_lane, x, y, z, grade, float(s_lane[-1]), d_in, d_out, p)


def straight_route(length_m: float, grade: float, p: RouteParams, *, radius_m: float = math.inf,
                   transition_m: float = 0.0) -> Route:
    """A test route of ``length_m`` at a constant ``grade``: straight, or a left-turning
    curve of ``radius_m`` entered and left through clothoids of ``transition_m`` each
    (curvature linear in arc length), between straight leads at the same grade.

    A 90° ramp of radius ``R`` with clothoids of length ``T`` is
    ``straight_route(R·π/2 + T, g, p, radius_m=R, transition_m=T)``.
    """
    n = max(2, int(math.ceil(length_m / (0.25 * p.spacing_m))))
    s = np.linspace(0.0, length_m, n + 1)
    if math.isinf(radius_m):
        x, y = s.copy(), np.zeros_like(s)
    else:
        tr = min(transition_m, 0.5 * length_m)
        k = np.full_like(s, 1.0 / radius_m)
        if tr > 0:
            k = np.minimum(k, np.minimum(s, length_m - s) / (tr * radius_m))
        ds = np.diff(s)
        th = np.concatenate([[0.0], np.cumsum(0.5 * (k[1:] + k[:-1]) * ds)])
        x = np.concatenate([[0.0], np.cumsum(0.5 * (np.cos(th[1:]) + np.cos(th[:-1])) * ds)])
        y = np.concatenate([[0.0], np.cumsum(0.5 * (np.sin(th[1:]) + np.sin(th[:-1])) * ds)])
    z = grade * s
    return _assemble(s, x, y, z, np.full_like(s, grade), float(length_m), 0.0, 0.0, p)
