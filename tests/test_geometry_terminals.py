"""The two branches of a T's terminal keep to their own side until they are levels apart."""

import pytest

from flyover.geometry.layout import LayoutSettings, RampFeatures, build_interchange
from flyover.geometry.state import LayoutState
from flyover.geometry.terminals import terminal_fences
from flyover.topology.catalog import catalog_topologies


def _state(name):
    t = catalog_topologies()[name]
    feats = {r: RampFeatures(150.0, 4.0) for r in t.ramps}
    return LayoutState(t, {r: 3 for r in t.roads}, feats, LayoutSettings(), 1)


@pytest.mark.parametrize("name", ["directional_t", "semidirectional_t", "trumpet"])
def test_each_branch_of_a_terminal_is_fenced_off_its_siblings_side(name):
    b = _state(name)
    edge = 3 * b.st.lane_width_m
    reach = b.st.fit.clearance_m / 0.08 + b.st.fit.transition_m  # both at 4 %
    left, median = terminal_fences(b.moves, b.features, b.st, "rL")  # B1 straight on
    (right,) = terminal_fences(b.moves, b.features, b.st, "rR")  # B1 right @1
    t_hi = b.roads["B1"].t_hi
    for fence in (left, median, right):  # beyond B1's end, as far as they part in height
        assert fence[4:6] == pytest.approx((t_hi, t_hi + reach))
    assert left[6:] == pytest.approx((-1e4, -edge - 0.5))  # the straight one: not right
    assert median[6:] == pytest.approx((0.5, 1e4))  # nor across the median
    assert right[6:] == pytest.approx((-edge + 0.5, 1e4))  # the right turn: not left
    if name == "trumpet":  # rA1 joins the loop, not a terminal
        assert terminal_fences(b.moves, b.features, b.st, "rA1") == []
    else:  # B2 begins from rA2 (straight on) and rA1 (on its right at 0)
        merge, median = terminal_fences(b.moves, b.features, b.st, "rA2")
        (joins,) = terminal_fences(b.moves, b.features, b.st, "rA1")
        t_lo = b.roads["B2"].t_lo
        assert merge[4:6] == joins[4:6] == pytest.approx((t_lo - reach, t_lo))
        assert merge[6:] == pytest.approx((-1e4, -edge - 0.5))
        assert median[6:] == pytest.approx((0.5, 1e4))
        assert joins[6:] == pytest.approx((-edge + 0.5, 1e4))


def test_directional_t_right_turn_leaves_the_terminal_beside_the_left_turn_first_try():
    # feature set 4 of the workflow's directional_t (class c61ccb6e6aa), at its seed: the
    # left turn rL, fitted first, swung out to the right of B1's end to gain height, and
    # the right turn rR could not leave beside it at its 210 m radius on the first try
    t = catalog_topologies()["directional_t"]
    lanes = {"A1": 3, "A2": 5, "B1": 5, "B2": 4}
    feats = {"rA1": RampFeatures(100.0, 1.0), "rA2": RampFeatures(280.0, 4.0),
             "rL": RampFeatures(40.0, 2.0), "rR": RampFeatures(210.0, 3.0)}
    ic = build_interchange(t, lanes, feats, class_id="c61ccb6e6aa", sample=4,
                           seed=4219136739)
    for o in ic.outcomes:
        assert o.first_try_ok and o.fit.conflicts == 0, (o.ramp, o.fit.min_radius_m,
                                                         o.fit.conflicts)
