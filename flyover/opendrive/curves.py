"""Plan-view curves of the export: straight lines and chains of cubic Béziers.

A cubic Bézier is exactly an OpenDRIVE ``paramPoly3`` with
``pRange="normalized"`` (:func:`bezier_to_parampoly3`); chains are cut at
arc-length positions by de Casteljau subdivision, which is exact.

Readers place road position ``s`` of a normalized ``paramPoly3`` at the curve
parameter ``p = (s - s0) / length`` (SUMO, esmini, CommonRoad's converter, our
reader), not at arc length ``s - s0``, while heights, lane widths and lane
sections are written along arc length. A Bézier piece does not run at uniform
speed (on the catalog the two differed by up to 356 m inside a 2.4 km piece,
median 16 m), so :meth:`BezierChain.part` cuts every piece into parts on which
they differ by at most :data:`S_DRIFT_M` (:func:`s_drift`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import quad

__all__ = ["ParamPoly3", "Line", "BezierChain", "bezier_to_parampoly3", "split_bezier",
           "bezier_length", "s_drift", "uniform_parts", "S_DRIFT_M"]

#: the largest distance along a written ``paramPoly3`` between the point a reader puts at
#: road position ``s`` and the point at arc length ``s``: at the steepest ramp grade (5 %)
#: 1.25 cm of height, and lane sections within a quarter metre of their place. 5 cm made
#: the files ~2.8x larger than one record per piece and the ASAM checker's XSD 1.1 pass,
#: the slowest check, correspondingly slower; 0.25 m needs about sqrt(5) fewer records.
S_DRIFT_M = 0.25
_GL_X, _GL_W = np.polynomial.legendre.leggauss(8)

def _deriv(p: np.ndarray, t: np.ndarray) -> np.ndarray:
    t = np.asarray(t, dtype=float)[:, None]
    return 3 * ((1 - t) ** 2 * (p[1] - p[0]) + 2 * (1 - t) * t * (p[2] - p[1]) + t ** 2 * (p[3] - p[2]))


def _point(p: np.ndarray, t: np.ndarray) -> np.ndarray:
    t = np.asarray(t, dtype=float)[:, None]
    return (1 - t) ** 3 * p[0] + 3 * (1 - t) ** 2 * t * p[1] + 3 * (1 - t) * t ** 2 * p[2] + t ** 3 * p[3]


def _gl_length(b, c, d, t0: float, t1: float, intervals: int) -> float:
    """Composite 8-point Gauss-Legendre arc length of the speed ``|b + 2ct + 3dt²|``."""
    edges = np.linspace(t0, t1, intervals + 1)
    half = 0.5 * (edges[1:] - edges[:-1])
    t = (0.5 * (edges[1:] + edges[:-1]))[:, None] + half[:, None] * _GL_X
    v = b + t[..., None] * (2 * c + 3 * t[..., None] * d)
    return float((np.hypot(v[..., 0], v[..., 1]) @ _GL_W) @ half)


def bezier_length(p: np.ndarray, t0: float = 0.0, t1: float = 1.0) -> float:
    """Arc length of a cubic Bézier between parameters ``t0`` and ``t1``; better than
    1e-9 m.

    Composite Gauss-Legendre rules of 16 and 32 intervals; where they differ by more than
    1e-10 m (the speed comes close to zero on a tight piece, where fixed-order rules lose
    millimetres) adaptive quadrature instead.
    """
    p = np.asarray(p, dtype=float)
    b = 3 * (p[1] - p[0])
    c = 3 * (p[0] - 2 * p[1] + p[2])
    d = -p[0] + 3 * p[1] - 3 * p[2] + p[3]
    coarse, fine = _gl_length(b, c, d, t0, t1, 16), _gl_length(b, c, d, t0, t1, 32)
    if abs(fine - coarse) <= 1e-10:
        return fine

    def speed(t: float) -> float:
        v = b + t * (2 * c + 3 * t * d)
        return math.hypot(v[0], v[1])

    return float(quad(speed, t0, t1, limit=200, epsabs=1e-9, epsrel=1e-12)[0])


def s_drift(p: np.ndarray, intervals: int = 32) -> float:
    """The largest ``|arc length(t) - t·length|`` of a cubic Bézier, ``t`` in [0, 1]: how
    far a reader's point at road position ``s`` (``p = s/length``) is from arc length ``s``.

    >>> round(s_drift(np.array([[0, 0], [1, 0], [2, 0], [3, 0.]])), 12)
    0.0
    >>> round(s_drift(np.array([[0, 0], [0.1, 0], [0.2, 0], [3, 0.]])), 3)  # slow, then fast
    1.038
    """
    p = np.asarray(p, dtype=float)
    t = np.linspace(0.0, 1.0, intervals + 1)
    a, b = t[:-1, None], t[1:, None]
    nodes = 0.5 * (a + b) + 0.5 * (b - a) * _GL_X
    speed = np.linalg.norm(_deriv(p, nodes.ravel()), axis=1).reshape(nodes.shape)
    arc = np.concatenate([[0.0], np.cumsum(0.5 * (b - a)[:, 0] * (speed @ _GL_W))])
    return float(np.max(np.abs(arc - t * arc[-1])))


def uniform_parts(p: np.ndarray, drift_m: float = S_DRIFT_M) -> list[np.ndarray]:
    """``p`` cut (exactly, by de Casteljau) into parts whose :func:`s_drift` is at most
    ``drift_m``: equal steps of the parameter, as many as the drift (which shrinks with the
    square of a part's share) asks for, and any part still over halved again.

    >>> q = np.array([[0, 0], [0.1, 0], [0.2, 0], [3, 0.]])
    >>> parts = uniform_parts(q, 0.01)
    >>> len(parts), max(s_drift(x) for x in parts) <= 0.01
    (15, True)
    """
    p = np.asarray(p, dtype=float)
    d = s_drift(p)
    if d <= drift_m:
        return [p]
    n = max(2, math.ceil(math.sqrt(d / drift_m)))
    out: list[np.ndarray] = []
    for k in range(n):
        out += uniform_parts(split_bezier(p, k / n, (k + 1) / n), drift_m)
    return out


def split_bezier(p: np.ndarray, t0: float, t1: float) -> np.ndarray:
    """The control points of the part ``[t0, t1]`` of a cubic Bézier (exact)."""
    def left(q, t):
        a = q[:-1] * (1 - t) + q[1:] * t
        b = a[:-1] * (1 - t) + a[1:] * t
        c = b[:-1] * (1 - t) + b[1:] * t
        return np.array([q[0], a[0], b[0], c[0]]), np.array([c[0], b[1], a[2], q[3]])
    q = np.asarray(p, dtype=float)
    if t1 < 1.0:
        q = left(q, t1)[0]
    if t0 > 0.0:
        q = left(q, t0 / t1)[1]
    return q


@dataclass(frozen=True)
class ParamPoly3:
    """An OpenDRIVE ``<paramPoly3 pRange="normalized">`` record."""

    x: float
    y: float
    hdg: float
    length: float
    u: tuple[float, float, float, float]
    v: tuple[float, float, float, float]


@dataclass(frozen=True)
class Line:
    """An OpenDRIVE ``<line>`` record."""

    x: float
    y: float
    hdg: float
    length: float


def bezier_to_parampoly3(p: np.ndarray) -> ParamPoly3:
    """The exact ``paramPoly3`` (normalized) of a cubic Bézier.

    >>> pp = bezier_to_parampoly3(np.array([[0, 0], [1, 0], [2, 0], [3, 0.]]))
    >>> round(pp.length, 9), pp.u, pp.v
    (3.0, (0.0, 3.0, 0.0, 0.0), (0.0, 0.0, 0.0, 0.0))
    """
    p = np.asarray(p, dtype=float)
    b = 3 * (p[1] - p[0])
    c = 3 * (p[0] - 2 * p[1] + p[2])
    d = -p[0] + 3 * p[1] - 3 * p[2] + p[3]
    tan = b if np.linalg.norm(b) > 1e-9 else (p[3] - p[0])
    hdg = math.atan2(tan[1], tan[0])
    cs, sn = math.cos(hdg), math.sin(hdg)
    rot = lambda q: (cs * q[0] + sn * q[1], -sn * q[0] + cs * q[1])  # noqa: E731
    (bu, bv), (cu, cv), (du, dv) = rot(b), rot(c), rot(d)
    f = float
    return ParamPoly3(f(p[0][0]), f(p[0][1]), hdg, f(bezier_length(p)),
                      (0.0, f(bu), f(cu), f(du)), (0.0, 0.0 if abs(bv) < 1e-9 else f(bv), f(cv), f(dv)))


class BezierChain:
    """A G1 chain of cubic Bézier pieces with arc-length access."""

    def __init__(self, pieces: list[np.ndarray]):
        self.pieces = [np.asarray(p, dtype=float) for p in pieces]
        self.lengths = np.array([bezier_length(p) for p in self.pieces])
        self.starts = np.concatenate([[0.0], np.cumsum(self.lengths)])
        self.length = float(self.starts[-1])

    def locate(self, s: float) -> tuple[int, float]:
        """(piece index, Bézier parameter) of arc length ``s``."""
        s = min(max(s, 0.0), self.length)
        i = int(np.clip(np.searchsorted(self.starts, s, side="right") - 1, 0, len(self.pieces) - 1))
        p, target = self.pieces[i], s - self.starts[i]
        if target <= 1e-9:
            return i, 0.0
        if target >= self.lengths[i] - 1e-9:
            return i, 1.0
        t = target / self.lengths[i]
        for _ in range(30):
            err = bezier_length(p, 0.0, t) - target
            t = float(np.clip(t - err / np.linalg.norm(_deriv(p, np.array([t]))[0]), 0.0, 1.0))
            if abs(err) < 1e-10:
                break
        return i, t

    def pose(self, s: float) -> tuple[float, float, float]:
        """(x, y, heading) at arc length ``s``."""
        i, t = self.locate(s)
        xy = _point(self.pieces[i], np.array([t]))[0]
        d = _deriv(self.pieces[i], np.array([t]))[0]
        return float(xy[0]), float(xy[1]), math.atan2(d[1], d[0])

    def part(self, s0: float, s1: float, drift_m: float = S_DRIFT_M) -> list[ParamPoly3]:
        """``paramPoly3`` records of the chain between arc lengths ``s0`` and ``s1``, each
        within ``drift_m`` of arc length at every road position (:func:`uniform_parts`)."""
        (i0, t0), (i1, t1) = self.locate(s0), self.locate(s1)
        if t0 >= 1.0 - 1e-12 and i0 < len(self.pieces) - 1:
            i0, t0 = i0 + 1, 0.0
        if t1 <= 1e-12 and i1 > 0:
            i1, t1 = i1 - 1, 1.0
        out = []
        for i in range(i0, i1 + 1):
            a = t0 if i == i0 else 0.0
            b = t1 if i == i1 else 1.0
            if b - a <= 1e-12:
                continue
            q = split_bezier(self.pieces[i], a, b)
            if bezier_length(q) > 1e-6:
                out += [bezier_to_parampoly3(r) for r in uniform_parts(q, drift_m)]
        return out
