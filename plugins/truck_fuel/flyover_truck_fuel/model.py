"""The truck in closed loop, in CasADi: single-track dynamics, LQR tracking, fuel.

State (road-aligned frame of a :class:`~flyover_truck_fuel.route.Route`)::

    x = [s, d, psi, vy, r, vx, z_int, fuel_ml, t]

``s`` station, ``d`` lateral offset (left +), ``psi`` heading relative to the
route, ``vy``/``r`` lateral velocity and yaw rate, ``vx`` speed, ``z_int`` the
integral of the speed error, ``fuel_ml`` fuel burnt, ``t`` time since the plan
started, ``steer`` the front wheels' steer angle (lagging the command).

* **Longitudinal**: ``m_eq·v̇x = F_x − F_yf·sin δ + m·vy·r − c_rr·m·g·cos θ −
  ½ρ·c_dA·vx² − m·g·sin θ``; the traction force is bounded by engine power and
  drive-axle adhesion, the brake force by the service-brake deceleration.
* **Lateral**: single-track model with tyre forces ``μF_z·tanh(Cα/(μF_z))``
  (linear with cornering stiffness ``C`` for small slip, saturating at the
  friction limit).
* **Steering actuator**: first-order lag ``δ̇ = (δ_cmd − δ)/τ``.
* **Control** (sampled, held over a step): steer command by LQR on the lateral
  error model (Rajamani, Vehicle Dynamics and Control, 2nd ed. 2012, §3.2)
  augmented with the actuator lag, gains from :func:`control.lqr` on a speed
  grid and interpolated linearly (gain scheduling), plus the curvature
  feed-forward that cancels the steady-state error; traction/brake force by LQR on ``[∫e_v, e_v]`` (integral
  action) plus the resistance feed-forward.
* **Fuel**: Willans line ``P_fuel = (P_e + P_0)/e`` with ``P_e`` the wheel
  power over the driveline efficiency plus auxiliaries, overrun fuel cut-off
  when the force is negative above ``cutoff_speed_mps``, idle consumption
  below it.

One control step is one step of a CasADi ``rk`` integrator (fixed-step RK4,
expanded into an SX graph); :func:`closed_loop` maps it over ``N`` steps with
``Function.mapaccum``, so a whole re-planning interval is one call.

The per-interval parameter vector (:class:`Layout`) holds the route's
curvature and grade on a window of stations (linear interpolation inside the
graph, so they are read where the truck actually is) and the plan: a quintic
``d_ref(σ)`` over ``σ = s − s_plan`` and a speed ``v_ref(t)`` (derivative of the
planner's quartic ``s(t)``).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np

from flyover_truck_fuel.params import G, ControlParams, EngineParams, Settings, TruckParams

__all__ = ["STATE", "OUTPUT", "Layout", "lateral_error_model", "lateral_gains", "speed_gains",
           "closed_loop", "fuel_rate_ml_s"]

#: state names, in order
STATE = ("s", "d", "psi", "vy", "r", "vx", "z_int", "fuel_ml", "t", "steer")
#: per-step output names, in order
OUTPUT = ("a_lat", "steer", "force", "e_lat", "fuel_rate")

#: speeds (m/s) of the gain schedule
SPEED_GRID = np.array([1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 10.0, 12.0, 14.0, 17.0, 20.0, 25.0,
                       30.0])


@dataclass(frozen=True)
class Layout:
    """Positions in the per-interval parameter vector ``p``."""

    window: int

    @property
    def s0(self) -> int:
        return 0

    @property
    def ds(self) -> int:
        return 1

    @property
    def kappa(self) -> slice:
        return slice(2, 2 + self.window)

    @property
    def grade(self) -> slice:
        return slice(2 + self.window, 2 + 2 * self.window)

    @property
    def quintic(self) -> slice:
        o = 2 + 2 * self.window
        return slice(o, o + 6)

    @property
    def s_plan(self) -> int:
        return 8 + 2 * self.window

    @property
    def length(self) -> int:
        return 9 + 2 * self.window

    @property
    def speed(self) -> slice:
        """``c1..c4`` of ``s(t) = c1 t + c2 t² + c3 t³ + c4 t⁴``."""
        o = 10 + 2 * self.window
        return slice(o, o + 4)

    @property
    def horizon(self) -> int:
        return 14 + 2 * self.window

    @property
    def size(self) -> int:
        return 15 + 2 * self.window


def lateral_error_model(truck: TruckParams, v: float,
                        actuator: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """``A, B`` of the lateral error dynamics ``[e1, ė1, e2, ė2]`` at speed ``v``.

    Rajamani (2012), eq. 3.29, with axle cornering stiffnesses ``Cf, Cr``. With
    ``actuator`` the state gains the steer angle's departure from its
    feed-forward, ``δ̃``, driven through the actuator lag: the input is then the
    steer command (``δ̃̇ = (u − δ̃)/τ``).
    """
    m, iz = truck.mass_kg, truck.yaw_inertia_kgm2
    cf, cr, lf, lr = truck.cf_n_per_rad, truck.cr_n_per_rad, truck.lf_m, truck.lr_m
    a = np.array([
        [0.0, 1.0, 0.0, 0.0],
        [0.0, -(cf + cr) / (m * v), (cf + cr) / m, (-cf * lf + cr * lr) / (m * v)],
        [0.0, 0.0, 0.0, 1.0],
        [0.0, -(cf * lf - cr * lr) / (iz * v), (cf * lf - cr * lr) / iz,
         -(cf * lf**2 + cr * lr**2) / (iz * v)],
    ])
    b = np.array([[0.0], [cf / m], [0.0], [cf * lf / iz]])
    if not actuator:
        return a, b
    tau = truck.steer_lag_s
    a5 = np.zeros((5, 5))
    a5[:4, :4], a5[:4, 4:], a5[4, 4] = a, b, -1.0 / tau
    b5 = np.zeros((5, 1))
    b5[4, 0] = 1.0 / tau
    return a5, b5


def lateral_gains(truck: TruckParams, ctrl: ControlParams,
                  speeds: np.ndarray = SPEED_GRID) -> np.ndarray:
    """LQR gains ``(len(speeds), 5)`` of the lateral error model with the steering
    actuator (python-control); the steer angle's own weight is zero."""
    import control  # noqa: PLC0415

    q = np.diag([*ctrl.lateral_q, 0.0])
    out = []
    for v in speeds:
        a, b = lateral_error_model(truck, float(v), actuator=True)
        k, _, _ = control.lqr(a, b, q, np.array([[ctrl.lateral_r]]))
        out.append(np.asarray(k).ravel())
    return np.array(out)


def speed_gains(ctrl: ControlParams) -> tuple[float, float]:
    """LQR gains ``(k_int, k_v)`` on ``[∫e_v, e_v]`` with ``ė_v = u`` (an acceleration).

    For this double integrator the Riccati equation has the closed form
    ``k_int = √(q1/r)``, ``k_v = √(q2/r + 2√(q1/r))``.
    """
    import control  # noqa: PLC0415

    a = np.array([[0.0, 1.0], [0.0, 0.0]])
    b = np.array([[0.0], [1.0]])
    k, _, _ = control.lqr(a, b, np.diag(ctrl.speed_q), np.array([[ctrl.speed_r]]))
    k = np.asarray(k).ravel()
    return float(k[0]), float(k[1])


def fuel_rate_ml_s(force_n, v, truck: TruckParams, eng: EngineParams, lib=np):
    """Fuel rate (ml/s) for traction force ``force_n`` at speed ``v`` (numpy or CasADi).

    Willans line with auxiliaries; overrun cut-off for ``force ≤ 0`` above the
    cut-off speed, idle below it.
    """
    where = np.where if lib is np else ca.if_else
    fmax = np.maximum if lib is np else ca.fmax
    p_engine = force_n * v / truck.driveline_efficiency + eng.aux_power_kw * 1e3
    willans = (p_engine + eng.friction_power_w) / eng.willans_efficiency * eng.ml_per_joule
    idle = eng.idle_ml_per_s
    moving = where(v > eng.cutoff_speed_mps, 0.0, idle)
    return where(force_n > 0.0, fmax(willans, idle), moving)


def _hats(u, values, n):
    """Piecewise-linear interpolation of ``values[0..n-1]`` at fractional index ``u``."""
    u = ca.fmin(ca.fmax(u, 0.0), n - 1)
    return sum(values[j] * ca.fmax(0.0, 1.0 - ca.fabs(u - j)) for j in range(n))


def _schedule(v, grid: np.ndarray, table: np.ndarray):
    """Linear interpolation of gain rows ``table`` over speed ``grid`` at ``v``."""
    v = ca.fmin(ca.fmax(v, float(grid[0])), float(grid[-1]))
    out = 0
    for j in range(len(grid)):
        lo = grid[j - 1] if j else grid[0] - 1.0
        hi = grid[j + 1] if j + 1 < len(grid) else grid[-1] + 1.0
        w = ca.fmax(0.0, ca.fmin((v - lo) / (grid[j] - lo), (hi - v) / (hi - grid[j])))
        out = out + w * ca.DM(table[j])
    return out


@lru_cache(maxsize=8)
def closed_loop(st: Settings, steps: int, window: int = 40) -> tuple[ca.Function, Layout]:
    """The closed loop over ``steps`` control steps, as one CasADi function.

    Returns ``(F, layout)`` with ``F(x0, p) → (X, Y)``: ``X`` the states after
    each step ``(10, steps)``, ``Y`` the outputs ``(5, steps)``
    (:data:`OUTPUT`: lateral acceleration, steer angle, force, lateral error to
    the plan, fuel rate; at the start of each step). Built once per settings (cached).
    """
    tr, eng, ctl = st.truck, st.engine, st.control
    lay = Layout(window)
    m, iz, lf, lr = tr.mass_kg, tr.yaw_inertia_kgm2, tr.lf_m, tr.lr_m
    cf, cr, mu = tr.cf_n_per_rad, tr.cr_n_per_rad, tr.tyre_friction
    fzf, fzr = tr.front_load_n, tr.rear_load_n
    m_eq = m * tr.rotating_mass_factor
    wheelbase = tr.wheelbase_m
    k_us = m / wheelbase * (lr / cf - lf / cr)
    lat_k = lateral_gains(tr, ctl)
    k_int, k_v = speed_gains(ctl)

    x = ca.SX.sym("x", len(STATE))
    p = ca.SX.sym("p", lay.size)
    s, d, psi, vy, r, vx, z_int, _fuel, t, delta = (x[i] for i in range(len(STATE)))

    def route_at(si):
        u = (si - p[lay.s0]) / p[lay.ds]
        return _hats(u, p[lay.kappa], window), _hats(u, p[lay.grade], window)

    # -- controller (evaluated at the start of the step, held over it) --
    kap, grd = route_at(s)
    q = p[lay.quintic]
    sig = ca.fmin(ca.fmax(s - p[lay.s_plan], 0.0), p[lay.length])
    d_ref = q[0] + sig * (q[1] + sig * (q[2] + sig * (q[3] + sig * (q[4] + sig * q[5]))))
    d1 = q[1] + sig * (2 * q[2] + sig * (3 * q[3] + sig * (4 * q[4] + sig * 5 * q[5])))
    d2 = 2 * q[2] + sig * (6 * q[3] + sig * (12 * q[4] + sig * 20 * q[5]))
    one = 1.0 - kap * d_ref
    psi_ref = ca.atan2(d1, one)
    kap_traj = kap / one + d2
    vxs = ca.fmax(vx, 0.5)
    e1 = d - d_ref
    e2 = psi - psi_ref
    e1dot = vy + vxs * e2
    e2dot = r - vxs * kap_traj
    kk = _schedule(vxs, SPEED_GRID, lat_k)
    # feed-forward that zeroes the steady-state e1 (Rajamani eq. 3.45); in steady state the
    # lag state settles at δ̃ = −K4·e/(1 + k5), i.e. the heading gain acts as k3/(1 + k5)
    k3 = kk[2] / (1.0 + kk[4])
    # preview: the feed-forward steers for the path one actuator time constant ahead
    s_ahead = s + vxs * tr.steer_lag_s
    kap_a, _ = route_at(s_ahead)
    sig_a = ca.fmin(ca.fmax(s_ahead - p[lay.s_plan], 0.0), p[lay.length])
    d_a = q[0] + sig_a * (q[1] + sig_a * (q[2] + sig_a * (q[3] + sig_a * (q[4] + sig_a * q[5]))))
    d2_a = 2 * q[2] + sig_a * (6 * q[3] + sig_a * (12 * q[4] + sig_a * 20 * q[5]))
    kap_ff = kap_a / (1.0 - kap_a * d_a) + d2_a
    steer_ff = kap_ff * (wheelbase + k_us * vxs**2
                         - k3 * (lr - lf * m * vxs**2 / (cr * wheelbase)))
    steer_fb = -(kk[0] * e1 + kk[1] * e1dot + kk[2] * e2 + kk[3] * e2dot
                 + kk[4] * (delta - steer_ff))
    steer = ca.fmin(ca.fmax(steer_fb + steer_ff, -tr.max_steer_rad), tr.max_steer_rad)

    c = p[lay.speed]
    tt = ca.fmin(t, p[lay.horizon])
    v_ref = c[0] + tt * (2 * c[1] + tt * (3 * c[2] + tt * 4 * c[3]))
    a_ref = ca.if_else(t < p[lay.horizon], 2 * c[1] + tt * (6 * c[2] + tt * 12 * c[3]), 0.0)
    e_v = vx - v_ref
    th = ca.atan(grd)
    resist = (tr.rolling_resistance * m * G * ca.cos(th)
              + 0.5 * tr.air_density_kg_m3 * tr.cd_a_m2 * vx**2 + m * G * ca.sin(th))
    f_cmd = m_eq * (a_ref - k_int * z_int - k_v * e_v) + resist
    f_max = ca.fmin(tr.max_traction_n, tr.max_power_kw * 1e3 / vxs)
    f_min = -m * tr.max_brake_decel_mps2
    force = ca.fmin(ca.fmax(f_cmd, f_min), f_max)
    saturated = ca.logic_or(f_cmd > f_max, f_cmd < f_min)
    u = ca.vertcat(steer, force, ca.if_else(saturated, 0.0, 1.0), v_ref)

    # -- plant --
    xs = ca.SX.sym("xs", len(STATE))
    us = ca.SX.sym("us", 4)
    s_, d_, psi_, vy_, r_, vx_, _z, _f, _t, dl = (xs[i] for i in range(len(STATE)))
    cmd, fx, integrate, vr = us[0], us[1], us[2], us[3]
    kap_, grd_ = route_at(s_)
    vxp = ca.fmax(vx_, 0.5)
    af = dl - ca.atan2(vy_ + lf * r_, vxp)
    ar = -ca.atan2(vy_ - lr * r_, vxp)
    fyf = mu * fzf * ca.tanh(cf * af / (mu * fzf))
    fyr = mu * fzr * ca.tanh(cr * ar / (mu * fzr))
    th_ = ca.atan(grd_)
    res_ = (tr.rolling_resistance * m * G * ca.cos(th_) * ca.tanh(vx_ / 0.2)
            + 0.5 * tr.air_density_kg_m3 * tr.cd_a_m2 * vx_**2 + m * G * ca.sin(th_))
    sdot = (vx_ * ca.cos(psi_) - vy_ * ca.sin(psi_)) / (1.0 - kap_ * d_)
    ode = ca.vertcat(
        sdot,
        vx_ * ca.sin(psi_) + vy_ * ca.cos(psi_),
        r_ - kap_ * sdot,
        (fyf * ca.cos(dl) + fyr) / m - vx_ * r_,
        (lf * fyf * ca.cos(dl) - lr * fyr) / iz,
        (fx - fyf * ca.sin(dl) + m * vy_ * r_ - res_) / m_eq,
        integrate * (vx_ - vr),
        fuel_rate_ml_s(fx, vx_, tr, eng, lib=ca),
        1.0,
        (cmd - dl) / tr.steer_lag_s,
    )
    pw = ca.vertcat(us, p)
    integ = ca.integrator("truck", "rk", {"x": xs, "p": pw, "ode": ode}, 0.0, ctl.step_s,
                          {"number_of_finite_elements": 1, "simplify": True})
    x_next = integ(x0=x, p=ca.vertcat(u, p))["xf"]
    a_lat = (mu * fzf * ca.tanh(cf * (delta - ca.atan2(vy + lf * r, vxs)) / (mu * fzf))
             * ca.cos(delta)
             + mu * fzr * ca.tanh(cr * (-ca.atan2(vy - lr * r, vxs)) / (mu * fzr))) / m
    y = ca.vertcat(a_lat, delta, force, e1, fuel_rate_ml_s(force, vx, tr, eng, lib=ca))
    step = ca.Function("truck_step", [x, p], [x_next, y])
    chunk = step.mapaccum("truck_chunk", steps)
    return chunk, lay
