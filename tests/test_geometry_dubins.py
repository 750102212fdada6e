"""Dubins shortest paths (flyover.geometry.dubins): closed forms and an independent search."""

import math

import numpy as np
import pytest
from scipy.optimize import minimize

from flyover.geometry.dubins import WORDS, ranks, shortest, table, totals, words


def _drive(p0, h0, r, word, lengths):
    """End pose after driving arcs (L/R, radius r) and straights (S) of these lengths."""
    p, h = np.array(p0, float), float(h0)
    for kind, ell in zip(word, lengths):
        if kind == "S":
            p = p + ell * np.array([math.cos(h), math.sin(h)])
            continue
        s = 1.0 if kind == "L" else -1.0
        c = p + r * s * np.array([-math.sin(h), math.cos(h)])
        h += s * ell / r
        p = c - r * s * np.array([-math.sin(h), math.cos(h)])
    return p, h


def _search(p0, h0, p1, h1, r, rng):
    """Shortest word found by a numerical search over the six words' segment lengths."""
    best = math.inf
    for word in ("LSL", "RSR", "LSR", "RSL", "RLR", "LRL"):
        for _ in range(12):
            def miss(x, word=word):
                p, h = _drive(p0, h0, r, word, np.abs(x))
                dh = math.remainder(h - h1, 2 * math.pi)
                return float(np.sum((p - p1) ** 2) + (r * dh) ** 2)
            res = minimize(miss, rng.uniform(0, 6 * r, 3), method="Nelder-Mead",
                           options={"xatol": 1e-9, "fatol": 1e-12, "maxiter": 4000})
            if res.fun < 1e-6:
                best = min(best, float(np.abs(res.x).sum()))
    return best


@pytest.mark.parametrize("p1, h1, expected", [
    ((10.0, 0.0), 0.0, 10.0),                       # straight on
    ((10.0, 10.0), math.pi / 2, math.pi / 2 * 10),  # quarter circle left
    ((10.0, -10.0), -math.pi / 2, math.pi / 2 * 10),  # quarter circle right
    ((0.0, 20.0), math.pi, math.pi * 10),            # U-turn
    ((0.0, 0.0), 0.0, 0.0),                          # the same pose
])
def test_closed_forms(p1, h1, expected):
    got = float(shortest(np.zeros(2), 0.0, np.array(p1), h1, 10.0))
    assert got == pytest.approx(expected, abs=1e-9)


def test_matches_a_numerical_search():
    rng = np.random.default_rng(3)
    for _ in range(6):
        p0, p1 = rng.uniform(-50, 50, 2), rng.uniform(-50, 50, 2)
        h0, h1 = rng.uniform(-3, 3, 2)
        got = float(shortest(p0, h0, p1, h1, 10.0))
        assert got == pytest.approx(_search(p0, h0, p1, h1, 10.0, rng), abs=0.05)
        assert got >= np.hypot(*(p1 - p0)) - 1e-9  # never below the straight line


def test_broadcasts_over_windows():
    pa = np.stack([np.linspace(0, 100, 5), np.zeros(5)], axis=-1)
    pb = np.array([[300.0, 50.0], [300.0, 80.0]])
    got = shortest(pa[:, None, :], 0.0, pb[None, :, :], 0.0, 50.0)
    assert got.shape == (5, 2)
    one = float(shortest(pa[3], 0.0, pb[1], 0.0, 50.0))
    assert got[3, 1] == pytest.approx(one)


@pytest.mark.parametrize("seed", range(4))
def test_words_drive_to_the_end_pose_and_the_first_is_the_shortest(seed):
    """Every word :func:`words` gives, driven from the start pose, ends at the end pose;
    the first is as long as :func:`shortest`."""
    rng = np.random.default_rng(seed)
    for _ in range(20):
        p0, p1 = rng.uniform(-80, 80, 2), rng.uniform(-80, 80, 2)
        h0, h1 = rng.uniform(-3, 3, 2)
        r = float(rng.uniform(5, 40))
        ws = words(p0, h0, p1, h1, r)
        assert ws and ws[0].length == pytest.approx(float(shortest(p0, h0, p1, h1, r)))
        for w in ws:
            p, h = _drive(p0, h0, r, w.word, w.lengths)
            assert np.hypot(*(p - p1)) < 1e-6 * max(1.0, w.length)
            assert abs(math.remainder(h - h1, 2 * math.pi)) < 1e-6
            assert h - h0 == pytest.approx(w.turn)
            x, y, hh = w.poses(p0[0], p0[1], h0, np.array([w.length]))[0]
            assert np.hypot(x - p1[0], y - p1[1]) < 1e-6 * max(1.0, w.length)


def _poses_one_by_one(w, x, y, h, at):
    """:meth:`Word.poses` as it was written before it took many arc lengths at once."""
    out = np.empty((len(at), 3))
    ends = np.cumsum(w.lengths)
    for i, s in enumerate(np.asarray(at, float)):
        px, py, ph, done = x, y, h, 0.0
        for c, seg, end in zip(w.word, w.lengths, ends):
            ds = min(max(s - done, 0.0), seg)
            if c == "S":
                px, py = px + ds * np.cos(ph), py + ds * np.sin(ph)
            else:
                k = 1.0 if c == "L" else -1.0
                nh = ph + k * ds / w.r
                px += k * w.r * (np.sin(nh) - np.sin(ph))
                py -= k * w.r * (np.cos(nh) - np.cos(ph))
                ph = nh
            done = end
            if s <= end:
                break
        out[i] = px, py, ph
    return out


@pytest.mark.parametrize("seed", range(3))
def test_table_is_words_float_for_float(seed):
    """:func:`table` over many pose pairs at once gives the words :func:`words` gives one
    pair at a time, to the bit: which exist, their lengths, :func:`totals` their length and
    turn, :func:`ranks` their order; :meth:`Word.poses` at many arc lengths at once the
    poses it gave one by one (the detour and Dubins guesses are built so, byte for byte)."""
    rng = np.random.default_rng(seed)
    p0, h0 = rng.uniform(-80, 80, (30, 2)), rng.uniform(-3, 3, 30)
    p1, h1 = rng.uniform(-80, 80, (30, 2)), rng.uniform(-3, 3, 30)
    r = float(rng.uniform(5, 40))
    ok, lengths = table(p0, h0, p1, h1, r)
    for i in range(30):
        ws = words(p0[i], h0[i], p1[i], h1[i], r)
        assert [w.word for w in ws] == [WORDS[k] for k in np.argsort(ranks(ok[i], totals(
            lengths[i], "SSS", r)[0]))[:int(ok[i].sum())]]
        for w in ws:
            k = WORDS.index(w.word)
            assert ok[i, k] and tuple(float(x) for x in lengths[i, k]) == w.lengths
            length, turn = totals(lengths[i, k], w.word, r)
            assert (float(length), float(turn)) == (w.length, w.turn)
            at = np.linspace(-5.0, w.length + 5.0, 23)
            assert np.array_equal(w.poses(p0[i, 0], p0[i, 1], h0[i], at),
                                  _poses_one_by_one(w, p0[i, 0], p0[i, 1], h0[i], at))
