"""Shortest paths of bounded curvature (Dubins paths): how long a ramp must be at least.

A path from a pose (point and heading) to another that never turns tighter than
radius ``r`` is at least as long as the shortest of the six Dubins words (LSL, RSR,
LSR, RSL, RLR, LRL; Dubins, Am. J. Math. 79(3), 1957; the closed forms of Shkel &
Lumelsky, Robotica 19(1), 2001). A ramp that holds its radius target joins its
attachments by such a path, so the shortest Dubins path between any two points of
its attachment windows is a lower bound of its length
(``least_m`` in ``benchmarks/geometry.py``).

>>> import numpy as np
>>> float(shortest(np.zeros(2), 0.0, np.array([10.0, 0.0]), 0.0, 5.0)[()])  # straight
10.0
>>> round(float(shortest(np.zeros(2), 0.0, np.array([10.0, 10.0]), np.pi / 2, 10.0)[()]), 3)
15.708
"""

from __future__ import annotations

import numpy as np

__all__ = ["shortest"]

_TWO_PI = 2.0 * np.pi


def _mod(a: np.ndarray) -> np.ndarray:
    return np.mod(a, _TWO_PI)


def _take(best: np.ndarray, valid: np.ndarray, length: np.ndarray) -> np.ndarray:
    return np.fmin(best, np.where(valid, length, np.inf))


def shortest(p0: np.ndarray, h0, p1: np.ndarray, h1, r: float) -> np.ndarray:
    """Length of the shortest path of curvature at most ``1 / r`` from ``p0`` (``(..., 2)``)
    heading ``h0`` to ``p1`` heading ``h1`` (broadcast); ``inf`` where no word exists
    (never for all six together)."""
    p0, p1 = np.asarray(p0, float), np.asarray(p1, float)
    dx, dy = p1[..., 0] - p0[..., 0], p1[..., 1] - p0[..., 1]
    d = np.hypot(dx, dy) / r
    theta = np.arctan2(dy, dx)
    a = _mod(np.asarray(h0, float) - theta)
    b = _mod(np.asarray(h1, float) - theta)
    sa, ca, sb, cb = np.sin(a), np.cos(a), np.sin(b), np.cos(b)
    cab = np.cos(a - b)
    best = np.full(np.broadcast(d, a, b).shape, np.inf)
    with np.errstate(invalid="ignore"):
        # LSL
        p2 = 2 + d * d - 2 * cab + 2 * d * (sa - sb)
        k = np.arctan2(cb - ca, d + sa - sb)
        best = _take(best, p2 >= -1e-9, _mod(k - a) + np.sqrt(np.maximum(p2, 0)) + _mod(b - k))
        # RSR
        p2 = 2 + d * d - 2 * cab + 2 * d * (sb - sa)
        k = np.arctan2(ca - cb, d - sa + sb)
        best = _take(best, p2 >= -1e-9, _mod(a - k) + np.sqrt(np.maximum(p2, 0)) + _mod(k - b))
        # LSR
        p2 = -2 + d * d + 2 * cab + 2 * d * (sa + sb)
        pp = np.sqrt(np.maximum(p2, 0))
        k = np.arctan2(-ca - cb, d + sa + sb) - np.arctan2(-2.0, pp)
        best = _take(best, p2 >= -1e-9, _mod(k - a) + pp + _mod(k - b))
        # RSL
        p2 = d * d - 2 + 2 * cab - 2 * d * (sa + sb)
        pp = np.sqrt(np.maximum(p2, 0))
        k = np.arctan2(ca + cb, d - sa - sb) - np.arctan2(2.0, pp)
        best = _take(best, p2 >= -1e-9, _mod(a - k) + pp + _mod(b - k))
        # RLR
        c = (6.0 - d * d + 2 * cab + 2 * d * (sa - sb)) / 8.0
        pp = _mod(_TWO_PI - np.arccos(np.clip(c, -1, 1)))
        t = _mod(a - np.arctan2(ca - cb, d - sa + sb) + pp / 2.0)
        best = _take(best, np.abs(c) <= 1 + 1e-9, t + pp + _mod(a - b - t + pp))
        # LRL
        c = (6.0 - d * d + 2 * cab + 2 * d * (sb - sa)) / 8.0
        pp = _mod(_TWO_PI - np.arccos(np.clip(c, -1, 1)))
        t = _mod(-a - np.arctan2(ca - cb, d + sa - sb) + pp / 2.0)
        best = _take(best, np.abs(c) <= 1 + 1e-9, t + pp + _mod(b - a - t + pp))
    return best * r
