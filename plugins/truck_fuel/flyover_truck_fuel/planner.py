"""Lattice planner in the road-aligned frame (McNaughton et al., ICRA 2011; Werling et al., ICRA 2010).

At every re-planning instant a lattice of end states is sampled — lateral
offset ``d_T`` (around the preferred lane position), end speed ``v_T`` and
horizon ``T`` — and each is connected to the current state by polynomials:

* longitudinally a quartic ``s(t)`` (velocity keeping: start position,
  speed and acceleration, end speed and zero end acceleration);
* laterally a quintic ``d(σ)`` over the distance ``σ`` that quartic covers
  (start offset, slope and second derivative, end offset, zero end slope and
  second derivative).

Candidates that break a hard limit anywhere on 16 samples are discarded:
lateral acceleration ``v²·κ_path`` (``κ_path = κ/(1 − κ·d) + d''``),
path curvature (the truck's turning radius), longitudinal acceleration and
deceleration, and a speed envelope — the lateral-acceleration speed of the
route's curvature, made reachable by a backward braking pass, so that a
short horizon does not run into a curve it cannot brake for. Among the rest
the cost ``w_dev·mean((d − d_pref)²) + w_jlat·mean((v³·d''')²) +
w_jlon·mean(s⃛²) + w_v·mean((v − v_pref)²)`` is minimal. All candidates are
evaluated at once with numpy. If none is feasible the least-violating one is
taken and the plan is flagged.

Example
-------
>>> from flyover_truck_fuel.params import settings
>>> from flyover_truck_fuel.route import straight_route
>>> st = settings({})
>>> pl = LatticePlanner(straight_route(300.0, 0.0, st.route), st.planner, st.truck)
>>> plan = pl.plan(0.0, 0.0, 0.0, 0.0, 10.0, 0.0)
>>> plan.feasible, round(plan.end_speed, 1), round(plan.end_offset, 2)
(True, 10.0, 0.0)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flyover_truck_fuel.params import PlannerParams, TruckParams
from flyover_truck_fuel.route import Route

__all__ = ["Plan", "LatticePlanner", "speed_envelope", "quintic", "quartic_speed"]

_SAMPLES = 16


@dataclass(frozen=True)
class Plan:
    """One trajectory: ``d(σ)`` quintic from station ``s0`` over ``length``; ``s(t)`` quartic.

    ``quintic`` holds ``a0..a5`` of ``d(σ)``; ``speed`` holds ``c1..c4`` of
    ``s(t) − s0 = c1 t + c2 t² + c3 t³ + c4 t⁴`` for ``0 ≤ t ≤ horizon``.
    ``max_lateral_accel`` is the plan's own peak ``|v²·κ_path|``; ``violation``
    > 0 when no candidate kept every limit (this is the least-violating one).
    """

    s0: float
    length: float
    quintic: np.ndarray
    speed: np.ndarray
    horizon: float
    feasible: bool
    violation: float
    max_lateral_accel: float

    @property
    def end_speed(self) -> float:
        c1, c2, c3, c4 = self.speed
        t = self.horizon
        return float(c1 + 2 * c2 * t + 3 * c3 * t**2 + 4 * c4 * t**3)

    @property
    def end_offset(self) -> float:
        return float(np.polyval(self.quintic[::-1], self.length))

    def lateral(self, s: float) -> tuple[float, float, float]:
        """``d, d', d''`` at station ``s`` (constant beyond the end)."""
        sig = min(max(s - self.s0, 0.0), self.length)
        a = self.quintic
        d = np.polyval(a[::-1], sig)
        d1 = np.polyval((a[1:] * np.arange(1, 6))[::-1], sig)
        d2 = np.polyval((a[2:] * np.array([2, 6, 12, 20]))[::-1], sig)
        return float(d), float(d1), float(d2)

    def longitudinal(self, t: float) -> tuple[float, float, float]:
        """``s − s0, v, a`` at time ``t`` after the plan's start (constant speed beyond)."""
        c1, c2, c3, c4 = self.speed
        tt = min(t, self.horizon)
        s = c1 * tt + c2 * tt**2 + c3 * tt**3 + c4 * tt**4
        v = c1 + 2 * c2 * tt + 3 * c3 * tt**2 + 4 * c4 * tt**3
        a = 2 * c2 + 6 * c3 * tt + 12 * c4 * tt**2 if t < self.horizon else 0.0
        return float(s + v * max(t - self.horizon, 0.0)), float(v), float(a)


def quintic(d0, d1, d2, d_end, length):
    """Coefficients ``(..., 6)`` of ``d(σ)``: start ``d0, d1, d2``; end ``d_end``, 0, 0 at ``length``."""
    d0, d1, d2, d_end, S = np.broadcast_arrays(*(np.asarray(v, float) for v in
                                                 (d0, d1, d2, d_end, length)))
    a2 = 0.5 * d2
    h = d_end - d0 - d1 * S - a2 * S**2
    v = -d1 - 2 * a2 * S
    w = -2 * a2
    a3 = (10 * h - 4 * v * S + 0.5 * w * S**2) / S**3
    a4 = (-15 * h + 7 * v * S - w * S**2) / S**4
    a5 = (6 * h - 3 * v * S + 0.5 * w * S**2) / S**5
    return np.stack([d0, d1, a2, a3, a4, a5], axis=-1)


def quartic_speed(v0, a0, v_end, horizon):
    """Coefficients ``(..., 4)`` ``c1..c4`` of ``s(t)``: start ``v0, a0``; end ``v_end``, 0."""
    v0, a0, v_end, T = np.broadcast_arrays(*(np.asarray(x, float) for x in (v0, a0, v_end, horizon)))
    dv = v_end - v0 - a0 * T
    c3 = dv / T**2 + a0 / (3 * T)
    c4 = -a0 / (4 * T**2) - dv / (2 * T**3)
    return np.stack([v0, 0.5 * a0, c3, c4], axis=-1)


def speed_envelope(route: Route, p: PlannerParams, truck: TruckParams,
                   margin: float = 0.95) -> np.ndarray:
    """The highest speed at each station that keeps the lateral-acceleration limit
    on the route's curvature (times ``margin``), capped at the preferred speed,
    made reachable (a backward pass at ``max_decel_mps2``: every later limit can be
    met by braking; a forward pass at ``max_accel_mps2``) and widened by the
    planner's sample spacing (a running minimum), so that no sample falls beside
    a short curvature peak."""
    from scipy.ndimage import minimum_filter1d  # noqa: PLC0415

    k = np.maximum(np.abs(route.curvature), 1e-9)
    v = np.minimum(np.sqrt(margin * p.max_lateral_accel_mps2 / k), p.preferred_speed_mps)
    v = np.maximum(v, p.min_speed_mps) ** 2
    ds = route.spacing_m
    x = 2.0 * ds * np.arange(len(v))
    # v[i]^2 <= v[j]^2 + 2 a |i - j| ds for j after i (braking) and before i (accelerating)
    v = np.minimum.accumulate((v + p.max_decel_mps2 * x)[::-1])[::-1] - p.max_decel_mps2 * x
    v = np.minimum.accumulate(v - p.max_accel_mps2 * x) + p.max_accel_mps2 * x
    reach = p.preferred_speed_mps * max(p.horizons_s) / _SAMPLES
    v = minimum_filter1d(v, 2 * int(np.ceil(reach / ds)) + 1, mode="nearest")
    return np.sqrt(np.maximum(v, 0.0))


class LatticePlanner:
    """Plans on one route; :meth:`plan` is called on a receding horizon."""

    def __init__(self, route: Route, p: PlannerParams, truck: TruckParams):
        self.route = route
        self.p = p
        self.k_max = 1.0 / truck.min_turn_radius_m
        self.env = speed_envelope(route, p, truck)
        self.offsets = np.asarray(p.lateral_offsets_m, float)
        self.fractions = np.asarray(p.speed_fractions, float)
        self.horizons = np.asarray(p.horizons_s, float)
        self.tau = np.linspace(1.0 / _SAMPLES, 1.0, _SAMPLES)
        n_t = len(self.horizons)
        self._vs_fixed = np.repeat(p.preferred_speed_mps * self.fractions, n_t)
        self._tl = np.tile(self.horizons, len(self.fractions) + 2)

    def _end_speeds(self, s0: float, v0: float) -> tuple[np.ndarray, np.ndarray]:
        """End speeds (fractions of the preferred speed, the envelope ahead, the current
        speed) and horizons of the longitudinal candidates, flattened."""
        T = self.horizons
        ahead = np.interp(s0 + v0 * T, self.route.s, self.env)
        vs = np.concatenate([self._vs_fixed, ahead, np.full(len(T), v0)])
        return np.maximum(vs, self.p.min_speed_mps), self._tl

    def plan(self, s0: float, d0: float, d1: float, d2: float, v0: float, a0: float) -> Plan:
        """The best trajectory from station ``s0`` with lateral state ``(d0, d', d'')``
        and longitudinal state ``(v0, a0)`` (compiled; same result as :meth:`plan_numpy`)."""
        from flyover_truck_fuel._lattice import best_candidate  # noqa: PLC0415

        p, r = self.p, self.route
        v0 = max(v0, 0.1)
        vs, tl = self._end_speeds(s0, v0)
        o, l_, ok, viol, alat = best_candidate(
            float(s0), float(d0), float(d1), float(d2), float(v0), float(a0), vs, tl,
            self.offsets, self.tau, r.s, r.curvature, self.env, r.d_pref,
            p.max_lateral_accel_mps2, self.k_max, p.max_accel_mps2, p.max_decel_mps2,
            p.preferred_speed_mps, p.weight_deviation, p.weight_lateral_jerk,
            p.weight_longitudinal_jerk, p.weight_speed)
        T, v_end = float(tl[l_]), float(vs[l_])
        dv = v_end - v0 - a0 * T
        c = np.array([v0, 0.5 * a0, dv / T**2 + a0 / (3 * T), -a0 / (4 * T**2) - dv / (2 * T**3)])
        length = max(float(T * (c[0] + T * (c[1] + T * (c[2] + T * c[3])))), 1.0)
        d_end = float(np.interp(s0 + length, r.s, r.d_pref)) + float(self.offsets[o])
        S, a2 = length, 0.5 * d2
        h = d_end - d0 - d1 * S - a2 * S * S
        vv, w = -d1 - 2 * a2 * S, -2 * a2
        a = np.array([d0, d1, a2, (10 * h - 4 * vv * S + 0.5 * w * S * S) / S**3,
                      (-15 * h + 7 * vv * S - w * S * S) / S**4,
                      (6 * h - 3 * vv * S + 0.5 * w * S * S) / S**5])
        return Plan(float(s0), length, a, c, T, bool(ok), float(viol), float(alat))

    def _at(self, s: np.ndarray, col: np.ndarray) -> np.ndarray:
        return np.interp(s, self.route.s, col)

    def plan_numpy(self, s0: float, d0: float, d1: float, d2: float, v0: float,
                   a0: float) -> Plan:
        """:meth:`plan` written with numpy arrays over all candidates (the readable
        reference of the compiled kernel)."""
        p = self.p
        v0 = max(v0, 0.1)
        T = self.horizons
        n_o, n_t = len(self.offsets), len(T)
        # longitudinal candidates: end speeds (fractions of the preferred speed, the
        # envelope ahead, the current speed) x horizons -> quartics, sampled in time
        ahead = np.interp(s0 + v0 * T, self.route.s, self.env)
        vs = np.concatenate([np.broadcast_to(p.preferred_speed_mps * self.fractions[:, None],
                                             (len(self.fractions), n_t)),
                             ahead[None, :], np.full((1, n_t), v0)])
        vs = np.maximum(vs, p.min_speed_mps).ravel()
        Tl = np.broadcast_to(T, (len(vs) // n_t, n_t)).ravel()
        c = quartic_speed(v0, a0, vs, Tl)                          # (L, 4)
        t = Tl[:, None] * self.tau[None, :]                        # (L, M)
        c1, c2, c3, c4 = (c[:, i:i + 1] for i in range(4))
        sig = t * (c1 + t * (c2 + t * (c3 + t * c4)))
        v = c1 + t * (2 * c2 + t * (3 * c3 + t * 4 * c4))
        acc = 2 * c2 + t * (6 * c3 + t * 12 * c4)
        jerk = 6 * c3 + 24 * c4 * t
        length = sig[:, -1]
        st = s0 + sig
        kap = np.interp(st, self.route.s, self.route.curvature)
        env = np.interp(st, self.route.s, self.env)
        dpref = np.interp(st, self.route.s, self.route.d_pref)
        lon_viol = (np.maximum(acc - p.max_accel_mps2 * 1.05, 0).max(1)
                    + np.maximum(-acc - p.max_decel_mps2 * 1.05, 0).max(1)
                    + np.maximum(v - env - 0.05, 0).max(1) + np.maximum(-v, 0).max(1)
                    + (length <= 1.0) * 10.0)
        lon_cost = (p.weight_longitudinal_jerk * (jerk**2).mean(1)
                    + p.weight_speed * ((v - p.preferred_speed_mps) ** 2).mean(1))
        length = np.maximum(length, 1.0)
        # lateral candidates: every offset for every longitudinal one -> (O, L, ...)
        d_end = np.interp(s0 + length, self.route.s, self.route.d_pref)[None, :] \
            + self.offsets[:, None]
        a = quintic(d0, d1, d2, d_end, length[None, :])            # (O, L, 6)
        a0_, a1_, a2_, a3_, a4_, a5_ = (a[..., i:i + 1] for i in range(6))
        d = a0_ + sig * (a1_ + sig * (a2_ + sig * (a3_ + sig * (a4_ + sig * a5_))))
        dd2 = 2 * a2_ + sig * (6 * a3_ + sig * (12 * a4_ + sig * 20 * a5_))
        dd3 = 6 * a3_ + sig * (24 * a4_ + sig * 60 * a5_)
        k_path = kap / (1.0 - kap * d) + dd2
        a_lat = v**2 * k_path
        viol = (np.maximum(np.abs(a_lat).max(-1) - p.max_lateral_accel_mps2, 0)
                / p.max_lateral_accel_mps2
                + np.maximum(np.abs(k_path).max(-1) - self.k_max, 0) / self.k_max
                + lon_viol[None, :]).ravel()
        cost = (p.weight_deviation * ((d - dpref) ** 2).mean(-1)
                + p.weight_lateral_jerk * ((v**3 * dd3) ** 2).mean(-1)
                + lon_cost[None, :]).ravel()
        feasible = viol <= 0.0
        if feasible.any():
            best = int(np.argmin(np.where(feasible, cost, np.inf)))
        else:
            best = int(np.argmin(viol + 1e-6 * cost))
        o, l_ = divmod(best, len(length))
        return Plan(float(s0), float(length[l_]), a[o, l_], c[l_], float(Tl[l_]),
                    bool(feasible[best]), float(viol[best]),
                    float(np.abs(a_lat[o, l_]).max()))
