"""Vertical profiles with end grades (flyover.geometry.profile)."""

import numpy as np
import pytest

from flyover.geometry.profile import elevation_polys, evaluate_polys, heights


def _profile(length, z0, zc, z1, grade, g0=0.0, g1=0.0):
    polys = elevation_polys(length, z0, zc, z1, grade, 40.0, g0, g1)
    s = np.linspace(0.0, length, 40001)
    z, g = evaluate_polys(polys, s)
    return polys, s, z, g


@pytest.mark.parametrize("z0, zc, z1, g0, g1", [
    (0.0, 6.5, 6.5, 0.04, 0.0),    # leaves a parent climbing as it does
    (0.0, 6.5, 6.5, -0.03, 0.0),   # leaves a parent descending: dips, then climbs
    (6.5, 13.0, 3.5, 0.0, 0.02),   # descends into a parent climbing: a sag at the end
    (6.5, 6.5, 0.0, 0.04, 0.0),    # leaves a climbing parent at its own crest: crest curve
    (0.0, 0.5, 0.0, 0.02, 0.01),   # a short climb, both ends on grades
    (6.5, 6.5, 6.5, 0.03, -0.02),
])
def test_profile_starts_and_ends_at_the_given_grades_smoothly(z0, zc, z1, g0, g1):
    grade = 0.04
    polys, s, z, g = _profile(600.0, z0, zc, z1, grade, g0, g1)
    assert z[0] == pytest.approx(z0, abs=1e-9) and z[-1] == pytest.approx(z1, abs=1e-9)
    assert g[0] == pytest.approx(g0, abs=1e-12) and g[-1] == pytest.approx(g1, abs=1e-12)
    assert np.abs(g).max() <= max(grade, abs(g0), abs(g1)) + 1e-9
    # continuous in height and grade at every record boundary
    for p in polys[1:]:
        zl, gl = evaluate_polys(polys, np.array([p.s_m - 1e-9]))
        zr, gr = evaluate_polys(polys, np.array([p.s_m]))
        assert abs(zl[0] - zr[0]) < 1e-6 and abs(gl[0] - gr[0]) < 1e-6
    # the grade changes no faster than a vertical curve of the target grade over 40 m, or
    # than a climb from level of its shortest rise to the crest (whose curves shrink to
    # rise / grade: 0.5 m in the short climb, 0.45 m in the last case)
    rise = min(r for r in (z.max() - z0, z.max() - z1) if r > 1e-9)
    assert np.abs(np.diff(g) / np.diff(s)).max() <= max(grade / 40.0, grade**2 / rise) + 1e-9


@pytest.mark.parametrize("g0", [1e-6, 1e-4, 5e-4])
def test_a_short_climb_from_a_slight_grade_reaches_the_target_as_from_level(g0):
    # cloverstack 38's oA2: 1 m from its stub's free end at 0.05 %, 3 % target
    _, s, z, g = _profile(300.0, 5.5, 6.5, 6.5, 0.03, g0)
    _, _, z_level, g_level = _profile(300.0, 5.5, 6.5, 6.5, 0.03)
    assert g.max() == pytest.approx(0.03, abs=1e-4)
    # and differs from it by as little as the start grade: the climb starts g0 * 33 m early
    assert np.abs(z - z_level).max() <= 40.0 * g0 and np.abs(g - g_level).max() <= 2.0 * g0


def test_levelling_off_from_the_parents_grade_keeps_the_gentle_curve():
    # leaves a parent climbing 3 % at the crest where that grade runs out (+0.45 m):
    # one curve of 30 m from 3 % to level at 0.04 / 40 per metre, never steeper than 3 %
    polys, s, z, g = _profile(600.0, 6.5, 6.5, 6.5, 0.04, 0.03)
    assert g.max() == pytest.approx(0.03, abs=1e-12)
    leg = s <= 100.0  # (the descent to 6.5 m at the level end is a short climb from level)
    assert np.abs(np.diff(g[leg]) / np.diff(s[leg])).max() <= 0.04 / 40.0 + 1e-9
    assert polys[1].s_m == pytest.approx(30.0) and polys[1].a == pytest.approx(6.95)


def test_level_ends_give_the_profile_the_search_assumes():
    s = np.linspace(0.0, 800.0, 1601)
    polys = elevation_polys(800.0, 0.0, 13.0, 6.5, 0.04, 40.0)
    z, _ = evaluate_polys(polys, s)
    assert np.allclose(z, heights(s[None], np.array([800.0]), 0.0, 13.0, 6.5, 0.04, 40.0)[0],
                       atol=1e-9)
    assert polys == elevation_polys(800.0, 0.0, 13.0, 6.5, 0.04, 40.0, 0.0, 0.0)


def test_a_climb_of_nanometres_is_none():
    # Columbus's r13 (workflow set 26) left r8 at a grade of 1.6e-5 and so ended 5.3e-9 m
    # under the plateau that made: the climb down to its end height was two pieces
    # 5e-9 m long with c = -+9.4e7, and its grade read at its end 2e6 pp (in the .xodr too)
    length, g0 = 1245.9284659518212, 1.628049073308413e-05
    polys = elevation_polys(length, 0.5, 0.5, 0.5, 0.01, 40.0, g0=g0)
    assert max(abs(p.c) for p in polys) < 1.0
    s = np.linspace(0.0, length, 5001)
    z, g = evaluate_polys(polys, s)
    assert np.abs(z - 0.5).max() < 1e-5 and np.abs(g).max() < 1e-4
