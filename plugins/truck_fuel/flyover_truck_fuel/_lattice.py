"""Compiled (numba) evaluation of the planner's lattice: the same arithmetic as
:meth:`flyover_truck_fuel.planner.LatticePlanner.plan_numpy`, without temporaries.

Returns the index of the best candidate (lateral offset ``o``, longitudinal
``l``), whether it keeps every limit, its violation and its peak lateral
acceleration.
"""

from __future__ import annotations


import numpy as np
from numba import njit

__all__ = ["best_candidate"]


@njit(cache=True, inline="always")
def _interp(xs, col, x):
    n = xs.shape[0]
    if x <= xs[0]:
        return col[0]
    if x >= xs[n - 1]:
        return col[n - 1]
    i = np.searchsorted(xs, x) - 1
    f = (x - xs[i]) / (xs[i + 1] - xs[i])
    return col[i] * (1.0 - f) + col[i + 1] * f


@njit(cache=True)
def best_candidate(s0, d0, d1, d2, v0, a0, vs, tl, offsets, tau, rs, kap_col, env_col,
                   dpref_col, a_lat_max, k_max, acc_max, dec_max, v_pref,
                   w_dev, w_jlat, w_jlon, w_v):  # pragma: no cover - compiled
    n_l, n_o, n_m = vs.shape[0], offsets.shape[0], tau.shape[0]
    sig = np.empty(n_m)
    vel = np.empty(n_m)
    kap = np.empty(n_m)
    dpr = np.empty(n_m)
    best_o, best_l, best_cost = -1, -1, np.inf
    any_o, any_l, any_score, any_viol = 0, 0, np.inf, np.inf
    best_alat, any_alat = 0.0, 0.0
    a2 = 0.5 * d2
    for l in range(n_l):
        T = tl[l]
        dv = vs[l] - v0 - a0 * T
        c1, c2 = v0, 0.5 * a0
        c3 = dv / T**2 + a0 / (3.0 * T)
        c4 = -a0 / (4.0 * T**2) - dv / (2.0 * T**3)
        acc_hi, dec_hi, env_hi, neg, jerk2, dv2 = 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
        for m in range(n_m):
            t = T * tau[m]
            sig[m] = t * (c1 + t * (c2 + t * (c3 + t * c4)))
            v = c1 + t * (2 * c2 + t * (3 * c3 + t * 4 * c4))
            vel[m] = v
            acc = 2 * c2 + t * (6 * c3 + t * 12 * c4)
            jerk = 6 * c3 + 24 * c4 * t
            st = s0 + sig[m]
            kap[m] = _interp(rs, kap_col, st)
            dpr[m] = _interp(rs, dpref_col, st)
            acc_hi = max(acc_hi, acc - acc_max * 1.05)
            dec_hi = max(dec_hi, -acc - dec_max * 1.05)
            env_hi = max(env_hi, v - _interp(rs, env_col, st) - 0.05)
            neg = max(neg, -v)
            jerk2 += jerk * jerk
            dv2 += (v - v_pref) ** 2
        length = sig[n_m - 1]
        lon_viol = acc_hi + dec_hi + env_hi + neg + (10.0 if length <= 1.0 else 0.0)
        lon_cost = w_jlon * jerk2 / n_m + w_v * dv2 / n_m
        S = max(length, 1.0)
        d_base = _interp(rs, dpref_col, s0 + S)
        for o in range(n_o):
            h = d_base + offsets[o] - d0 - d1 * S - a2 * S * S
            vv = -d1 - 2 * a2 * S
            w = -2 * a2
            q3 = (10 * h - 4 * vv * S + 0.5 * w * S * S) / S**3
            q4 = (-15 * h + 7 * vv * S - w * S * S) / S**4
            q5 = (6 * h - 3 * vv * S + 0.5 * w * S * S) / S**5
            alat_hi, k_hi, dev, jl = 0.0, 0.0, 0.0, 0.0
            for m in range(n_m):
                x = sig[m]
                d = d0 + x * (d1 + x * (a2 + x * (q3 + x * (q4 + x * q5))))
                dd2 = 2 * a2 + x * (6 * q3 + x * (12 * q4 + x * 20 * q5))
                dd3 = 6 * q3 + x * (24 * q4 + x * 60 * q5)
                kp = kap[m] / (1.0 - kap[m] * d) + dd2
                alat_hi = max(alat_hi, abs(vel[m] ** 2 * kp))
                k_hi = max(k_hi, abs(kp))
                dev += (d - dpr[m]) ** 2
                jl += (vel[m] ** 3 * dd3) ** 2
            viol = (max(alat_hi - a_lat_max, 0.0) / a_lat_max + max(k_hi - k_max, 0.0) / k_max
                    + lon_viol)
            cost = w_dev * dev / n_m + w_jlat * jl / n_m + lon_cost
            if viol <= 0.0:
                if cost < best_cost:
                    best_o, best_l, best_cost, best_alat = o, l, cost, alat_hi
            else:
                score = viol + 1e-6 * cost
                if score < any_score:
                    any_o, any_l, any_score, any_viol, any_alat = o, l, score, viol, alat_hi
    if best_o >= 0:
        return best_o, best_l, True, 0.0, best_alat
    return any_o, any_l, False, any_viol, any_alat
