"""Dubins shortest paths (flyover.geometry.dubins): closed forms and an independent search."""

import math

import numpy as np
import pytest
from scipy.optimize import minimize

from flyover.geometry.dubins import shortest, words


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
