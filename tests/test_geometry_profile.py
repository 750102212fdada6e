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
    # the grade changes no faster than a vertical curve of the target grade over 40 m
    assert np.abs(np.diff(g) / np.diff(s)).max() <= grade / 40.0 + 1e-9


def test_level_ends_give_the_profile_the_search_assumes():
    s = np.linspace(0.0, 800.0, 1601)
    polys = elevation_polys(800.0, 0.0, 13.0, 6.5, 0.04, 40.0)
    z, _ = evaluate_polys(polys, s)
    assert np.allclose(z, heights(s[None], np.array([800.0]), 0.0, 13.0, 6.5, 0.04, 40.0)[0],
                       atol=1e-9)
    assert polys == elevation_polys(800.0, 0.0, 13.0, 6.5, 0.04, 40.0, 0.0, 0.0)
