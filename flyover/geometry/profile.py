"""Vertical profiles of ramps: a smooth grade line between the heights of its ends.

A ramp starts at height ``z0`` and ends at ``z1``, both with zero grade (it
leaves and joins level carriageways), and may have to pass a crest ``zc``
(a flyover). Its profile climbs (or descends) from ``z0`` to ``zc`` as early as
possible and from ``zc`` to ``z1`` as late as possible, each time with a
parabolic vertical curve of length ``T`` into and out of a constant grade
``g``. The maximum longitudinal slope is therefore exactly ``g`` whenever the
ramp is long enough; otherwise the grade needed (:func:`required_grade`) is
steeper and the ramp misses its target.

Example
-------
>>> import numpy as np
>>> polys = elevation_polys(400.0, 0.0, 6.5, 6.5, 0.04, 40.0)
>>> z, g = evaluate_polys(polys, np.array([0.0, 400.0]))
>>> [round(float(x), 3) for x in z], round(max_grade(polys, 400.0) * 100, 3)
([0.0, 6.5], 4.0)
"""

from __future__ import annotations

import numpy as np

from flyover.geometry.model import ElevationPoly

__all__ = ["climb_distance", "heights", "required_grade", "elevation_polys",
           "evaluate_polys", "max_grade"]


def climb_distance(height: np.ndarray, grade: float, transition: float) -> np.ndarray:
    """Horizontal distance to climb ``height`` at ``grade`` with vertical curves."""
    h = np.abs(np.asarray(height, float))
    t = np.minimum(transition, h / grade)
    return np.where(h > 0, h / grade + t, 0.0)


def _climb(s: np.ndarray, h: np.ndarray, grade: float, transition: float) -> np.ndarray:
    """Height gained after ``s`` metres of a climb of total ``h`` (broadcasting)."""
    t = np.maximum(np.minimum(transition, h / grade), 1e-9)
    d = np.where(h > 0, h / grade + t, 0.0)
    s = np.clip(s, 0.0, None)
    up = grade * s**2 / (2 * t)
    mid = grade * t / 2 + grade * (s - t)
    top = h - grade * np.clip(d - s, 0, None) ** 2 / (2 * t)
    z = np.where(s < t, up, np.where(s <= d - t, mid, top))
    return np.where(s >= d, h, np.where(h > 0, z, 0.0))


def heights(s: np.ndarray, length: np.ndarray, z0, zc, z1, grade: float,
            transition: float) -> np.ndarray:
    """Profile heights at arc lengths ``s`` ``(P, N)`` for ramps of ``length`` ``(P,)``."""
    length = np.asarray(length, float)[..., None]
    z0, zc, z1 = (np.asarray(v, float)[..., None] for v in (z0, zc, z1))
    hr, hf = np.abs(zc - z0), np.abs(zc - z1)
    rise = np.sign(zc - z0) * _climb(s, hr, grade, transition)
    fall = np.sign(z1 - zc) * (hf - _climb(length - s, hf, grade, transition))
    return z0 + rise + fall


def required_grade(length: float, z0: float, zc: float, z1: float, grade: float,
                   transition: float) -> float:
    """The smallest grade ``>= grade`` whose profile fits in ``length`` (bisection)."""
    def need(g: float) -> float:
        return float(climb_distance(zc - z0, g, transition) + climb_distance(zc - z1, g, transition))

    if need(grade) <= length:
        return grade
    lo, hi = grade, 10.0
    if need(hi) > length:
        return hi
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if need(mid) > length else (lo, mid)
    return hi


def _climb_polys(s0: float, z0: float, h: float, sign: float, grade: float,
                 transition: float) -> list[ElevationPoly]:
    if h <= 0:
        return []
    t = min(transition, h / grade)
    d = h / grade + t
    g, z0, s0 = float(sign * grade), float(z0), float(s0)
    out = [ElevationPoly(s0, z0, 0.0, g / (2 * t), 0.0)]
    if d - 2 * t > 1e-9:
        out.append(ElevationPoly(s0 + t, z0 + g * t / 2, g, 0.0, 0.0))
    out.append(ElevationPoly(s0 + d - t, z0 + sign * (h - grade * t / 2), g, -g / (2 * t), 0.0))
    return out


def elevation_polys(length: float, z0: float, zc: float, z1: float, grade: float,
                    transition: float) -> tuple[ElevationPoly, ...]:
    """OpenDRIVE-style elevation polynomials of the profile, covering ``0..length``.

    ``grade`` is raised to :func:`required_grade` when the ramp is too short.
    """
    g = required_grade(length, z0, zc, z1, grade, transition)
    hr, hf = abs(zc - z0), abs(zc - z1)
    dr = float(climb_distance(hr, g, transition))
    df = float(climb_distance(hf, g, transition))
    polys = _climb_polys(0.0, z0, hr, np.sign(zc - z0), g, transition)
    if length - df - dr > 1e-9 or not polys:
        polys.append(ElevationPoly(dr, float(zc), 0.0, 0.0, 0.0))
    polys += _climb_polys(length - df, zc, hf, np.sign(z1 - zc), g, transition)
    return tuple(p for i, p in enumerate(polys) if i + 1 == len(polys) or polys[i + 1].s_m > p.s_m)


def evaluate_polys(polys: tuple[ElevationPoly, ...], s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Heights and grades of an elevation profile at arc lengths ``s``."""
    s = np.asarray(s, float)
    starts = np.array([p.s_m for p in polys])
    i = np.clip(np.searchsorted(starts, s, side="right") - 1, 0, len(polys) - 1)
    coef = np.array([[p.a, p.b, p.c, p.d] for p in polys])[i]
    ds = s - starts[i]
    z = coef[:, 0] + ds * (coef[:, 1] + ds * (coef[:, 2] + ds * coef[:, 3]))
    g = coef[:, 1] + ds * (2 * coef[:, 2] + 3 * ds * coef[:, 3])
    return z, g


def max_grade(polys: tuple[ElevationPoly, ...], length: float, n: int = 2001) -> float:
    """Largest absolute grade of the profile, sampled densely over ``0..length``."""
    _, g = evaluate_polys(polys, np.linspace(0.0, length, n))
    return float(np.abs(g).max())
