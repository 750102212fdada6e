"""A ramp whose child attaches on the side facing its road keeps room for it there."""

import pytest

from flyover.geometry.beside import RUN_SLACK_M, child_room_fences, run_slacks
from flyover.geometry.layout import LayoutSettings, RampFeatures, build_interchange
from flyover.geometry.state import LayoutState
from flyover.topology.catalog import catalog_topologies


def _state(name):
    t = catalog_topologies()[name]
    feats = {r: RampFeatures(150.0, 4.0) for r in t.ramps}
    return LayoutState(t, {r: 3 for r in t.roads}, feats, LayoutSettings(), 1), feats


def test_j1_r1_and_r3_keep_a_lane_off_their_roads_outside_their_windows():
    b, feats = _state("j1")
    edge = 3 * b.st.lane_width_m + 0.5
    strip = b.width["r2"] + 1.0
    spec = b.spec("r1", feats["r1"])  # leaves R1 on the right, r2 leaves it on the left
    (fence,) = child_room_fences(b.moves, b.width, b.st, spec)
    assert fence[4:] == pytest.approx((spec.start.hi, 1e4, -edge - strip, -edge))
    r1 = b.roads["R1"]
    assert fence[:2] == pytest.approx(r1.origin)
    spec = b.spec("r3", feats["r3"])  # joins R4 on the right, r2 joins it on the left
    (fence,) = child_room_fences(b.moves, b.width, b.st, spec)
    assert fence[4:] == pytest.approx((-1e4, spec.end.lo, -edge - strip, -edge))
    # r4 has no child, r2 no road end
    assert child_room_fences(b.moves, b.width, b.st, b.spec("r4", feats["r4"])) == []


def test_a_run_beside_the_road_is_tried_straight_then_narrow_then_twice_as_wide():
    # Columbus's r11 (100-280 m) still turned in its run where only its first gap_m was
    # held off the edge (drawn sets 5, 16, 29, 31); at 60 m it grazed the narrow slot on
    # every try (sets 8, 14, 18, 21) and dropped the child's room
    assert run_slacks(None) == ((False, 0.0),)
    assert run_slacks((476.9, 556.9)) == ((True, 0.0), (True, RUN_SLACK_M), (False, 0.0),
                                          (False, RUN_SLACK_M))
    b, feats = _state("j1")  # no run: the slack changes nothing
    spec = b.spec("r3", feats["r3"])
    assert child_room_fences(b.moves, b.width, b.st, spec, slack=RUN_SLACK_M) == \
        child_room_fences(b.moves, b.width, b.st, spec)


def test_stubs_fork_at_their_free_end_and_keep_no_room_beside():
    b, feats = _state("stack4")
    for stub in ("eA1", "mA1"):
        assert child_room_fences(b.moves, b.width, b.st, b.spec(stub, feats[stub])) == []


@pytest.mark.parametrize("sample, seed, feats, lanes", [
    # feature sets 20 and 24 of the workflow's j1 (class cec3dc6bf72) at their seeds: r3
    # ran along R4's edge, r2 found room beside it only at its low start beside R2 and
    # met R1/R2 coming down into it on the first try
    (20, 3584184547, {"r1": (40.0, 4.0), "r2": (100.0, 2.0), "r3": (40.0, 3.0),
                      "r4": (30.0, 1.0)}, {"R1": 5, "R2": 3, "R3": 4, "R4": 4}),
    (24, 3536819450, {"r1": (100.0, 1.0), "r2": (30.0, 2.0), "r3": (40.0, 5.0),
                      "r4": (40.0, 5.0)}, {"R1": 3, "R2": 5, "R3": 3, "R4": 4}),
])
def test_j1_r2_comes_in_beside_r3_on_the_first_try(sample, seed, feats, lanes):
    t = catalog_topologies()["j1"]
    ic = build_interchange(t, lanes, {r: RampFeatures(*v) for r, v in feats.items()},
                           class_id="cec3dc6bf72", sample=sample, seed=seed)
    for o in ic.outcomes:
        assert o.first_try_ok and o.fit.conflicts == 0, (o.ramp, o.fit.min_radius_m,
                                                         o.fit.conflicts)


def test_a_run_moved_along_its_road_is_put_back_with_the_fits():
    # build._moved_run and build._swapped put the build back as it was when what they
    # tried does not hold: the runs moved for a child (run_shift) go back with the fits
    b, _ = _state("j1")
    b.fitted.run_shift["r1"] = 75.0
    kept = b.fitted.saved()
    b.fitted.run_shift["r1"] = 150.0
    b.fitted.run_shift["r3"] = 30.0
    b.fitted.fits["r2"] = None  # a stand-in fit: restore only has to forget it
    b.fitted.restore(kept)
    assert b.fitted.run_shift == {"r1": 75.0}
    assert "r2" not in b.fitted.fits
