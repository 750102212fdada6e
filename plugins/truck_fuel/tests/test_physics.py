"""The truck model: energy balance, grade, LQR gains, fuel cut-off."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flyover_truck_fuel.model import fuel_rate_ml_s, lateral_error_model, lateral_gains, speed_gains
from flyover_truck_fuel.params import G, settings
from flyover_truck_fuel.route import straight_route
from flyover_truck_fuel.simulate import drive, ramp_summary


def _ramp(st, grade, length=1000.0):
    route = straight_route(length, grade, st.route)
    return ramp_summary(route, drive(route, st))


def test_energy_balance_on_a_straight_flat_road_at_constant_speed(st):
    tr, en = st.truck, st.engine
    v = st.planner.preferred_speed_mps
    s = _ramp(st, 0.0)
    assert s.completed and s.mean_speed_mps == pytest.approx(v, rel=1e-3)
    # by hand: traction = rolling + air resistance; engine power through the driveline
    # plus auxiliaries; fuel power = (P_e + P_0) / e (Willans line)
    force = tr.rolling_resistance * tr.mass_kg * G + 0.5 * tr.air_density_kg_m3 * tr.cd_a_m2 * v**2
    p_engine = force * v / tr.driveline_efficiency + en.aux_power_kw * 1e3
    p_fuel = (p_engine + en.friction_power_w) / en.willans_efficiency
    ml = p_fuel * (1000.0 / v) / (en.lhv_mj_per_kg * 1e6) / en.fuel_density_kg_per_l * 1e3
    assert s.fuel_ml == pytest.approx(ml, rel=0.005)
    assert s.fuel_ml_per_km == pytest.approx(ml, rel=0.005)


def test_more_fuel_uphill_than_on_the_flat_than_downhill(st):
    up, flat, down = (_ramp(st, g, 500.0).fuel_ml_per_km for g in (0.02, 0.0, -0.02))
    assert up > 2.0 * flat and flat > down


def test_steep_descent_is_braked_with_fuel_cut_off(st):
    route = straight_route(500.0, -0.04, st.route)
    run = drive(route, st)
    on = (run.x[0] > 50.0) & (run.x[0] < 450.0)
    assert (run.y[2][on] < 0).all()           # the brakes hold the speed
    assert ramp_summary(route, run).fuel_ml == 0.0
    assert abs(run.x[5][on] - st.planner.preferred_speed_mps).max() < 0.05


def test_fuel_rate_idles_when_crawling_and_cuts_off_when_braking(st):
    tr, en = st.truck, st.engine
    assert fuel_rate_ml_s(-1000.0, 10.0, tr, en) == 0.0
    assert fuel_rate_ml_s(-1000.0, 1.0, tr, en) == pytest.approx(en.idle_ml_per_s)
    assert fuel_rate_ml_s(10.0, 0.5, tr, en) >= en.idle_ml_per_s


def test_speed_lqr_gains_match_the_double_integrator_closed_form():
    for q1, q2, r in ((0.25, 1.0, 1.0), (4.0, 0.5, 2.0), (1.0, 9.0, 0.1)):
        ctrl = settings({"control": {"speed_q": [q1, q2], "speed_r": r}}).control
        k_int, k_v = speed_gains(ctrl)
        assert k_int == pytest.approx(math.sqrt(q1 / r), rel=1e-6)
        assert k_v == pytest.approx(math.sqrt(q2 / r + 2.0 * math.sqrt(q1 / r)), rel=1e-6)


def test_lateral_lqr_matches_the_scalar_closed_form_and_stabilises_every_speed(st):
    import control

    # scalar x' = a x + b u: K = (a + sqrt(a^2 + b^2 q / r)) / b
    a, b, q, r = 0.7, 2.0, 3.0, 0.5
    k, _, _ = control.lqr(np.array([[a]]), np.array([[b]]), np.array([[q]]), np.array([[r]]))
    assert float(k[0, 0]) == pytest.approx((a + math.sqrt(a * a + b * b * q / r)) / b, rel=1e-9)
    speeds = np.array([2.0, 5.0, 10.0, 20.0])
    gains = lateral_gains(st.truck, st.control, speeds)
    assert gains.shape == (4, 5)
    for v, kk in zip(speeds, gains):
        am, bm = lateral_error_model(st.truck, float(v), actuator=True)
        assert np.linalg.eigvals(am - bm @ kk[None, :]).real.max() < 0
