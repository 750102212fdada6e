"""Vertical profiles of ramps: a smooth grade line between the heights of its ends.

A ramp starts at height ``z0`` and ends at ``z1``, both with zero grade where it
leaves and joins a level carriageway, and may have to pass a crest ``zc``
(a flyover). Its profile climbs (or descends) from ``z0`` to ``zc`` as early as
possible and from ``zc`` to ``z1`` as late as possible, each time with a
parabolic vertical curve of length ``T`` into and out of a constant grade
``g``. The maximum longitudinal slope is therefore exactly ``g`` whenever the
ramp is long enough; otherwise the grade needed (:func:`required_grade`) is
steeper and the ramp misses its target.

A ramp leaving (joining) another ramp where that one is on a grade starts (ends)
at that grade, ``g0`` (``g1``), so that the road has no kink in its profile: its
climb (descent) then begins with a vertical curve from that grade to its own
(:func:`_leg`); where its parent climbs on beyond the ramp's crest, the ramp's
crest rises to where that grade runs out (a crest curve). A climb that only levels
off from its parent's grade keeps the rate ``g / T``; the part of a rise the ramp
climbs by itself has its curves shortened as a short climb from level has them
(:func:`_leg_transition`), so that a slight start grade changes the profile only
slightly. With ``g0 = g1 = 0`` the profile is the one above, and the one the
search assumes (:func:`heights`).

Example
-------
>>> import numpy as np
>>> polys = elevation_polys(400.0, 0.0, 6.5, 6.5, 0.04, 40.0)
>>> z, g = evaluate_polys(polys, np.array([0.0, 400.0]))
>>> [round(float(x), 3) for x in z], round(max_grade(polys, 400.0) * 100, 3)
([0.0, 6.5], 4.0)
"""

from __future__ import annotations

import math

import numpy as np

from flyover.geometry.model import ElevationPoly

__all__ = ["climb_distance", "parting_distance", "loop_radius", "heights", "required_grade",
           "elevation_polys", "evaluate_polys", "max_grade"]


#: a height difference (m) below which a ramp's end does not climb: Columbus's r13 ended
#: 5.3e-9 m under its plateau (the grade it leaves its parent at), and the climb down
#: was two pieces 5e-9 m long with c = +-9.4e7 (a 2e6 pp grade read at its end)
FLAT_M = 1e-6


def climb_distance(height: np.ndarray, grade: float, transition: float) -> np.ndarray:
    """Horizontal distance to climb ``height`` at ``grade`` with vertical curves."""
    h = np.abs(np.asarray(height, float))
    t = np.minimum(transition, h / grade)
    return np.where(h > 0, h / grade + t, 0.0)


def parting_distance(grade: float, clearance: float, transition: float) -> float:
    """How far two roads leaving (joining) one point must run before they are
    ``clearance`` apart in height when they part at ``grade`` (the sum of their grades,
    taken as at least 0.5 %), after a grade transition: the reach of a T terminal's
    branch fence and of a fork's way out.

    >>> parting_distance(0.08, 5.0, 40.0)
    102.5
    """
    return clearance / max(grade, 0.005) + transition


def loop_radius(radius: float, height: float, slope_pct: float, transition: float) -> float:
    """The radius a loop of ``radius`` takes up when it must climb ``height`` at
    ``slope_pct`` (taken as at least 0.5 %): a loop that must climb farther than its
    three-quarter turn is long is as big as a loop turning that length.

    >>> round(loop_radius(30.0, 7.0, 4.0, 40.0), 2), loop_radius(100.0, 7.0, 4.0, 40.0)
    (45.62, 100.0)
    """
    g = max(slope_pct, 0.5) / 100.0
    return max(radius, float(climb_distance(height, g, transition)) / (1.5 * math.pi))


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


def _leg_transition(h: float, e: float, grade: float, transition: float) -> float:
    """The curve length ``t`` (for a change of ``grade``: its curves turn at
    ``grade / t`` per metre) of a climb of ``h`` that starts at grade ``e`` and ends level.

    Of the rise, levelling off from ``e`` at the rate ``grade / transition`` gains
    ``l = e² · transition / (2 · grade)`` (0 where ``e <= 0``; :func:`_crest` makes
    ``h >= l``); the rest, ``h - l``, the ramp climbs by itself. The rate is the mean of
    the shares' rates, weighted by height: ``grade / transition`` for the levelling
    off and, for the ramp's own climb, the rate of a climb of ``h`` from level, whose
    curves shrink to ``h / grade`` where ``h < grade · transition``
    (:func:`_climb_polys`). It is no sharper than the rate at which the climb just
    reaches ``grade``, nor gentler than ``grade / transition``. So ``e -> 0`` gives the
    climb from level (peak ``grade``), a rise that only levels off (``h = l``) keeps
    ``transition`` (peak ``e``), and a climb long enough for ``grade`` is unchanged.

    >>> _leg_transition(1.0, 0.0, 0.03, 40.0), round(_leg_transition(1.0, 0.0005, 0.03, 40.0), 3)
    (33.333333333333336, 33.338)
    >>> _leg_transition(0.45, 0.03, 0.04, 40.0), _leg_transition(3.0, 0.0005, 0.03, 40.0)
    (40.0, 40.0)
    >>> round(_leg_transition(0.5, 0.02, 0.04, 40.0), 3)  # 0.2 m levelling off, 0.3 m own
    17.241
    """
    if h <= 0:
        return transition
    lev = min(e * e * transition / (2 * grade), h) if e > 0 else 0.0
    if h - lev <= 1e-9:  # levelling off only (to rounding)
        return transition
    own = h / (lev / transition + (h - lev) / min(transition, h / grade))
    peak = 2 * grade * h / (2 * grade**2 - e * e) if e < grade and e * e < 2 * grade**2 \
        else transition
    return min(transition, max(own, peak))


def _leg(h: float, e: float, grade: float, transition: float) -> tuple[float, float, float, float]:
    """A climb of ``h >= 0`` that starts at grade ``e`` (toward the top, may be negative)
    and ends level: ``(a1, q, m, a2)``: a vertical curve of ``a1`` m from ``e`` to the
    peak grade ``q``, ``m`` m at ``q``, a curve of ``a2`` m from ``q`` to level, both curves
    at ``grade / t`` per metre (``t``: :func:`_leg_transition`). ``q`` is ``grade`` unless
    the climb is too short for it; ``h`` is at least what levelling off from ``e`` gains
    (:func:`_crest`)."""
    t = _leg_transition(h, e, grade, transition)
    q = grade
    m = (h - t * (2 * grade**2 - e**2) / (2 * grade)) / grade if e <= grade else \
        (h - t * e**2 / (2 * grade)) / grade
    if m < 0:
        m, q = 0.0, min(grade, math.sqrt(max(grade * h / t + e**2 / 2, 0.0)))
    return t * abs(q - e) / grade, q, m, t * q / grade


def _crest(z0: float, zc: float, z1: float, g0: float, g1: float, grade: float,
           transition: float) -> float:
    """The crest, raised where a ramp starts climbing (ends descending) at a grade whose
    levelling off alone gains more than the climb to ``zc``."""
    top = zc
    for z, e in ((z0, g0), (z1, -g1)):
        if e > 0:
            top = max(top, z + e**2 * transition / (2 * grade))
    return top


def _leg_length(h: float, e: float, grade: float, transition: float) -> float:
    if e == 0.0:
        return float(climb_distance(h, grade, transition))
    a1, _, m, a2 = _leg(h, e, grade, transition)
    return a1 + m + a2


def required_grade(length: float, z0: float, zc: float, z1: float, grade: float,
                   transition: float, g0: float = 0.0, g1: float = 0.0) -> float:
    """The smallest grade ``>= grade`` whose profile fits in ``length`` (bisection);
    ``g0``/``g1``: the grades it starts and ends at."""
    def need(g: float) -> float:
        top = _crest(z0, zc, z1, g0, g1, g, transition)
        return float(_leg_length(top - z0, g0, g, transition)
                     + _leg_length(top - z1, -g1, g, transition))

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
    if h <= FLAT_M:  # none: its vertical curves would be nanometres long, c ~ 1e8
        return []
    t = min(transition, h / grade)
    d = h / grade + t
    g, z0, s0 = float(sign * grade), float(z0), float(s0)
    out = [ElevationPoly(s0, z0, 0.0, g / (2 * t), 0.0)]
    if d - 2 * t > 1e-9:
        out.append(ElevationPoly(s0 + t, z0 + g * t / 2, g, 0.0, 0.0))
    out.append(ElevationPoly(s0 + d - t, z0 + sign * (h - grade * t / 2), g, -g / (2 * t), 0.0))
    return out


def _leg_polys(s0: float, z0: float, h: float, e: float, grade: float,
               transition: float) -> list[ElevationPoly]:
    """The climb of :func:`_leg` from ``(s0, z0)`` (``e``: the grade it starts at)."""
    a1, q, m, a2 = _leg(h, e, grade, transition)
    out, s, z = [], float(s0), float(z0)
    if a1 > 1e-9:
        out.append(ElevationPoly(s, z, float(e), float((q - e) / (2 * a1)), 0.0))
        s, z = s + a1, z + (e + q) / 2 * a1
    if m > 1e-9:
        out.append(ElevationPoly(s, z, float(q), 0.0, 0.0))
        s, z = s + m, z + q * m
    if a2 > 1e-9:
        out.append(ElevationPoly(s, z, float(q), float(-q / (2 * a2)), 0.0))
    return out


def _reversed(polys: list[ElevationPoly], span: float, length: float) -> list[ElevationPoly]:
    """Quadratics of ``u = length - s`` over ``0..span`` as quadratics of ``s``."""
    ends = [p.s_m for p in polys[1:]] + [span]
    out = []
    for p, u1 in zip(polys, ends):
        d = u1 - p.s_m
        out.append(ElevationPoly(float(length - p.s_m - d), p.a + p.b * d + p.c * d**2,
                                 -p.b - 2 * p.c * d, p.c, 0.0))
    return out[::-1]


def elevation_polys(length: float, z0: float, zc: float, z1: float, grade: float,
                    transition: float, g0: float = 0.0, g1: float = 0.0
                    ) -> tuple[ElevationPoly, ...]:
    """OpenDRIVE-style elevation polynomials of the profile, covering ``0..length``;
    ``g0``/``g1``: the grades it starts and ends at (its parents', module doc).

    ``grade`` is raised to :func:`required_grade` when the ramp is too short.
    """
    g = required_grade(length, z0, zc, z1, grade, transition, g0, g1)
    zc = _crest(z0, zc, z1, g0, g1, g, transition)
    hr, hf = abs(zc - z0), abs(zc - z1)
    dr = _leg_length(hr, g0, g, transition)
    df = _leg_length(hf, -g1, g, transition)
    polys = _climb_polys(0.0, z0, hr, np.sign(zc - z0), g, transition) if g0 == 0.0 else \
        _leg_polys(0.0, z0, hr, g0, g, transition)
    if length - df - dr > 1e-9 or not polys:
        polys.append(ElevationPoly(dr, float(zc), 0.0, 0.0, 0.0))
    if g1 == 0.0:
        polys += _climb_polys(length - df, zc, hf, np.sign(z1 - zc), g, transition)
    else:  # the same climb from the end, backwards
        polys += _reversed(_leg_polys(0.0, z1, hf, -g1, g, transition), df, length)
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
