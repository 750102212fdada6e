"""The first of a stub's two children keeps clear of the way out its sibling needs."""

import math

import numpy as np
import pytest

from flyover.geometry.check import same_level_conflicts
from flyover.geometry.fit import Rail, RampSpec, fit_ramp
from flyover.geometry.fitted import stations
from flyover.geometry.fork import departure_grade, way_out
from flyover.geometry.layout import LayoutSettings, RampFeatures, build_interchange
from flyover.geometry.state import LayoutState
from flyover.geometry.tables import sample_seed
from flyover.topology.canonical import class_id
from flyover.topology.catalog import catalog_topologies

ST = LayoutSettings()


def _child(turn, radius=100.0, slope=3.0, crest=None, at_start=True, z_end=6.5):
    """A stub's child fixed at the stub's free end (at the origin, heading +x, z 6.5, on
    its right lane: offset -4 m), its other end on a road at ``z_end``."""
    fixed = Rail.line("e", "Out-R", (0, 0), 0.0, 6.5, -4.0, 0.0, 0.0)
    road = Rail.line("A1", "In-R", (500, -500), -np.pi / 2, z_end, -15.0, 0.0, 200.0)
    a, b = (fixed, road) if at_start else (road, fixed)
    return RampSpec("r", a, b, None, turn, 1, 4.0, radius, slope, crest)


def test_the_way_out_turns_at_the_radius_target_from_the_siblings_lane_centre():
    way = way_out(_child(-np.pi / 2), True, 0.0, ST)
    assert way.ramp == "r" and way.half_width_m == 2.0
    # it starts on the lane centre, half its width right of its reference line
    assert way.xy[0] == pytest.approx((0.0, -6.0))
    # and turns right at 100 m: every point 100 m from the circle's centre
    centre = np.array([0.0, -106.0])
    assert np.hypot(*(way.xy - centre).T) == pytest.approx(100.0, abs=0.01)
    # level here (it descends at its far end), and so is a level sibling: the two
    # part in height only at 0.5 %, so it runs its whole turn (157 m)
    assert np.all(way.z == 6.5)
    assert np.hypot(*np.diff(way.xy, axis=0).T).sum() == pytest.approx(50 * np.pi, rel=1e-3)


def test_the_way_out_ends_where_the_two_are_a_clearance_apart_in_height():
    # the sibling climbs to a crest 13 m up at 4 %, the first child at 2 %: 5.5 m / 6 %
    sib = _child(-np.pi / 2, radius=280.0, slope=4.0, crest=19.5)
    assert departure_grade(sib, 6.5) == pytest.approx(0.04)
    way = way_out(sib, True, 0.02, ST)
    reach = ST.fit.clearance_m / 0.06 + ST.fit.transition_m
    assert np.hypot(*np.diff(way.xy, axis=0).T).sum() == pytest.approx(reach, rel=1e-3)
    assert way.z[0] == 6.5 and np.all(np.diff(way.z) > 0)
    # at 4 % (and a 40 m transition) it is 4 % x (reach - 20 m) up at its end
    assert way.z[-1] - 6.5 == pytest.approx(0.04 * (reach - 20.0), abs=0.05)


def test_into_a_join_the_way_runs_back_from_the_siblings_end():
    way = way_out(_child(-np.pi / 2, at_start=False), False, 0.0, ST)
    assert way.xy[0] == pytest.approx((0.0, -6.0))
    # backward (x < 0); it arrives turning right, so it came from the right (its side)
    assert np.all(way.xy[1:, 0] < 0) and way.xy[-1, 1] < way.xy[0, 1] - 90.0
    assert np.hypot(*(way.xy - np.array([0.0, -106.0])).T) == pytest.approx(100.0, abs=0.01)


def test_no_way_for_an_end_that_is_not_fixed():
    spec = _child(-np.pi / 2)
    assert way_out(spec, False, 0.0, ST) is None  # its end is a window on a road


def _state(lanes, targets, name="turbine"):
    t = catalog_topologies()[name]
    feats = {r: RampFeatures(float(a), float(b)) for r, (a, b) in targets.items()}
    return t, lanes, feats


# workflow feature sets of the catalog turbine (class c6e7ded01c5, t = 2): before the
# fork's room, rB2 missed its radius or grazed lB2 just after eB2's fork at the first try
TURBINE = {
    75: ({"A1": 3, "A2": 4, "B1": 4, "B2": 3},
         {"eA1": (40, 3), "eA2": (150, 2), "eB1": (40, 3), "eB2": (100, 1),
          "lA1": (210, 4), "lA2": (30, 2), "lB1": (40, 5), "lB2": (40, 2),
          "rA1": (60, 5), "rA2": (60, 2), "rB1": (60, 5), "rB2": (100, 3)}),
    44: ({"A1": 5, "A2": 5, "B1": 5, "B2": 4},
         {"eA1": (100, 5), "eA2": (280, 4), "eB1": (150, 4), "eB2": (40, 3),
          "lA1": (30, 5), "lA2": (210, 2), "lB1": (210, 5), "lB2": (60, 1),
          "rA1": (60, 5), "rA2": (210, 1), "rB1": (280, 4), "rB2": (280, 3)}),
}


def test_only_the_first_child_of_a_fork_reserves_its_siblings_way():
    t, lanes, feats = _state(*TURBINE[75])
    b = LayoutState(t, lanes, feats, ST, 1)
    for ramp in b.order():
        spec = b.spec(ramp, feats[ramp])
        room = b.fork_room(spec)
        if ramp in ("lA1", "lA2", "lB1", "lB2"):  # fitted before their stub's right turn
            assert [w.ramp for w in room] == ["r" + ramp[1:]]
        else:  # stubs (on roads) and the right turns (their sibling is fitted)
            assert room == ()
        b.record(ramp, fit_ramp(spec, b.obstacles(), ST.fit, seed=0))


@pytest.mark.slow
@pytest.mark.parametrize("sample", sorted(TURBINE))
def test_a_turbine_right_turn_leaves_its_fork_beside_the_left_turn_at_the_first_try(sample):
    """lB2, fitted first, swung right across rB2's start after eB2's fork (75: 3.3 m apart
    17-34 m out, 3.5 m needed; 44: 0.6 m at 25 m): rB2 grazed it at the first try. Now lB2
    keeps clear of rB2's way out, rB2 leaves beside it at the first try, and the two are
    clear at their level near the fork."""
    t, lanes, feats = _state(*TURBINE[sample])
    cid = class_id(t)
    ic = build_interchange(t, lanes, feats, class_id=cid, sample=sample,
                           seed=sample_seed(20231024, cid, sample),
                           settings=LayoutSettings(max_length_ratio=2.5))
    out = {o.ramp: o for o in ic.outcomes}
    assert out["rB2"].first_try_ok and out["lB2"].first_try_ok, out["rB2"].infeasible
    assert not same_level_conflicts(ic.geometry)
    # lane centres within 100 m of the fork, outside the end zones: at one level, the
    # two half widths (less the margin) apart at least
    (pl, zl, sl), (pr, zr, sr) = ((c["xy"], c["z"], c["s"]) for c in (
        stations(out[r].fit, 400, 2.0) for r in ("lB2", "rB2")))
    ml, mr = (sl > 15) & (sl < 100), (sr > 15) & (sr < 100)
    d = np.hypot(*(pl[ml][:, None] - pr[mr][None]).transpose(2, 0, 1))
    dz = np.abs(zl[ml][:, None] - zr[mr][None])
    assert np.where(dz < ST.fit.clearance_m, d, math.inf).min() >= 3.5
