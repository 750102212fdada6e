"""A first guess for a ramp's search: the shortest Dubins path between its windows.

Decides where a ramp between two attachment windows would run if it turned only at
its radius target: the stations on its windows and the shortest Dubins path
(:func:`flyover.geometry.dubins.words`) that turns by the ramp's turn, at the radius
that puts its lane centre on the target; reads the ramp's spec only.

A ramp whose windows lie far apart for its turn (a turbine's right turn that merges
beyond the left turn merging before it: 90° at 40 m, then two kilometres along the
road) is an arc and a long straight. Differential evolution started from random
Bézier chains finds such a shape only now and then (its radius comes out 5–25 % off,
or tighter at a point); started from the Dubins path cut into pieces at its arcs'
ends (:func:`path_pieces`, each piece the cubic nearest that part of the path), it
starts next to it. :func:`dubins_guess` gives that decision vector, and the number of
pieces the path needs; the last restart of a ramp that misses its targets starts from it
(:func:`flyover.geometry.build._fit_with_levels`: one member of the first population; the
others are random as before, so obstacles the path runs into are still avoided).

Stubs (a free end) and ``inf`` targets get no guess (``None``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from flyover.geometry.dubins import WORDS, Word, ranks, table, totals
from flyover.geometry.fit import LEAD_MIN_M, RampSpec, bounds

__all__ = ["DubinsGuess", "can_guess", "detour_guesses", "dubins_guess", "path_pieces"]

#: a path segment shorter than this (m) is no piece of its own
MIN_SEGMENT_M = 5.0
#: a segment shorter than 2 % of the path is no piece of its own if it turns less than this
#: (rad): a short arc turning more (a tight one) is
MIN_SEGMENT_TURN = 0.15
#: an arc turning more than this (rad) is cut in two pieces (one cubic is nearly a circular
#: arc up to a quarter turn)
MAX_PIECE_TURN = np.pi / 2
#: the path's lane centre turns this much (relative) wider than the radius target: the
#: cubics nearest its arcs hold them up to 3 % tighter, and the search accepts 2 %
RADIUS_MARGIN = 0.02
#: the most pieces a guess asks for
MAX_PIECES = 4


@dataclass(frozen=True)
class DubinsGuess:
    """A ramp's Dubins path between its windows and the decision vector it gives.

    Attributes
    ----------
    start_s, end_s
        Stations on the start and end windows.
    word
        The path (from the end of the start lead to the start of the end lead).
    pieces
        The Bézier pieces the path needs (:func:`path_pieces`).
    x
        The decision vector of the spec with that many pieces (see
        :func:`flyover.geometry.fit.bounds`), clipped to its bounds.
    """

    start_s: float
    end_s: float
    word: Word
    pieces: int
    x: np.ndarray


def _reference_radius(spec: RampSpec, left: bool) -> float:
    """The reference-line radius that puts the lane centre (``width / 2`` right of it)
    :data:`RADIUS_MARGIN` wider than the radius target on a turn to the left (``left``)
    or right."""
    half, r = 0.5 * spec.width_m, (1.0 + RADIUS_MARGIN) * spec.target_radius_m
    return r - half if left else r + half


def _main_turn_left(seg: np.ndarray, word: str) -> np.ndarray:
    """Whether the longest arc of each path spelled ``word`` (a Dubins word, which has an
    arc; segment lengths ``seg``, ``(..., 3)``) turns left; on a tie, right."""
    most = {c: np.max([seg[..., k] for k, ck in enumerate(word) if ck == c]
                      or [np.full(seg.shape[:-1], -np.inf)], axis=0) for c in "LR"}
    return most["L"] > most["R"]


def _best_word(spec: RampSpec, n: int) -> tuple[float, float, Word] | None:
    """The shortest path turning by the spec's turn between ``n`` × ``n`` stations of its
    windows (from the end of a minimal start lead to the start of a minimal end lead):
    of each pair of stations, the first of its words (:func:`flyover.geometry.dubins.words`'s
    order) that turns so with its longest arc to the side asked for; of those, the shortest
    (on a tie, the first side, then start station, then end station)."""
    a, b = spec.start, spec.end
    lead = LEAD_MIN_M if any(spec.leads()) else 0.0
    sa = np.linspace(a.lo, a.hi, n) if a.hi - a.lo > 1e-6 else np.array([a.lo])
    sb = np.linspace(b.lo, b.hi, n) if b.hi - b.lo > 1e-6 else np.array([b.lo])
    pa, ha, _ = a.at(sa)
    pb, hb, _ = b.at(sb)
    pa = pa + lead * np.stack([np.cos(ha), np.sin(ha)], -1)
    pb = pb - lead * np.stack([np.cos(hb), np.sin(hb)], -1)
    raw = hb[None, :] - ha[:, None]
    tr = spec.turn_rad + ((raw - spec.turn_rad + np.pi) % (2 * np.pi) - np.pi)
    best = None
    for left in (True, False):
        r = _reference_radius(spec, left)
        if r <= 1.0:
            continue
        ok, seg = table(pa[:, None], ha[:, None], pb[None], hb[None], r)
        length = np.empty(ok.shape)
        fits = np.empty(ok.shape, bool)
        for w, word in enumerate(WORDS):
            length[..., w], turn = totals(seg[..., w, :], word, r)
            fits[..., w] = ok[..., w] & ~(np.abs(turn - tr) > 1e-6) & (
                _main_turn_left(seg[..., w, :], word) == left)
        # the first word of each pair (in words' order) that fits
        rank = np.where(fits, ranks(ok, length), len(WORDS))
        w = np.argmin(rank, axis=-1)
        first = np.take_along_axis(length, w[..., None], -1)[..., 0]
        first = np.where(np.min(rank, axis=-1) < len(WORDS), first, np.inf)
        k = int(np.argmin(first))
        i, j = np.unravel_index(k, first.shape)
        if np.isfinite(first[i, j]) and (best is None or first[i, j] < best[2].length):
            ls = seg[i, j, w[i, j]]
            best = (float(sa[i]), float(sb[j]),
                    Word(WORDS[w[i, j]], (float(ls[0]), float(ls[1]), float(ls[2])), float(r)))
    return best


def path_pieces(word: Word, pieces: int | None = None) -> list[tuple[float, float]]:
    """The path cut into Bézier pieces ``(from, to)`` (arc lengths, m): at the ends of
    its segments (one shorter than :data:`MIN_SEGMENT_M`, or than 2 % of the path and
    turning less than :data:`MIN_SEGMENT_TURN`, is joined to its neighbour), an arc over :data:`MAX_PIECE_TURN` in halves, at most
    :data:`MAX_PIECES`; ``pieces``: exactly that many (the shortest joined to a
    neighbour, or the one turning most halved, until there are).

    >>> path_pieces(Word("RSL", (60.0, 1000.0, 4.0), 40.0))
    [(0.0, 60.0), (60.0, 1064.0)]
    """
    parts, done = [], 0.0
    for c, s in zip(word.word, word.lengths):
        if s > 1e-9:
            parts.append([done, done + s, c])
        done += s

    def short(part: list) -> bool:
        a, b, c = part
        slight = c == "S" or (b - a) / word.r < MIN_SEGMENT_TURN
        return b - a < MIN_SEGMENT_M or (slight and b - a < 0.02 * word.length)

    merged: list[list] = []
    for part in parts:
        if merged and short(part):
            merged[-1][1] = part[1]
        elif merged and short(merged[-1]):
            merged[-1][1], merged[-1][2] = part[1], part[2]
        else:
            merged.append(part)
    out = []
    for a, b, c in merged or [[0.0, word.length, "S"]]:
        if c != "S" and (b - a) / word.r > MAX_PIECE_TURN:
            out += [(a, 0.5 * (a + b)), (0.5 * (a + b), b)]
        else:
            out.append((a, b))
    target = pieces or min(len(out), MAX_PIECES)
    while len(out) > target:
        k = min(range(len(out)), key=lambda i: out[i][1] - out[i][0])
        j = k + 1 if k == 0 or (k < len(out) - 1 and out[k + 1][1] - out[k + 1][0]
                                < out[k - 1][1] - out[k - 1][0]) else k - 1
        lo, hi = min(k, j), max(k, j)
        out[lo:hi + 1] = [(out[lo][0], out[hi][1])]
    while len(out) < target:
        k = max(range(len(out)), key=lambda i: (_turn(word, *out[i]), out[i][1] - out[i][0]))
        a, b = out[k]
        out[k:k + 1] = [(a, 0.5 * (a + b)), (0.5 * (a + b), b)]
    return [(float(a), float(b)) for a, b in out]


def _turn(word: Word, a: float, b: float) -> float:
    """The absolute heading change along ``a..b`` of the path."""
    done, out = 0.0, 0.0
    for c, s in zip(word.word, word.lengths):
        lo, hi = max(a, done), min(b, done + s)
        if c != "S" and hi > lo:
            out += (hi - lo) / word.r
        done += s
    return out


#: where along a piece (0-1) the cubic is held near the path (:func:`_handles`)
_HELD = np.linspace(0.0, 1.0, 17)


def _handles(target: np.ndarray, p0: np.ndarray, h_a: float, p3: np.ndarray,
             h_b: float) -> tuple[float, float]:
    """Tangent lengths (m) of the cubic from ``p0`` heading ``h_a`` to ``p3`` heading
    ``h_b`` nearest (least squares) the path's points ``target`` (``(17, 2)``, at
    :data:`_HELD` of a part of it)."""
    t = _HELD
    ta, tb = np.array([np.cos(h_a), np.sin(h_a)]), np.array([np.cos(h_b), np.sin(h_b)])
    b0, b1, b2, b3 = (1 - t) ** 3, 3 * (1 - t) ** 2 * t, 3 * (1 - t) * t ** 2, t ** 3
    base = (b0 + b1)[:, None] * p0 + (b2 + b3)[:, None] * p3
    m = np.stack([(b1[:, None] * ta).ravel(), (-b2[:, None] * tb).ravel()], -1)
    sol, *_ = np.linalg.lstsq(m, (target - base).ravel(), rcond=None)
    return float(sol[0]), float(sol[1])


def can_guess(spec: RampSpec) -> bool:
    """Whether :func:`dubins_guess` looks for a path: a ramp between two windows with a
    finite radius target."""
    return spec.free is None and spec.start is not None and spec.end is not None \
        and math.isfinite(spec.target_radius_m)


def dubins_guess(spec: RampSpec, pieces: int | None = None, n: int = 24) -> DubinsGuess | None:
    """The decision vector of ``spec`` nearest the shortest Dubins path between its
    windows that turns by its turn with its lane centre at its radius target, with
    ``pieces`` Bézier pieces (default: as many as the path needs, :func:`path_pieces`, no
    fewer than the spec has, and more while a joint's heading is beyond what the search
    lets it turn, up to :data:`MAX_PIECES`); ``None`` for a stub, an ``inf`` target or
    when no such path exists."""
    if not can_guess(spec):
        return None
    found = _best_word(spec, n)
    if found is None:
        return None
    sa, sb, word = found
    p = pieces or max(len(path_pieces(word)), spec.pieces)
    while True:
        x, b = _vector(spec, sa, sb, word, path_pieces(word, p))
        inside = bool(np.all((x >= b[:, 0] - 1e-9) & (x <= b[:, 1] + 1e-9)))
        if inside or pieces or p >= MAX_PIECES:
            break
        p += 1
    return DubinsGuess(sa, sb, word, p, np.clip(x, b[:, 0], b[:, 1]))


def _vector(spec: RampSpec, sa: float, sb: float, word: Word,
            parts: list[tuple[float, float]]) -> tuple[np.ndarray, np.ndarray]:
    """The decision vector (not clipped) of ``spec`` with one Bézier piece per part of
    the path from station ``sa`` to station ``sb``, and its bounds."""
    p = len(parts)
    sp = spec if spec.pieces == p else replace(spec, pieces=p)
    lead = LEAD_MIN_M if any(spec.leads()) else 0.0
    pa, ha, _ = spec.start.at(np.array([sa]))
    x0, y0, h0 = pa[0, 0] + lead * np.cos(ha[0]), pa[0, 1] + lead * np.sin(ha[0]), float(ha[0])
    # the joints, then each part's points the cubic is held near, in one pass along the path
    at = np.concatenate([np.array([a for a, _ in parts] + [parts[-1][1]])]
                        + [a + _HELD * (b - a) for a, b in parts])
    poses = word.poses(x0, y0, h0, at)
    joints, held = poses[:p + 1], poses[p + 1:, :2].reshape(p, len(_HELD), 2)
    lam_out, lam_in = np.empty(p), np.empty(p)
    for k in range(p):
        j0, j1 = joints[k], joints[k + 1]
        span = max(float(np.hypot(*(j1[:2] - j0[:2]))), 1e-6)
        out, into = _handles(held[k], j0[:2], j0[2], j1[:2], j1[2])
        lam_out[k], lam_in[k] = out / span, into / span
    x = [sa, sb] + [lead] * sum(sp.leads()) + [lam_out[0], lam_in[-1]]
    c = joints[-1, :2] - joints[0, :2]
    dist = max(float(np.hypot(*c)), 1.0)
    ux, uy = c / dist
    for k in range(1, p):
        f = k / p
        rel = joints[k, :2] - (joints[0, :2] + f * c)
        x += [float(rel @ (ux, uy)) / dist, float(rel @ (-uy, ux)) / dist,
              float(joints[k, 2] - (h0 + word.turn * f)), lam_in[k - 1], lam_out[k]]
    return np.array(x, float), np.array(bounds(sp), float)


#: pieces of a detour start (:func:`detour_guesses`): an S-bend or a turn out and back in
DETOUR_PIECES = 5
#: a detour is at most this many times the length asked for
DETOUR_SLACK = 1.4


def detour_guesses(spec: RampSpec, length_m: float, pieces: int = DETOUR_PIECES,
                   n: int = 9) -> np.ndarray:
    """Decision vectors (``(k, D)``, ``pieces`` Bézier pieces, clipped to the bounds) of
    detours between the windows of ``spec`` from ``length_m`` to :data:`DETOUR_SLACK` times
    it long: two Dubins paths at the lane-centre radius target (the wider side's reference
    radius) through a waypoint, the waypoints on an ``n`` × ``2n - 1`` grid around the
    chord between the stations of the shortest path (from a quarter of it before to a
    quarter past, a chord's length to either side) heading every 45°, the paths by how near
    ``length_m`` they are (for a ramp that must climb further than its shortest path runs:
    :func:`flyover.geometry.build._fit_with_levels`). Empty for a ramp with no guess."""
    dim = len(bounds(replace(spec, pieces=pieces)))
    found = _best_word(spec, 24) if can_guess(spec) else None
    if found is None:
        return np.empty((0, dim))
    sa, sb, _ = found
    lead = LEAD_MIN_M if any(spec.leads()) else 0.0
    pa, ha, _ = spec.start.at(np.array([sa]))
    pb, hb, _ = spec.end.at(np.array([sb]))
    h0, h1 = float(ha[0]), float(hb[0])
    p0 = pa[0] + lead * np.array([np.cos(h0), np.sin(h0)])
    p1 = pb[0] - lead * np.array([np.cos(h1), np.sin(h1)])
    r = max(_reference_radius(spec, True), _reference_radius(spec, False))
    raw = h1 - h0
    tr = spec.turn_rad + ((raw - spec.turn_rad + np.pi) % (2 * np.pi) - np.pi)
    c = p1 - p0
    d = max(float(np.hypot(*c)), 1.0)
    v = np.array([-c[1], c[0]]) / d
    # waypoints (f, g, heading) in the order the paths are listed in
    f = np.linspace(-0.25, 1.25, n)[:, None, None, None]
    g = np.linspace(-1.0, 1.0, 2 * n - 1)[None, :, None, None]
    q = np.broadcast_to(p0 + f * c + g * d * v, (n, 2 * n - 1, 8, 2))
    hq = np.arange(8)[None, None, :] * np.pi / 4
    ok1, seg1 = table(p0, h0, q, hq, r)
    ok2, seg2 = table(q, hq, p1, h1, r)
    # each pair of words through a waypoint (listed as words lists them, shortest first)
    length = np.full(ok1.shape + (6,), np.inf)
    for i, w1 in enumerate(WORDS):
        for j, w2 in enumerate(WORDS):
            ls = np.concatenate([seg1[..., i, :], seg2[..., j, :]], -1)
            total, turn = totals(ls, w1 + w2, r)
            keep = ok1[..., i] & ok2[..., j] & ~(np.abs(turn - tr) > 1e-6) \
                & (length_m <= total) & (total <= DETOUR_SLACK * length_m)
            length[..., i, j] = np.where(keep, total, np.inf)
    len1 = totals(seg1, "SSS", r)[0]
    len2 = totals(seg2, "SSS", r)[0]
    o1 = np.argsort(ranks(ok1, len1), -1)  # the word at each rank
    o2 = np.argsort(ranks(ok2, len2), -1)
    listed = np.take_along_axis(np.take_along_axis(length, o1[..., :, None], -2),
                                o2[..., None, :], -1).reshape(ok1.shape[:-1] + (36,))
    near = np.argmin(listed, -1)  # the shortest through each waypoint (the first listed)
    paths = []
    for at in zip(*np.nonzero(np.isfinite(np.min(listed, -1)))):
        i, j = o1[at][near[at] // 6], o2[at][near[at] % 6]
        paths.append(Word(WORDS[i] + WORDS[j], tuple(float(x) for x in seg1[at][i])
                          + tuple(float(x) for x in seg2[at][j]), r))
    paths.sort(key=lambda w: w.length)
    out = []
    for w in paths:
        x, b = _vector(spec, sa, sb, w, path_pieces(w, pieces))
        out.append(np.clip(x, b[:, 0], b[:, 1]))
    return np.array(out).reshape(len(out), dim)
