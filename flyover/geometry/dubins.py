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

from dataclasses import dataclass

import numpy as np

__all__ = ["shortest", "Word", "words"]

_TWO_PI = 2.0 * np.pi


def _mod(a: np.ndarray) -> np.ndarray:
    return np.mod(a, _TWO_PI)


def _take(best: np.ndarray, valid: np.ndarray, length: np.ndarray) -> np.ndarray:
    return np.fmin(best, np.where(valid, length, np.inf))


def _segments(p0, h0, p1, h1, r: float) -> list[tuple[str, np.ndarray, np.ndarray, np.ndarray,
                                                    np.ndarray]]:
    """The six Dubins words from ``p0`` heading ``h0`` to ``p1`` heading ``h1`` at radius
    ``r`` (broadcast): ``(word, exists, t, p, q)``, the three segments' lengths in units
    of ``r`` (meaningless where the word does not exist)."""
    p0, p1 = np.asarray(p0, float), np.asarray(p1, float)
    dx, dy = p1[..., 0] - p0[..., 0], p1[..., 1] - p0[..., 1]
    d = np.hypot(dx, dy) / r
    theta = np.arctan2(dy, dx)
    a = _mod(np.asarray(h0, float) - theta)
    b = _mod(np.asarray(h1, float) - theta)
    sa, ca, sb, cb = np.sin(a), np.cos(a), np.sin(b), np.cos(b)
    cab = np.cos(a - b)
    out = []
    with np.errstate(invalid="ignore"):
        p2 = 2 + d * d - 2 * cab + 2 * d * (sa - sb)
        k = np.arctan2(cb - ca, d + sa - sb)
        out.append(("LSL", p2 >= -1e-9, _mod(k - a), np.sqrt(np.maximum(p2, 0)), _mod(b - k)))
        p2 = 2 + d * d - 2 * cab + 2 * d * (sb - sa)
        k = np.arctan2(ca - cb, d - sa + sb)
        out.append(("RSR", p2 >= -1e-9, _mod(a - k), np.sqrt(np.maximum(p2, 0)), _mod(k - b)))
        p2 = -2 + d * d + 2 * cab + 2 * d * (sa + sb)
        pp = np.sqrt(np.maximum(p2, 0))
        k = np.arctan2(-ca - cb, d + sa + sb) - np.arctan2(-2.0, pp)
        out.append(("LSR", p2 >= -1e-9, _mod(k - a), pp, _mod(k - b)))
        p2 = d * d - 2 + 2 * cab - 2 * d * (sa + sb)
        pp = np.sqrt(np.maximum(p2, 0))
        k = np.arctan2(ca + cb, d - sa - sb) - np.arctan2(2.0, pp)
        out.append(("RSL", p2 >= -1e-9, _mod(a - k), pp, _mod(b - k)))
        c = (6.0 - d * d + 2 * cab + 2 * d * (sa - sb)) / 8.0
        pp = _mod(_TWO_PI - np.arccos(np.clip(c, -1, 1)))
        t = _mod(a - np.arctan2(ca - cb, d - sa + sb) + pp / 2.0)
        out.append(("RLR", np.abs(c) <= 1 + 1e-9, t, pp, _mod(a - b - t + pp)))
        c = (6.0 - d * d + 2 * cab + 2 * d * (sb - sa)) / 8.0
        pp = _mod(_TWO_PI - np.arccos(np.clip(c, -1, 1)))
        t = _mod(-a - np.arctan2(ca - cb, d + sa - sb) + pp / 2.0)
        out.append(("LRL", np.abs(c) <= 1 + 1e-9, t, pp, _mod(b - a - t + pp)))
    return out


def shortest(p0: np.ndarray, h0, p1: np.ndarray, h1, r: float) -> np.ndarray:
    """Length of the shortest path of curvature at most ``1 / r`` from ``p0`` (``(..., 2)``)
    heading ``h0`` to ``p1`` heading ``h1`` (broadcast); ``inf`` where no word exists
    (never for all six together)."""
    segs = _segments(p0, h0, p1, h1, r)
    best = np.full(np.broadcast(*segs[0][1:]).shape, np.inf)
    for _, valid, t, p, q in segs:
        best = _take(best, valid, t + p + q)
    return best * r


@dataclass(frozen=True)
class Word:
    """One Dubins path: its word (``"LSR"``…) and the length (m) of each of its three
    segments, from a start pose at radius ``r``."""

    word: str
    lengths: tuple[float, float, float]
    r: float

    @property
    def length(self) -> float:
        return float(sum(self.lengths))

    @property
    def turn(self) -> float:
        """The heading change (rad) along the path (left positive)."""
        sign = {"L": 1.0, "R": -1.0, "S": 0.0}
        return float(sum(sign[c] * s / self.r for c, s in zip(self.word, self.lengths)))

    def poses(self, x: float, y: float, h: float, at: np.ndarray) -> np.ndarray:
        """Poses ``(N, 3)`` (x, y, heading, unwrapped) at arc lengths ``at`` along the path
        from ``(x, y, h)``."""
        s = np.asarray(at, float)
        px, py, ph = (np.full(len(s), v, float) for v in (x, y, h))
        going = np.ones(len(s), bool)  # not yet at its arc length
        done = 0.0
        for c, seg, end in zip(self.word, self.lengths, np.cumsum(self.lengths)):
            ds = np.minimum(np.maximum(s - done, 0.0), seg)
            if c == "S":
                nx, ny, nh = px + ds * np.cos(ph), py + ds * np.sin(ph), ph
            else:
                k = 1.0 if c == "L" else -1.0
                nh = ph + k * ds / self.r
                nx = px + k * self.r * (np.sin(nh) - np.sin(ph))
                ny = py - k * self.r * (np.cos(nh) - np.cos(ph))
            px, py, ph = np.where(going, nx, px), np.where(going, ny, py), np.where(going, nh, ph)
            done = end
            going &= ~(s <= end)
        return np.stack([px, py, ph], -1)


def words(p0, h0: float, p1, h1: float, r: float) -> list[Word]:
    """Every Dubins word that exists from ``p0`` heading ``h0`` to ``p1`` heading ``h1`` at
    radius ``r`` (scalars; the six of :func:`shortest`, those without a solution left out),
    shortest first.

    >>> ws = words(np.zeros(2), 0.0, np.array([100.0, 20.0]), 0.0, 10.0)
    >>> [(w.word, round(w.length, 1), round(w.turn, 2)) for w in ws[:2]]
    [('LSR', 102.0, 0.0), ('RSR', 164.8, -6.28)]
    """
    out = [(w, t, p, q) for w, ok, t, p, q in _segments(p0, h0, p1, h1, r) if ok]
    ws = [Word(w, (float(t) * r, float(p) * r, float(q) * r), float(r)) for w, t, p, q in out]
    return sorted(ws, key=lambda w: w.length)


#: the six words in :func:`_segments`'s order
WORDS = ("LSL", "RSR", "LSR", "RSL", "RLR", "LRL")


def table(p0, h0, p1, h1, r: float) -> tuple[np.ndarray, np.ndarray]:
    """The six words of :func:`words` for many pose pairs at once (broadcast): whether each
    exists ``(..., 6)`` and its three segments' lengths in metres ``(..., 6, 3)``, in
    :data:`WORDS`'s order (as :func:`words` computes them, float for float)."""
    segs = _segments(p0, h0, p1, h1, r)
    shape = np.broadcast(*[a for s in segs for a in s[1:]]).shape
    ok = np.stack([np.broadcast_to(s[1], shape) for s in segs], -1)
    lengths = np.stack([np.stack([np.broadcast_to(a * r, shape) for a in s[2:]], -1)
                        for s in segs], -2)
    return ok, lengths


def totals(lengths: np.ndarray, word: str, r: float) -> tuple[np.ndarray, np.ndarray]:
    """:attr:`Word.length` and :attr:`Word.turn` of paths spelled ``word`` with segment
    lengths ``lengths`` (``(..., len(word))``), summed in :class:`Word`'s order."""
    length = np.zeros(lengths.shape[:-1])
    turn = np.zeros(lengths.shape[:-1])
    sign = {"L": 1.0, "R": -1.0, "S": 0.0}
    for k, c in enumerate(word):
        length = length + lengths[..., k]
        turn = turn + sign[c] * lengths[..., k] / r
    return length, turn


def ranks(ok: np.ndarray, length: np.ndarray) -> np.ndarray:
    """The order :func:`words` lists the words in (shortest first, ties in :data:`WORDS`'s
    order; one that does not exist last): each word's rank ``(..., 6)``."""
    order = np.argsort(np.where(ok, length, np.inf), axis=-1, kind="stable")
    out = np.empty_like(order)
    np.put_along_axis(out, order, np.arange(order.shape[-1]), axis=-1)
    return out
