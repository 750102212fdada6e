"""Drive a route: plan on a receding horizon, track with LQR, integrate the truck.

:func:`drive` runs the closed loop of :func:`flyover_truck_fuel.model.closed_loop`
one re-planning interval per CasADi call and returns the trajectory;
:func:`ramp_summary` reduces it to the figures of one ramp (the stations
``0..ramp_length_m``; the leads only bring the truck onto the ramp at speed
and back onto a road).

The drive stops early — ``completed = False`` with the reason — when the
truck leaves its plan by more than ``max_tracking_error_m``, when no plan
keeps the limits (the route is too tight for the truck), or when it takes
more than five times the preferred-speed time.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np

from flyover_truck_fuel.model import STATE, closed_loop
from flyover_truck_fuel.params import Settings
from flyover_truck_fuel.planner import LatticePlanner
from flyover_truck_fuel.route import Route

__all__ = ["Drive", "RampSummary", "drive", "ramp_summary"]

log = logging.getLogger(__name__)

_S, _D, _PSI, _VY, _R, _VX, _Z, _FUEL, _T, _STEER = range(len(STATE))
_WINDOW_DS = 1.0


@dataclass(frozen=True)
class Drive:
    """A driven route: per control step time, state and outputs.

    ``x`` is ``(10, n)`` (:data:`~flyover_truck_fuel.model.STATE`, with ``t``
    the time since the start), ``y`` is ``(5, n)``
    (:data:`~flyover_truck_fuel.model.OUTPUT`). ``completed`` is False with a
    ``reason`` when the drive stopped early.
    """

    x: np.ndarray
    y: np.ndarray
    completed: bool
    reason: str
    plans: int
    infeasible_plans: int
    max_planned_lateral_accel: float


@dataclass(frozen=True)
class RampSummary:
    """One ramp's figures (see the plugin's row columns)."""

    length_m: float
    duration_s: float
    mean_speed_mps: float
    fuel_ml: float
    fuel_ml_per_km: float
    max_lateral_error_m: float
    max_lateral_accel_mps2: float
    completed: bool
    reason: str


def _window(route: Route, s: float, n: int) -> tuple[float, np.ndarray, np.ndarray]:
    s_w = s - 2.0 * _WINDOW_DS + _WINDOW_DS * np.arange(n)
    return (float(s_w[0]), np.interp(s_w, route.s, route.curvature),
            np.interp(s_w, route.s, route.grade))


def drive(route: Route, st: Settings, *, initial_speed: float | None = None) -> Drive:
    """Drive ``route`` from its first station to its last (see the module docstring)."""
    pp, cp = st.planner, st.control
    steps = max(1, int(round(pp.replan_s / cp.step_s)))
    v_cap = pp.preferred_speed_mps * max(1.0, max(pp.speed_fractions)) + 3.0
    window = int(math.ceil(v_cap * steps * cp.step_s / _WINDOW_DS)) + 5
    chunk, lay = closed_loop(st, steps, window)
    planner = LatticePlanner(route, pp, st.truck)
    v0 = pp.preferred_speed_mps if initial_speed is None else initial_speed
    x = np.zeros(len(STATE))
    x[_S], x[_D], x[_VX] = route.s[0], route.d_pref[0], v0
    plan = planner.plan(route.s[0], route.d_pref[0], 0.0, 0.0, v0, 0.0)
    s_end = float(route.s[-1])
    t_limit = 5.0 * (s_end - route.s[0]) / pp.preferred_speed_mps + 30.0
    xs, ys = [], []
    p = np.zeros(lay.size)
    p[lay.ds] = _WINDOW_DS
    n_plans, n_bad, worst_plan = 1, 0, plan.max_lateral_accel
    t_total, reason, bad_run = 0.0, "", 0
    while True:
        if not plan.feasible:
            n_bad += 1
            bad_run += 1
            if bad_run >= 3:
                reason = (f"no plan keeps the limits at station {plan.s0:.0f} m "
                          f"(violation {plan.violation:.2f})")
                break
        else:
            bad_run = 0
        p[lay.s0], p[lay.kappa], p[lay.grade] = _window(route, x[_S], window)
        p[lay.quintic] = plan.quintic
        p[lay.s_plan], p[lay.length] = plan.s0, plan.length
        p[lay.speed] = plan.speed
        p[lay.horizon] = plan.horizon
        x[_T] = 0.0
        X, Y = chunk(x, p)
        X, Y = X.full(), Y.full()
        X[_T] += t_total
        t_total += steps * cp.step_s
        xs.append(X)
        ys.append(Y)
        x = X[:, -1].copy()
        err = np.abs(Y[3]).max()
        if not np.all(np.isfinite(X)):
            reason = f"the simulation diverged near station {x[_S]:.0f} m"
            break
        if err > st.route.max_tracking_error_m:
            reason = (f"left the lane: {err:.2f} m off the plan at station "
                      f"{X[_S, int(np.argmax(np.abs(Y[3])))]:.0f} m")
            break
        if x[_S] >= s_end:
            break
        if t_total > t_limit:
            reason = f"too slow: {t_total:.0f} s and only at station {x[_S]:.0f} m"
            break
        # next plan starts from this plan's state (consistency), or from the truck if it drifted
        ts = steps * cp.step_s
        ds_, v_p, a_p = plan.longitudinal(ts)
        d_p, d1_p, d2_p = plan.lateral(x[_S])
        if abs(x[_VX] - v_p) > 1.0:
            v_p, a_p = x[_VX], 0.0
        if abs(x[_D] - d_p) > 0.3:
            d_p, d1_p, d2_p = x[_D], math.tan(x[_PSI]), 0.0
        plan = planner.plan(x[_S], d_p, d1_p, d2_p, v_p, a_p)
        n_plans += 1
        worst_plan = max(worst_plan, plan.max_lateral_accel)
    x_all = np.concatenate(xs, axis=1) if xs else np.zeros((len(STATE), 0))
    y_all = np.concatenate(ys, axis=1) if ys else np.zeros((5, 0))
    return Drive(x_all, y_all, reason == "", reason, n_plans, n_bad, worst_plan)


def ramp_summary(route: Route, run: Drive) -> RampSummary:
    """Figures of the ramp part (stations ``0..ramp_length_m``) of a drive."""
    s = run.x[_S]
    L = route.ramp_length_m
    on = (s >= 0.0) & (s <= L)
    reached = s.size and s.max() >= L
    if s.size == 0 or not on.any():
        return RampSummary(L, math.nan, math.nan, math.nan, math.nan, math.nan, math.nan,
                           False, run.reason or "the truck never reached the ramp")
    t, fuel = run.x[_T], run.x[_FUEL]
    # times and fuel at the ramp's two ends, by interpolation between steps
    t0, f0 = np.interp(0.0, s, t), np.interp(0.0, s, fuel)
    s_last = L if reached else float(s.max())
    t1, f1 = np.interp(s_last, s, t), np.interp(s_last, s, fuel)
    dur = float(t1 - t0)
    used = float(f1 - f0)
    return RampSummary(
        length_m=float(L), duration_s=dur,
        mean_speed_mps=float(s_last / dur) if dur > 0 else math.nan,
        fuel_ml=used, fuel_ml_per_km=used / (s_last / 1000.0) if s_last > 0 else math.nan,
        max_lateral_error_m=float(np.abs(run.y[3][on]).max()),
        max_lateral_accel_mps2=float(np.abs(run.y[0][on]).max()),
        completed=bool(run.completed and reached),
        reason=run.reason)
