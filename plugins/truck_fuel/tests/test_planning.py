"""Route, lattice planner and tracking."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flyover_truck_fuel.params import settings
from flyover_truck_fuel.planner import LatticePlanner, quintic, quartic_speed, speed_envelope
from flyover_truck_fuel.route import ramp_route, straight_route
from flyover_truck_fuel.simulate import drive, ramp_summary


def _curve(st, radius):
    return straight_route(radius * math.pi / 2 + radius / 3, 0.0, st.route, radius_m=radius,
                          transition_m=radius / 3)


def test_polynomials_meet_their_boundary_conditions():
    a = quintic(0.5, 0.01, -0.002, -1.0, 40.0)
    d = np.polynomial.polynomial.Polynomial(a)
    assert [d(0.0), d.deriv()(0.0), d.deriv(2)(0.0)] == pytest.approx([0.5, 0.01, -0.002])
    assert [d(40.0), d.deriv()(40.0), d.deriv(2)(40.0)] == pytest.approx([-1.0, 0, 0], abs=1e-12)
    c = quartic_speed(10.0, 0.3, 7.0, 4.0)
    s = np.polynomial.polynomial.Polynomial(np.concatenate([[0.0], c]))
    assert [s.deriv()(0.0), s.deriv(2)(0.0)] == pytest.approx([10.0, 0.3])
    assert [s.deriv()(4.0), s.deriv(2)(4.0)] == pytest.approx([7.0, 0.0], abs=1e-12)


@pytest.mark.parametrize("limit", [1.5, 2.5])
def test_planner_respects_the_lateral_acceleration_limit(limit):
    st = settings({"planner": {"max_lateral_accel_mps2": limit}})
    route = _curve(st, 30.0)
    run = drive(route, st)
    s = ramp_summary(route, run)
    assert s.completed and run.infeasible_plans == 0
    assert run.max_planned_lateral_accel <= limit * (1 + 1e-6)
    assert s.max_lateral_accel_mps2 <= limit * 1.05      # the truck, not only the plan
    assert s.mean_speed_mps < math.sqrt(limit * 30.0)    # it slowed down for the curve


def test_planner_slows_before_a_curve_it_sees_ahead(st):
    route = _curve(st, 30.0)
    env = speed_envelope(route, st.planner, st.truck)
    assert env[np.searchsorted(route.s, 20.0)] < math.sqrt(st.planner.max_lateral_accel_mps2 * 30)
    planner = LatticePlanner(route, st.planner, st.truck)
    v_curve = math.sqrt(st.planner.max_lateral_accel_mps2 * 30.0)
    far = planner.plan(-60.0, 0.0, 0.0, 0.0, 10.0, 0.0)     # the curve is beyond braking reach
    near = planner.plan(-20.0, 0.0, 0.0, 0.0, 10.0, 0.0)    # within braking reach
    assert far.feasible and far.end_speed == pytest.approx(10.0)
    assert near.feasible and near.end_speed < v_curve
    assert near.max_lateral_accel <= st.planner.max_lateral_accel_mps2


def test_a_curve_tighter_than_the_truck_can_turn_is_not_completed(st):
    route = _curve(st, 8.0)
    s = ramp_summary(route, drive(route, st))
    assert not s.completed and "limits" in s.reason


def test_ramp_route_follows_the_lane_centre_of_a_catalog_ramp(st, j1_geometry):
    for ramp in j1_geometry.ramps:
        route = ramp_route(j1_geometry, ramp, st.route)
        assert route.min_radius_m == pytest.approx(ramp.min_radius_m, rel=0.02)
        assert route.max_slope_pct == pytest.approx(ramp.max_slope_pct, rel=0.05)
        assert np.diff(route.s).max() <= st.route.spacing_m + 1e-9
        # the truck starts in the parent's lane: next to the ramp, one lane over
        assert 3.0 < abs(route.d_pref[0]) < 4.5 and route.d_pref[np.searchsorted(route.s, 0.0)] == 0
        start = ramp.start.label
        assert (route.d_pref[0] > 0) == start.endswith("R")       # leaving rightwards


@pytest.mark.parametrize("steer_lag_s", [0.1, 0.4])
def test_tracking_error_stays_small_on_catalog_ramps(j1_geometry, steer_lag_s):
    st = settings({"truck": {"steer_lag_s": steer_lag_s}})
    for ramp in j1_geometry.ramps:
        route = ramp_route(j1_geometry, ramp, st.route)
        s = ramp_summary(route, drive(route, st))
        assert s.completed, s.reason
        assert s.max_lateral_error_m <= 0.3
        assert s.max_lateral_accel_mps2 <= st.planner.max_lateral_accel_mps2 * 1.05


def test_compiled_lattice_picks_the_same_plan_as_the_numpy_reference(st):
    route = _curve(st, 40.0)
    planner = LatticePlanner(route, st.planner, st.truck)
    rng = np.random.default_rng(7)
    for _ in range(200):
        state = (rng.uniform(-120.0, 80.0), rng.uniform(-1.0, 1.0), rng.uniform(-0.05, 0.05),
                 rng.uniform(-0.01, 0.01), rng.uniform(2.0, 12.0), rng.uniform(-1.0, 1.0))
        a, b = planner.plan(*state), planner.plan_numpy(*state)
        assert a.feasible == b.feasible and a.horizon == b.horizon
        assert a.quintic == pytest.approx(b.quintic, rel=1e-9, abs=1e-12)
        assert a.speed == pytest.approx(b.speed, rel=1e-9, abs=1e-12)
        assert a.max_lateral_accel == pytest.approx(b.max_lateral_accel, rel=1e-9, abs=1e-12)
