"""Ramp fitting: continuity, radius and slope targets, loops, flyovers, infeasible targets."""

import math
from dataclasses import replace

import numpy as np
import pytest

from flyover.geometry.bezier import heading_vec, held_radius, sample_spline
from flyover.geometry import _kernels
from flyover.geometry.fit import (FitSettings, Obstacles, Rail, RampSpec, conflicts_with,
                                  fit_ramp, measure)
from flyover.geometry.profile import evaluate_polys, max_grade

W = 4.0


def _check_ends(fit):
    """G1 at both ends: position < 1 cm, heading < 0.5°, height < 1 cm (measured on the curve)."""
    ctrl = fit.ctrl
    for rail, s, k, pose in ((fit.spec.start, fit.start_s, 0, fit.start_pose),
                             (fit.spec.end, fit.end_s, -1, fit.end_pose)):
        p, h, z = rail.at(np.array([s]))
        end = ctrl[k, 0] if k == 0 else ctrl[k, 3]
        tan = ctrl[k, 1] - ctrl[k, 0] if k == 0 else ctrl[k, 3] - ctrl[k, 2]
        assert np.hypot(*(end - p[0])) < 0.01
        dh = math.atan2(tan[1], tan[0]) - h[0]
        assert abs((dh + math.pi) % (2 * math.pi) - math.pi) < math.radians(0.5)
        zz, _ = evaluate_polys(fit.elevation, np.array([0.0 if k == 0 else fit.length_m]))
        assert abs(zz[0] - z[0]) < 0.01
    # joints: G1
    for a, b in zip(ctrl[:-1], ctrl[1:]):
        assert np.hypot(*(a[3] - b[0])) < 1e-9
        ta, tb = a[3] - a[2], b[1] - b[0]
        assert abs(ta[0] * tb[1] - ta[1] * tb[0]) / (np.hypot(*ta) * np.hypot(*tb)) < 1e-6


def _held(ref, width) -> np.ndarray:
    """The radius each sampled candidate holds over HOLD_M (as the search measures it)."""
    from types import SimpleNamespace  # noqa: PLC0415

    s, tang = ref.s.reshape(-1, ref.s.shape[-1]), ref.tangent.reshape(-1, ref.s.shape[-1], 2)
    return np.array([held_radius(SimpleNamespace(s=a, tangent=b), width, _kernels.HOLD_M)
                     for a, b in zip(s, tang)])


def _measured(fit):
    dense = sample_spline(fit.ctrl, 2000)
    rmin = held_radius(dense, W, _kernels.HOLD_M)
    return rmin, max_grade(fit.elevation, fit.length_m, 20001) * 100


def _right_turn(radius, slope):
    a = Rail.line("A1", "Out-R", (0, 0), 0.0, 0.0, -15.0, -800, -40)
    b = Rail.line("B1", "In-R", (0, 0), -np.pi / 2, 6.5, -15.0, 40, 800)
    return RampSpec("r", a, b, None, -np.pi / 2, 1, W, radius, slope)


@pytest.mark.parametrize("radius,slope", [(100.0, 4.0), (250.0, 2.0), (40.0, 6.0)])
def test_right_turn_meets_radius_and_slope_targets_with_g1_ends(radius, slope):
    # as the layout does: a fit that misses is tried again with another seed (a tight
    # 40 m turn held over 10 m is missed by about one search in three)
    for seed in (3, 4, 5):
        fit = fit_ramp(_right_turn(radius, slope), seed=seed)
        if fit.ok:
            break
    _check_ends(fit)
    rmin, smax = _measured(fit)
    assert abs(rmin - radius) <= 0.05 * radius
    assert abs(smax - slope) <= 0.2
    assert fit.ok and fit.conflicts == 0


def test_loop_ramp_turns_270_degrees_with_target_radius():
    a = Rail.line("A1", "Out-R", (0, 0), 0.0, 0.0, -15.0, 30, 800)
    b = Rail.line("B1", "In-R", (0, 0), np.pi / 2, 6.5, -15.0, -800, -30)
    spec = RampSpec("loop", a, b, None, -1.5 * np.pi, 2, W, 60.0, 4.0)
    fit = fit_ramp(spec, seed=1)
    _check_ends(fit)
    dense = sample_spline(fit.ctrl, 500)
    turn = np.sum(np.diff(np.unwrap(np.arctan2(dense.tangent[:, 1], dense.tangent[:, 0]))))
    assert turn == pytest.approx(-1.5 * np.pi, abs=0.02)
    rmin, smax = _measured(fit)
    assert abs(rmin - 60.0) <= 3.0 and abs(smax - 4.0) <= 0.2


@pytest.mark.parametrize("radius", [30.0, 40.0])
def test_a_fitted_loop_is_nowhere_tighter_than_its_radius_target(radius):
    """Pointwise, not only held over 10 m: a short first leg of a loop's cubic turned at
    half its target for a metre or two (30 and 40 m loops, seed 0: 0.53 x the target)
    and was reported within tolerance; a vehicle follows the curvature at every point."""
    from flyover.geometry.bezier import lane_radius

    a = Rail.line("A1", "Out-R", (0, 0), 0.0, 0.0, -15.0, 30, 800)
    b = Rail.line("B1", "In-R", (0, 0), np.pi / 2, 6.5, -15.0, -800, -30)
    spec = RampSpec("loop", a, b, None, -1.5 * np.pi, 2, W, radius, 4.0)
    for seed in range(4):
        fit = fit_ramp(spec, seed=seed)
        assert fit.ok
        point = float(lane_radius(sample_spline(fit.ctrl, 2000).curvature, W).min())
        assert point >= 0.95 * radius, (seed, point)
        assert fit.point_radius_m == pytest.approx(point, rel=0.01)
        # a fit tight at one point is not within tolerance, however well it holds its radius
        assert not replace(fit, point_radius_m=0.94 * radius).radius_ok


def test_flyover_clears_the_road_it_crosses():
    # left turn from eastbound (level 0) to northbound at level 1, across a southbound road at
    # level 1 lying between: the ramp must pass it with clearance → it needs a crest at 13 m
    a = Rail.line("A1", "Out-R", (0, -2), 0.0, 0.0, -7.5, -900, -60)
    b = Rail.line("B1", "In-R", (2, 0), np.pi / 2, 6.5, -7.5, 60, 900)
    road = [-2.0, 0.0, 0.0, -1.0, -1e5, 1e5, -7.5, 0.0, 6.5]  # B2 southbound, x = -2 .. -9.5
    obst = Obstacles(np.array([road]))
    spec = RampSpec("fly", a, b, None, np.pi / 2, 1, W, 150.0, 5.0, z_crest=13.0)
    fit = fit_ramp(spec, obst, seed=2)
    _check_ends(fit)
    assert fit.conflicts == 0
    assert fit.z_crest == 13.0
    rmin, smax = _measured(fit)
    assert abs(rmin - 150) <= 7.5 and abs(smax - 5.0) <= 0.2
    # where it crosses B2 it is at least the clearance above it
    dense = sample_spline(fit.ctrl, 400)
    z, _ = evaluate_polys(fit.elevation, dense.s.ravel())
    over = (dense.xy[:, 0] < -2.0) & (dense.xy[:, 0] > -9.5)
    assert over.any() and (z[over] - 6.5 >= 5.5 - 1e-6).all()


def _median_flyover(lead_m):
    # a left exit into the median of eastbound A1 (z 0, attached at x 0..5) turning north
    # onto B1 (z 6.5, at x 480), across westbound A2 (z 0) beside the median: at 2 % the
    # ramp is 5.5 m up only after ~315 m, so it has to climb beside A1 before it turns
    a = Rail.line("A1", "Out-L", (0, 0), 0.0, 0.0, W, 0.0, 5.0)
    b = Rail.line("B1", "In-R", (480, 0), np.pi / 2, 6.5, -7.5, 60, 800)
    a2 = [-1e4, 4.0, 1.0, 0.0, -1e5, 1e5, 0.0, 11.25, 0.0]  # A2: y = 4 .. 15.25
    return RampSpec("fly", a, b, None, np.pi / 2, 1, W, 150.0, 2.0, None, lead_m), \
        Obstacles(np.array([a2]))


def test_a_flyover_climbs_along_its_road_on_a_straight_lead_before_it_turns():
    spec, obst = _median_flyover((400.0, 60.0))
    fit = fit_ramp(spec, obst, seed=1)
    assert fit.ok and fit.conflicts == 0
    _check_ends(fit)
    assert fit.ctrl.shape[0] == spec.pieces + 2  # a lead piece at each end
    lead = fit.ctrl[0]
    assert np.allclose(lead[:, 1], lead[0, 1], atol=1e-9)  # straight, along A1's heading
    assert 1.0 <= lead[3, 0] - lead[0, 0] <= 400.0
    tail = fit.ctrl[-1]
    assert np.allclose(tail[:, 0], tail[3, 0], atol=1e-9)  # straight, along B1's heading
    assert conflicts_with(fit, obst, FitSettings()) == {}
    # one cubic that turns at once meets A2 before it has climbed: it is A2 it meets,
    # with as many samples as the search counts
    plain = replace(spec, lead_m=(None, None))
    early = measure(plain, np.array([2.5, 300.0, 0.3, 0.3]), obst, FitSettings())
    assert early.conflicts > 0 and not early.ok
    assert conflicts_with(early, obst, FitSettings()) == {"road 0": early.conflicts}


def test_inf_radius_turn_is_the_gentlest_curve_and_never_tighter_than_the_floor():
    spec = _right_turn(math.inf, 3.0)
    fit = fit_ramp(spec, seed=2)
    _check_ends(fit)
    rmin, smax = _measured(fit)
    # no tighter than the radius an inf ramp is built with (a 90° turn: 356 m)
    assert rmin > spec.inf_floor_m == FitSettings().inf_reference_m
    assert fit.radius_ok and fit.ok
    assert abs(smax - 3.0) <= 0.2
    # a kink (or any curve tighter than the floor) is no "straight" ramp
    assert not replace(fit, min_radius_m=0.95 * spec.inf_floor_m - 0.1).radius_ok
    assert replace(fit, min_radius_m=spec.inf_floor_m).radius_ok


def test_an_inf_target_is_met_as_the_benchmark_reads_the_exported_xodr():
    """One reading of ``inf`` (flyover.geometry.straight.inf_met): the fit accepted an
    ``inf`` target at 0.95 × 30 m (``geometry.inf_min_radius_m``), the benchmark only at
    0.95 × 250 m, so Columbus's ``r12`` was "ok" with a 29–117 m reverse bend that the
    radius re-measured from the .xodr counted as a miss."""
    import importlib.util
    from pathlib import Path

    path = Path(__file__).resolve().parents[1] / "benchmarks" / "geometry.py"
    mod_spec = importlib.util.spec_from_file_location("geometry_bench", path)
    bench = importlib.util.module_from_spec(mod_spec)
    mod_spec.loader.exec_module(bench)
    spec = _right_turn(math.inf, 3.0)
    fit = fit_ramp(spec, seed=2)
    for r in (29.0, 117.0, 237.0, 238.0, 1066.0):
        row = {"target_radius_m": math.inf, "xodr_radius_m": r, "target_slope_pct": 3.0,
               "xodr_slope_pct": 3.0}
        ok = replace(fit, min_radius_m=r, point_radius_m=r).radius_ok
        assert ok == bench.agrees(row, FitSettings().inf_reference_m)[0] == (r >= 237.5)


def test_inf_radius_candidates_below_the_floor_are_penalised_and_not_acceptable():
    from flyover.geometry.fit import _decode, bounds, ramp_objective

    spec = replace(_right_turn(math.inf, 3.0), inf_floor_m=400.0)
    lo, hi = np.array(bounds(spec)).T
    x = lo[:, None] + (hi - lo)[:, None] * np.random.default_rng(1).random((len(lo), 40))
    f, terms = ramp_objective(spec, Obstacles(), FitSettings())
    t = terms(x)
    rmin = _held(sample_spline(_decode(spec, x).ctrl, FitSettings().samples), W)
    assert np.allclose(t["rad_err"], np.minimum(rmin - 400.0, 0.0) / 400.0, rtol=1e-9)
    below = rmin < 0.98 * 400.0
    assert below.any() and not f.acceptable(f.table(x))[below].any()


def test_same_level_ramp_cannot_meet_a_slope_and_says_so():
    a = Rail.line("A1", "Out-R", (0, 0), 0.0, 0.0, -15.0, -600, -200)
    b = Rail.line("A1", "In-R", (0, 0), 0.0, 0.0, -15.0, 200, 600)
    fit = fit_ramp(RampSpec("cd", a, b, None, 0.0, 2, W, 300.0, 3.0), seed=0)
    assert fit.max_slope_pct == 0.0
    assert not fit.slope_ok and not fit.ok


def test_same_seed_gives_the_same_curve():
    f1 = fit_ramp(_right_turn(100.0, 4.0), seed=5)
    f2 = fit_ramp(_right_turn(100.0, 4.0), seed=5)
    assert np.array_equal(f1.ctrl, f2.ctrl)


def test_vectorized_and_plain_de_reach_the_same_tolerance():
    plain = fit_ramp(_right_turn(100.0, 4.0), settings=FitSettings(vectorized=False), seed=4)
    assert plain.ok


def test_heading_vec_is_unit():
    assert np.allclose(np.linalg.norm(heading_vec(np.linspace(0, 7, 9)), axis=-1), 1.0)


def test_evolve_is_seeded_stays_in_bounds_and_finds_the_minimum():
    from flyover.geometry.fit import evolve

    seen = []

    def f(x):  # shifted sphere with a ridge; x is (D, P)
        seen.append(x.copy())
        return ((x - 0.3) ** 2).sum(0) + np.abs(x[0] - x[1])

    bounds = [(-1.0, 1.0)] * 5
    a = evolve(f, bounds, 8, 300, seed=11)
    b = evolve(f, bounds, 8, 300, seed=11)
    c = evolve(f, bounds, 8, 300, seed=12)
    assert np.array_equal(a.x, b.x) and a.evaluations == b.evaluations
    assert not np.array_equal(a.x, c.x)
    assert a.fun < 1e-8 and np.allclose(a.x, 0.3, atol=1e-4)
    allx = np.concatenate(seen, axis=1)
    assert allx.min() >= -1.0 and allx.max() <= 1.0


def test_evolve_stops_on_request_and_returns_the_chosen_candidate():
    from flyover.geometry.fit import evolve

    def stop(pop, energy, gen):
        return int(np.argmax(energy)) if gen == 3 else None  # pick the worst, on purpose

    r = evolve(lambda x: (x**2).sum(0), [(-1.0, 1.0)] * 3, 5, 100, seed=1, stop=stop,
               init=np.zeros((1, 3)))
    assert r.generations == 3
    assert r.fun > 0.0  # the zero vector given as init is the best, but not the one chosen


def test_compiled_objective_kernel_matches_the_numpy_reference():
    """The numba kernel measures candidates exactly as bezier/profile do in numpy."""
    from flyover.geometry import _kernels
    from flyover.geometry.bezier import turning
    from flyover.geometry.profile import heights

    rng = np.random.default_rng(4)
    p, n_p, m = 40, 2, 24
    ctrl = rng.normal(0.0, 120.0, (p, n_p, 4, 2))
    ctrl[:, 1, 0] = ctrl[:, 0, 3]  # joined pieces
    za, zb = rng.uniform(0, 7, p), rng.uniform(0, 7, p)
    zc = np.maximum(np.maximum(za, zb), 13.0)
    empty = Obstacles()
    args = (15.0, 1.5, 5.5, np.zeros((0, 9))) + empty.grid(10.0)
    length, rmin, turn, kvar, k2, g2, conf, depth = _kernels.spline_terms(
        ctrl, m, W, za, zc, zb, 0.04, 40.0, *args)
    ref = sample_spline(ctrl, m)
    assert np.allclose(length, ref.length, rtol=1e-12)
    assert np.allclose(rmin, _held(ref, W), rtol=1e-9)
    assert np.allclose(turn, turning(ref.tangent), atol=1e-9)
    assert np.allclose(kvar, ref.curvature.var(-1), rtol=1e-6, atol=1e-12)
    assert np.allclose(k2, (ref.curvature ** 2).mean(-1), rtol=1e-9)
    kk = ref.curvature.reshape(p, n_p, m)
    assert np.allclose(g2, ((kk[:, 1:, 0] - kk[:, :-1, -1]) ** 2).sum(-1), rtol=1e-9)
    assert not conf.any() and not depth.any()
    # heights enter through the conflicts: a road band at each candidate's mid-height is
    # met exactly where the numpy grade line is within the clearance of it; each sample
    # stands for the straight stretch from the previous one (heights and stations linear)
    z = heights(ref.s, ref.length, za, zc, zb, 0.04, 40.0)
    for i in range(3):
        zl = float(z[i, m])
        road = np.array([[-1e4, -1e4, 1.0, 0.0, -1e5, 1e5, -1e5, 1e5, zl]])  # covers the plane
        got = _kernels.spline_terms(ctrl[i:i + 1], m, W, za[i:i + 1], zc[i:i + 1], zb[i:i + 1],
                                    0.04, 40.0, 15.0, 1.5, 5.5, road, *empty.grid(10.0))
        count, deep = 0, 0.0
        for j in range(n_p * m):
            jp = max(j - 1, 0)
            # the part of the stretch outside the end zones (s is linear along it)
            s0, s1, z0, z1 = ref.s[i, jp], ref.s[i, j], z[i, jp], z[i, j]
            t = np.array([0.0 if j else 1.0, 1.0])
            if s1 != s0:
                lim = np.sort([(15.0 - s0) / (s1 - s0), (ref.length[i] - 15.0 - s0) / (s1 - s0)])
                t = np.array([max(t[0], lim[0]), min(t[1], lim[1])])
            elif not 15.0 < s0 < ref.length[i] - 15.0:
                continue
            if t[0] > t[1]:
                continue
            ze = z0 + t * (z1 - z0)
            # deep in a band that covers the plane: the way out is up or down, shortest
            # where the stretch comes nearest the road's height
            near = 0.0 if (ze.min() <= zl <= ze.max()) else np.abs(ze - zl).min()
            if near < 5.5:
                count += 1
                deep += 5.5 - near
        assert count > 0 and got[6][0] == count
        assert got[7][0] == pytest.approx(deep, rel=1e-9)


def test_objective_terms_follow_their_definition_on_the_decoded_curves():
    """The compiled terms equal the objective's definition computed in numpy from the
    decoded control points (flyover across a road, so the crest and conflicts count)."""
    from flyover.geometry import _kernels
    from flyover.geometry.fit import _decode, bounds, ramp_objective
    from flyover.geometry.profile import climb_distance

    a = Rail.line("A1", "Out-R", (0, -2), 0.0, 0.0, -7.5, -900, -60)
    b = Rail.line("B1", "In-R", (2, 0), np.pi / 2, 6.5, -7.5, 60, 900)
    road = np.array([[-2.0, 0.0, 0.0, -1.0, -1e5, 1e5, -7.5, 0.0, 6.5]])
    settings = FitSettings()
    spec = RampSpec("fly", a, b, None, np.pi / 2, 2, W, 150.0, 3.0, z_crest=13.0)
    lo, hi = np.array(bounds(spec)).T
    x = lo[:, None] + (hi - lo)[:, None] * np.random.default_rng(5).random((len(lo), 30))
    f, terms = ramp_objective(spec, Obstacles(road), settings)
    t = terms(x)

    dec = _decode(spec, x)
    ref = sample_spline(dec.ctrl, settings.samples)
    za, zb = dec.a[3], dec.b[3]
    zc = np.maximum(np.maximum(za, zb), 13.0)
    need = climb_distance(zc - za, 0.03, 40.0) + climb_distance(zc - zb, 0.03, 40.0)
    rmin = _held(ref, W)
    assert np.allclose(t["rad_err"], (rmin - 150.0) / 150.0, rtol=1e-9)
    assert np.allclose(t["smooth"], ref.curvature.var(-1) * 150.0 ** 2, rtol=1e-6, atol=1e-9)
    assert np.allclose(t["shortfall"], np.clip(need - ref.length, 0, None) / need, rtol=1e-9)
    l_ref = 1.2 * np.maximum(need, 150.0 * np.abs(dec.turn) + 80.0)
    assert np.allclose(t["excess"], np.clip(ref.length / l_ref - 1, 0, None), atol=1e-12)
    assert np.all(t["conflicts"] >= 0) and np.all((t["conflicts"] > 0) == (t["depth"] > 0))
    assert not t["spread"].any()  # no free end
    # the tightest lane-centre radius at any sample, against 97 % of the target
    point = np.abs(1.0 / ref.curvature + W / 2).min(-1)
    floor = (1 - _kernels.POINT_MARGIN) * 150.0
    assert np.allclose(t["spike"], np.clip(floor - point, 0, None) / floor, atol=1e-12)
    assert t["spike"].any()  # random shapes: most have a tight point
    # the energy weighs the terms as documented
    e = (100 * t["rad_err"] ** 2 + 0.05 * t["smooth"] + 20 * t["shortfall"] ** 2
         + 10 * np.clip(t["turn_err"] - 0.05, 0, None)
         + settings.conflict_weight * (t["conflicts"] + settings.depth_weight * t["depth"])
         + 0.01 * np.minimum(t["g2"], 10) + 2 * t["excess"] ** 2
         + _kernels.SPIKE_WEIGHT * (t["spike"] + 10 * t["spike"] ** 2))
    assert np.allclose(f(x), e, rtol=1e-12)
    ok = ((np.abs(t["rad_err"]) < settings.accept_radius) & (t["shortfall"] == 0)
          & (t["turn_err"] < 0.05) & (t["conflicts"] == 0) & (t["excess"] < 0.3)
          & (t["spike"] == 0))
    assert np.array_equal(f.acceptable(f.table(x)), ok)
    assert set(_kernels.TERMS) == set(t)


def test_a_crossing_between_two_samples_is_still_a_conflict():
    """Samples 10 m apart on either side of another ramp's lane (5 m from its centre,
    farther than the two half widths): the lane is followed between them, so the
    crossing counts, once, for the sample whose stretch crosses."""
    from flyover.geometry import _kernels

    x = np.arange(0.0, 101.0, 10.0)[None, :] + 0.5  # crosses x = 55.5 between 50.5 and 60.5
    y = np.zeros_like(x)
    ys = np.arange(-60.0, 60.0, _kernels.STEP_M)
    obst = Obstacles(points=np.stack([np.full_like(ys, 55.5), ys], -1), z=np.zeros(len(ys)),
                     half_width=np.full(len(ys), 1.5), owner=("b",) * len(ys))
    args = (15.0, 1.5, 5.5, np.zeros((0, 9))) + obst.grid(10.0)
    n, depth = _kernels.conflicts(x, y, x - 0.5, np.zeros_like(x), np.array([100.0]), *args)
    # the stretch from 50.5 to 60.5 runs through the obstacle point at (55.5, 0): as deep
    # as the reach (the two half widths widened by half the obstacle's point spacing:
    # sqrt(3² + 1²))
    assert n[0] == 1 and depth[0] == pytest.approx(math.sqrt(10.0))
    # 6 m above the other lane (clearance 5.5 m): no conflict
    n, _ = _kernels.conflicts(x, y, x - 0.5, np.full_like(x, 6.0), np.array([100.0]), *args)
    assert n[0] == 0


def _loop_line(rise_m, radius=60.0, step=15.0):
    """A lane centre sampled every ``step`` m: east along y = 0 to the origin, 270 degrees
    left around (0, radius), then south across its own start at x = -radius; it climbs
    ``rise_m`` between the two passes. Returns x, y, s, z ``(1, N)``, length ``(1,)``."""
    lead = 200.0
    s = np.arange(0.0, 2 * lead + 1.5 * math.pi * radius + 1e-9, step)
    arc = np.clip(s - lead, 0.0, 1.5 * math.pi * radius) / radius
    x = np.where(s < lead, s - lead, radius * np.sin(arc))
    y = np.where(s < lead, 0.0, radius - radius * np.cos(arc))
    after = s > lead + 1.5 * math.pi * radius
    x = np.where(after, -radius, x)
    y = np.where(after, radius - (s - lead - 1.5 * math.pi * radius), y)
    z = s * rise_m / (1.5 * math.pi * radius + 2 * radius)
    return x[None], y[None], s[None], z[None], np.array([s[-1]])


def test_a_loop_crossing_itself_below_the_clearance_is_a_self_conflict():
    """The kernel's own test of a ramp against itself (loops): the crossing of a loop's
    last leg over its lead-in counts when 3.5 m apart, not when 6 m apart; nor do the
    stretches next to each other, nor without a gap (ramps that cannot cross themselves)."""
    args = (15.0, 1.5, 5.5)
    n, depth = _kernels.self_conflicts(*_loop_line(3.5), *args, 8.0)
    # the two stretches (and their neighbours sharing the crossing's sample points)
    assert 1 <= n[0] <= 4 and depth[0] > 0.0
    n, _ = _kernels.self_conflicts(*_loop_line(6.0), *args, 8.0)
    assert n[0] == 0
    n, _ = _kernels.self_conflicts(*_loop_line(3.5), *args, 0.0)
    assert n[0] == 0
    x, y, s, z, length = _loop_line(0.0)
    keep = s[0] < 300.0  # the lead-in and the first quarter of the loop: no crossing
    n, _ = _kernels.self_conflicts(x[:, keep], y[:, keep], s[:, keep], z[:, keep],
                                   np.array([300.0]), *args, 8.0)
    assert n[0] == 0


def test_road_band_test_is_exact_along_the_whole_stretch():
    """Against a road band the conflict kernel tests the whole straight stretch between
    two samples: it finds what a very fine walk along it finds, and as deep (random
    stretches across a tilted band, some grazing it, some at the clearance's edge)."""
    from flyover.geometry import _kernels

    rng = np.random.default_rng(7)
    empty = Obstacles()
    h = np.pi / 5
    road = np.array([[3.0, -4.0, np.cos(h), np.sin(h), -30.0, 40.0, -7.5, 0.0, 6.5]])
    t = np.linspace(0.0, 1.0, 100001)
    hits = 0
    for _ in range(300):
        a, b = rng.uniform(-40, 40, 2), rng.uniform(-40, 40, 2)
        za, zb = rng.uniform(0.0, 13.0, 2)
        x = np.array([[a[0], b[0]]])
        y = np.array([[a[1], b[1]]])
        z = np.array([[za, zb]])
        s = np.array([[100.0, 100.0 + np.hypot(*(b - a))]])
        n, deep = _kernels.conflicts(x, y, s, z, np.array([1000.0]), 15.0, 1.5, 5.5, road,
                                     *empty.grid(10.0))
        # the same by a fine walk (the first sample stands for itself: it is never inside)
        px, py = a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])
        pz = za + t * (zb - za)
        rx, ry = px - road[0, 0], py - road[0, 1]
        along = rx * road[0, 2] + ry * road[0, 3]
        lat = road[0, 2] * ry - road[0, 3] * rx
        way = np.minimum(np.minimum(lat + 9.0, 1.5 - lat), 5.5 - np.abs(pz - 6.5))
        way = np.where((along > -30) & (along < 40), way, 0.0)
        first = max(way[0], 0.0)  # sample 0 stands for itself, sample 1 for the stretch
        walk = max(way.max(), 0.0)
        hits += walk > 0.01
        if walk == 0.0 or walk > 0.01:  # clear, or not just grazing between walk points
            assert n[0] == int(first > 0) + int(walk > 0)
            assert deep[0] == pytest.approx(first + walk, abs=0.01)
    assert hits > 20


def test_ramp_point_test_is_exact_along_the_whole_stretch():
    """Against another ramp's lane-centre points the kernel also tests the whole stretch:
    met exactly where a very fine walk along it comes within reach of a point at a
    height within the clearance (random stretches across a climbing lane)."""
    from flyover.geometry import _kernels

    rng = np.random.default_rng(8)
    xs = np.arange(-60.0, 60.0, _kernels.STEP_M)
    pts = np.stack([xs, 0.3 * xs], -1)
    pz = 6.0 + 0.05 * xs
    obst = Obstacles(points=pts, z=pz, half_width=np.full(len(xs), 1.75),
                     owner=("b",) * len(xs))
    reach = math.sqrt((1.5 + 1.75) ** 2 + (_kernels.STEP_M / 2) ** 2)
    t = np.linspace(0.0, 1.0, 20001)
    hits = 0
    for _ in range(300):
        a, b = rng.uniform(-40, 40, 2), rng.uniform(-40, 40, 2)
        za, zb = rng.uniform(0.0, 13.0, 2)
        s = np.array([[100.0, 100.0 + np.hypot(*(b - a))]])
        n, deep = _kernels.conflicts(np.array([[a[0], b[0]]]), np.array([[a[1], b[1]]]), s,
                                     np.array([[za, zb]]), np.array([1000.0]), 15.0, 1.5, 5.5,
                                     np.zeros((0, 9)), *obst.grid(10.0))
        qx, qy = a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])
        qz = za + t * (zb - za)
        d = np.hypot(qx[:, None] - pts[:, 0], qy[:, None] - pts[:, 1])
        way = np.minimum(reach - d, 5.5 - np.abs(qz[:, None] - pz)).max(1)
        first, walk = max(way[0], 0.0), max(way.max(), 0.0)
        hits += walk > 0.01
        if walk == 0.0 or walk > 0.01:  # clear, or not just grazing between walk points
            assert n[0] == int(first > 0) + int(walk > 0)
            # the depth is taken at the closest approach or the middle: at most the walk's
            assert 0.0 < deep[0] - first <= walk + 0.01 or walk == 0.0
    assert hits > 20


def test_trials_worse_than_their_parents_skip_only_what_cannot_matter():
    """The bound on a trial's energy: candidates whose energy is within their bound get
    exactly the terms they get without one; the others (their energy without conflicts
    already above it) come back with infinite energy, and their true energy is above it
    too, so a DE trial loses to its parent either way."""
    from flyover.geometry.fit import bounds, ramp_objective

    a = Rail.line("A1", "Out-R", (0, -2), 0.0, 0.0, -7.5, -900, -60)
    b = Rail.line("B1", "In-R", (2, 0), np.pi / 2, 6.5, -7.5, 60, 900)
    road = np.array([[-2.0, 0.0, 0.0, -1.0, -1e5, 1e5, -7.5, 0.0, 6.5]])
    spec = RampSpec("fly", a, b, None, np.pi / 2, 2, W, 150.0, 3.0, z_crest=13.0)
    lo, hi = np.array(bounds(spec)).T
    x = lo[:, None] + (hi - lo)[:, None] * np.random.default_rng(6).random((len(lo), 200))
    f, _ = ramp_objective(spec, Obstacles(road), FitSettings())
    full = f.table(x)
    e = f.energy(full)
    assert (full[7] > 0).sum() > 20  # many candidates do meet the road
    bound = np.quantile(e, 0.4) * np.ones(x.shape[1])
    cut = f.table(x, bound)
    e_cut = f.energy(cut)
    within = e <= bound
    assert within.sum() > 50 and (~within).sum() > 50
    assert np.array_equal(cut[:, within], full[:, within])
    skipped = np.isinf(e_cut)
    assert np.all(e[skipped] > bound[skipped]) and skipped.sum() > 0
    assert not f.acceptable(cut)[skipped].any()
    assert np.array_equal(e_cut[~skipped], e[~skipped])


def test_evolve_with_bounded_trials_takes_the_same_path():
    """Giving a DE trial that cannot beat its parent an infinite energy (what the bounded
    objective does) changes nothing: same best vector, energy and effort."""
    from flyover.geometry.fit import evolve

    def sphere(x):
        return ((x - 0.3) ** 2).sum(0) + 0.1 * np.abs(np.sin(7 * x)).sum(0)

    def bounded(x, bound=None):
        e = sphere(x)
        return e if bound is None else np.where(e > bound, np.inf, e)

    bounded.bounded = True
    a = evolve(sphere, [(-1.0, 1.0)] * 4, 4, 80, seed=5)
    b = evolve(bounded, [(-1.0, 1.0)] * 4, 4, 80, seed=5)
    assert np.array_equal(a.x, b.x) and a.fun == b.fun and a.evaluations == b.evaluations


def test_a_ramp_with_end_z_first_reaches_its_end_height_early_and_runs_on_at_it():
    """A ramp a child joins beside its road at that road's height (Columbus's r11, from r1
    at 7 m down to I-270 North, r12 joining it from the collector road's end at 0.5 m)
    descends first (``RampSpec.end_z_first``); without it the profile keeps its start's
    height as long as it can and descends just before its end, where the child found it
    7 m up (drawn set 9: r12 at 1 % came out 1.9 %)."""
    from flyover.geometry.profile import climb_distance  # noqa: PLC0415

    a = Rail.line("A1", "Out-R", (0, 0), 0.0, 6.5, -15.0, -800, -40)
    b = Rail.line("B1", "In-R", (0, 0), -np.pi / 2, 0.0, -15.0, 40, 800)
    spec = RampSpec("r", a, b, None, -np.pi / 2, 1, W, 100.0, 4.0)
    late, early = (fit_ramp(replace(spec, end_z_first=f), seed=1) for f in (False, True))
    down = float(climb_distance(6.5, 0.04, FitSettings().transition_m))
    for fit in (late, early):
        assert fit.ok and fit.length_m > down + 20.0
        assert abs(fit.max_slope_pct - 4.0) <= 0.2
        _check_ends(fit)

    def z(fit, s):
        return float(evaluate_polys(fit.elevation, np.array([s]))[0][0])

    assert z(early, down + 1.0) == pytest.approx(0.0, abs=1e-6)
    assert z(late, late.length_m - down - 1.0) == pytest.approx(6.5, abs=1e-6)
    assert z(late, down + 1.0) > 1.0
