"""Cubic Bézier splines in the plane, evaluated for whole DE populations at once.

A spline of ``n`` cubic pieces is an array of control points of shape
``(..., n, 4, 2)``; every function here broadcasts over the leading axes, so a
population of ``P`` candidate ramps is one array ``(P, n, 4, 2)``.

Example
-------
>>> import numpy as np
>>> k = 0.5522847498  # quarter circle of radius 100
>>> c = np.array([[[0, 0], [100 * k, 0], [100, 100 * (1 - k)], [100, 100]]], float)
>>> s = sample_spline(c, 64)
>>> round(float(1 / np.abs(s.curvature).max()), 1), round(float(s.length), 1)
(99.2, 157.1)
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

__all__ = ["SplineSamples", "sample_spline", "lane_radius", "lane_centre", "turning",
           "heading_vec"]


@lru_cache(maxsize=16)
def _basis(m: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    t = np.linspace(0.0, 1.0, m)
    u = 1.0 - t
    b = np.stack([u**3, 3 * u**2 * t, 3 * u * t**2, t**3], axis=1)
    db = np.stack([-3 * u**2, 3 * u**2 - 6 * u * t, 6 * u * t - 3 * t**2, 3 * t**2], axis=1)
    ddb = np.stack([6 * u, -12 * u + 6 * t, 6 * u - 12 * t, 6 * t], axis=1)
    return t, b, db, ddb


def heading_vec(theta: np.ndarray) -> np.ndarray:
    """Unit vectors ``(..., 2)`` for headings ``theta`` (radians from +x)."""
    theta = np.asarray(theta, float)
    return np.stack([np.cos(theta), np.sin(theta)], axis=-1)


@dataclass(frozen=True)
class SplineSamples:
    """Points sampled uniformly in the Bézier parameter of every piece.

    Attributes
    ----------
    xy
        ``(..., n*m, 2)`` points in travel order (pieces concatenated).
    s
        ``(..., n*m)`` arc length from the start (trapezoid rule).
    curvature
        ``(..., n*m)`` signed curvature (positive = turning left).
    tangent
        ``(..., n*m, 2)`` first derivatives (not normalised).
    piece_length
        ``(..., n)`` arc length of each piece.
    """

    xy: np.ndarray
    s: np.ndarray
    curvature: np.ndarray
    tangent: np.ndarray
    piece_length: np.ndarray

    @property
    def length(self) -> np.ndarray:
        """Total arc length ``(...)``."""
        return self.piece_length.sum(axis=-1)


def sample_spline(ctrl: np.ndarray, m: int = 32) -> SplineSamples:
    """Sample every piece of ``ctrl`` ``(..., n, 4, 2)`` at ``m`` parameter values."""
    ctrl = np.asarray(ctrl, float)
    _, b, db, ddb = _basis(m)
    p = np.matmul(b, ctrl)
    d1 = np.matmul(db, ctrl)
    d2 = np.matmul(ddb, ctrl)
    speed = np.hypot(d1[..., 0], d1[..., 1])
    cross = d1[..., 0] * d2[..., 1] - d1[..., 1] * d2[..., 0]
    kappa = cross / np.maximum(speed, 1e-9) ** 3
    seg = 0.5 * (speed[..., 1:] + speed[..., :-1]) / (m - 1)
    piece_len = seg.sum(axis=-1)
    local = np.concatenate([np.zeros(seg.shape[:-1] + (1,)), np.cumsum(seg, axis=-1)], axis=-1)
    offsets = np.cumsum(piece_len, axis=-1) - piece_len
    s = local + offsets[..., None]
    lead = ctrl.shape[:-3]
    n = ctrl.shape[-3]
    return SplineSamples(
        xy=p.reshape(lead + (n * m, 2)),
        s=s.reshape(lead + (n * m,)),
        curvature=kappa.reshape(lead + (n * m,)),
        tangent=d1.reshape(lead + (n * m, 2)),
        piece_length=piece_len,
    )


def lane_radius(curvature: np.ndarray, width_m: float) -> np.ndarray:
    """Radius of the lane centre line, ``width_m/2`` right of a left-edge reference line.

    Offsetting a curve of signed curvature ``κ`` by ``w/2`` to the right gives
    the radius ``|1/κ + w/2|`` (infinite where ``κ = 0``).
    """
    k = np.asarray(curvature, float)
    with np.errstate(divide="ignore"):
        r = np.abs(1.0 / k + 0.5 * width_m)
    return np.where(k == 0.0, np.inf, r)


def held_radius(samples: "SplineSamples", width_m: float, hold_m: float) -> float:
    """The tightest lane-centre radius a sampled spline holds over ``hold_m`` of arc (or
    its whole length, if shorter): from the mean curvature (heading change over arc
    length of the reference line) between each sample and the first one ``hold_m``
    further on, as :func:`lane_radius` offsets it. A circular arc of radius ``r`` gives
    ``r``; a curve tight for less than ``hold_m`` gives more than its pointwise minimum.

    >>> import numpy as np
    >>> k = 4 / 3 * np.tan(np.pi / 8) * 100.0  # a cubic close to a quarter circle, r 100 m
    >>> arc = sample_spline(np.array([[[0, 0], [k, 0], [100, 100 - k], [100, 100]]], float), 400)
    >>> round(held_radius(arc, 0.0, 10.0), 1), round(float(lane_radius(arc.curvature, 0.0).min()), 1)
    (99.2, 99.2)
    >>> bent = sample_spline(np.array([[[0, 0], [5, 0], [400, 300], [1000, 300]]], float), 400)
    >>> held_radius(bent, 0.0, 10.0) > 1.2 * float(lane_radius(bent.curvature, 0.0).min())
    True
    """
    s = np.asarray(samples.s, float).ravel()
    tang = np.asarray(samples.tangent, float).reshape(-1, 2)
    head = np.unwrap(np.arctan2(tang[:, 1], tang[:, 0]))
    hold = min(hold_m, 0.999 * float(s[-1] - s[0]))
    if hold <= 0:
        return float("inf")
    k = np.searchsorted(s, s + hold, side="left")
    ok = k < len(s)
    j = np.flatnonzero(ok)
    ds = s[k[ok]] - s[j]
    kap = (head[k[ok]] - head[j]) / ds
    r = lane_radius(kap, width_m)
    return float(r.min()) if len(r) else float("inf")


def lane_centre(xy: np.ndarray, tangent: np.ndarray, width_m: float) -> tuple[np.ndarray, np.ndarray]:
    """x and y ``(...)`` of the lane centre line, ``width_m/2`` right of a left-edge
    reference line sampled at ``xy`` with tangents ``tangent`` ``(..., 2)``."""
    speed = np.maximum(np.hypot(tangent[..., 0], tangent[..., 1]), 1e-9)
    half = 0.5 * width_m / speed
    return xy[..., 0] + half * tangent[..., 1], xy[..., 1] - half * tangent[..., 0]


def turning(tangent: np.ndarray) -> np.ndarray:
    """Total signed heading change ``(...)`` along sampled tangents ``(..., N, 2)``."""
    ang = np.arctan2(tangent[..., 1], tangent[..., 0])
    d = np.diff(ang, axis=-1)
    d = (d + np.pi) % (2 * np.pi) - np.pi
    return d.sum(axis=-1)
