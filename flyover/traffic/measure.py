"""The stable window of a run: where entering and leaving flows balance, and its throughput.

A run starts empty: vehicles enter, and the first ones leave only after
crossing the interchange, so for a while fewer leave than enter. The number
of vehicles in the network, ``N = cumsum(entered - left)``, then levels off.
The **stable window** begins at the first interval from which ``N`` stays
within three standard deviations of its level over the second half of the
run (at least Poisson's, the square root of the level: arrivals are random);
the **stable throughput** is the
vehicles leaving per hour over that window. The window is **balanced** when
it is at least ``min_stable_s`` long and ``N`` changed over it by at most
``balance_tolerance`` of the vehicles that entered in it: a network still
filling up (a growing jam) is not.

Example
-------
>>> import numpy as np
>>> entered = np.full(60, 30); left = np.r_[np.zeros(8, int), np.full(52, 30)]
>>> w = stable_window(entered, left, 30.0)
>>> w.stable_from_s, w.throughput_veh_h, w.balanced
(240.0, 3600.0, True)
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["StableWindow", "stable_window"]


@dataclass(frozen=True)
class StableWindow:
    """The stable part of one run's series.

    Attributes
    ----------
    start
        Index of the first interval of the window.
    stable_from_s
        Time the window starts (``start * interval_s``).
    throughput_veh_h
        Vehicles leaving per hour over the window.
    entering_veh_h
        Vehicles entering per hour over the window.
    balanced
        The window is long enough and the network neither fills nor empties in it.
    per_interval_veh_h
        Each interval's leaving flow in the window (vehicles per hour).
    """

    start: int
    stable_from_s: float
    throughput_veh_h: float
    entering_veh_h: float
    balanced: bool
    per_interval_veh_h: np.ndarray


def stable_window(entered, left, interval_s: float, *, min_stable_s: float = 500.0,
                  balance_tolerance: float = 0.05, noise_veh: float = 6.0) -> StableWindow:
    """Detect the stable window of a series of vehicles entering/leaving per interval.

    ``noise_veh`` is the smallest half-width of the band (vehicles).
    """
    e = np.asarray(entered, dtype=float)
    lv = np.asarray(left, dtype=float)
    n_int = len(e)
    if n_int == 0 or len(lv) != n_int:
        raise ValueError("entered and left must be equally long and not empty")
    N = np.cumsum(e - lv)
    ref = N[n_int // 2:]
    level = float(ref.mean())
    # in a stationary network N varies about its level with (at least) Poisson spread
    tol = 3.0 * max(float(ref.std()), math.sqrt(max(level, 0.0)), noise_veh / 3.0)
    lo, hi = level - tol, level + tol
    at = np.r_[0.0, N]  # vehicles in the network at the start of each interval (and the end)
    outside = np.flatnonzero((at < lo) | (at > hi))  # interval i starts, i - 1 ends, outside
    start = int(outside[-1] + 1) if len(outside) else 0
    # ... and from where it first comes within one deviation of the level (the end of filling)
    near = np.flatnonzero(np.abs(at[start:n_int // 2 + 1] - level) <= tol / 3.0)
    start += int(near[0]) if len(near) else 0
    start = min(start, n_int // 2)  # the band is the second half's: it starts there at latest
    w_e, w_l = e[start:], lv[start:]
    span_h = len(w_l) * interval_s / 3600.0
    n_before = N[start - 1] if start > 0 else 0.0
    change = abs(N[-1] - n_before)
    balanced = (len(w_l) * interval_s >= min_stable_s - 1e-9
                and change <= max(noise_veh + tol, balance_tolerance * w_e.sum()))
    return StableWindow(start, start * float(interval_s), float(w_l.sum() / span_h),
                        float(w_e.sum() / span_h), bool(balanced),
                        w_l * 3600.0 / interval_s)
