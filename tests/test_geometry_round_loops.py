"""Outer connectors go round their loops: where they attach, and C-D roads' pairs (issue 18)."""

import math

import numpy as np

from flyover.geometry.build import _fit_with_levels
from flyover.geometry.check import ramp_crossings
from flyover.geometry.feasibility import round_loops
from flyover.geometry.layout import LayoutSettings, RampFeatures, build_interchange
from flyover.geometry.state import LayoutState
from flyover.topology.catalog import catalog_topologies

#: the workflow's cloverleaf feature set 1 (results/features, sampling version 4)
CLOVER_1_LANES = {"A1": 5, "A2": 3, "B1": 5, "B2": 5}
CLOVER_1 = {"lA1": (100.0, 3.0), "lA2": (150.0, 3.0), "lB1": (150.0, 4.0), "lB2": (40.0, 4.0),
            "oA1": (210.0, 3.0), "oA2": (60.0, 3.0), "oB1": (210.0, 4.0), "oB2": (150.0, 3.0)}


def test_a_connector_needs_its_45_degree_run_to_get_out_from_its_road():
    from flyover.geometry.loop_room import round_need  # noqa: PLC0415

    r = 100.0
    turn = (1 - math.cos(math.pi / 4)) * r
    need = round_need(np.array([0.0, turn / 2, turn, 2 * r]), r)
    # along its arc near the road, then a metre along for each metre out
    assert need[0] == 0.0
    assert math.isclose(need[1], math.sqrt(r**2 - (r - turn / 2) ** 2))
    assert math.isclose(need[2], r * math.sin(math.pi / 4))
    assert math.isclose(need[3] - need[2], 2 * r - turn)
    # a lone arc (the old rule) would be back at the road's normal after r along: the
    # loop's far side, 2 r out, is 2.41 r along at 45 degrees
    assert need[3] > 2.4 * r


def test_a_cloverleaf_connector_attaches_beyond_its_loops_far_side_at_45_degrees():
    """Cloverleaf feature set 1: the loop lA1 (100 m) reaches ~210 m out from A1 and ~330 m
    along it; the connector oB2 (150 m) joining A1 after it was allowed to attach where a
    lone 150 m arc clears every point of the loop (~490 m along A1), but no connector
    running from B2 to there passes outside the loop's far side: every fit round the loop
    missed (2 samples inside it), and the build took it over the loop at 13 m. Now its
    window on A1 begins where a connector turning to 45 degrees and running straight on
    clears every loop point, and it goes round."""
    t = catalog_topologies()["cloverleaf"]
    st = LayoutSettings()
    feats = {r: RampFeatures(*v) for r, v in CLOVER_1.items()}
    b = LayoutState(t, CLOVER_1_LANES, feats, st, 4154944655)
    order = b.order()
    for ramp in order[: order.index("oB2")]:  # what is fitted before it (lA1 among them)
        fit, _, _ = _fit_with_levels(b, b.spec(ramp, feats[ramp]), 1)
        b.record(ramp, fit)
    assert "lA1" in b.fits and b.windows.loops.round_loops("oB2") == {"lA1"}
    end = b.spec("oB2", feats["oB2"]).end  # its window on A1
    a1 = b.roads["A1"]
    d = np.array([math.cos(a1.heading), math.sin(a1.heading)])
    rel = b.fitted.stations["lA1"]["centre"] - np.array(a1.origin)
    along = rel @ d
    out = np.clip(-(rel @ np.array([-d[1], d[0]])) - a1.lanes * st.lane_width_m, 0, None)
    c = b.width["oB2"] + b.width["lA1"] / 2 + 1.0
    # beyond every loop point by its distance out and the room between them, and the
    # 45 degree arc's (sin 45 - 1 + cos 45) r = 0.41 r: ~601 m (a lone arc: ~489 m)
    assert end.lo >= float(np.max(along + out + c)) + 0.41 * 150.0
    start = b.spec("oB2", feats["oB2"]).start  # and before the loop's B2 side likewise
    assert start.hi < -500.0


def test_a_cloverleaf_connector_goes_round_a_loop_reaching_far_out():
    """The same feature set built as the workflow builds it (its seed): oB2 went over lA1
    (a bridge the design does not have, ``ramp_crossings``); now round it, within its
    targets, and so does every other connector."""
    _assert_all_round("cloverleaf", CLOVER_1, CLOVER_1_LANES, seed=4154944655)


def _assert_all_round(design: str, targets: dict, lanes: dict, seed: int) -> None:
    """Built with ``seed``, every outer connector of ``design`` goes round its loop (no
    bridge between them, ``ramp_crossings``) and every ramp is within its targets."""
    t = catalog_topologies()[design]
    feats = {r: RampFeatures(*v) for r, v in targets.items()}
    ic = build_interchange(t, lanes, feats, seed=seed)
    crossed = {frozenset((c.ramp, c.other)) for c in ramp_crossings(ic.geometry)}
    for p in round_loops(t):
        assert frozenset((p.connector, p.loop)) not in crossed, p
    assert all(o.fit.ok and o.fit.conflicts == 0 for o in ic.outcomes)


def test_cloverleaf_cd_connectors_go_round_the_loops_between_their_cd_roads():
    """cloverleaf_cd's connectors and loops leave and join collector-distributor roads
    (ramps), so no (connector, loop) pair was found: neither sampling nor the layout kept
    its connectors wider than, or round, its loops. Through the C-D roads (each counts as
    the carriageway it runs beside) they pair as cloverleaf's do, quadrant by quadrant
    (oA1 from cA1 beside A1 to cB1 beside B1 round lB1 from cB1 to cA1), and each
    connector is fitted after its loop, with the loop kept out at every height."""
    t = catalog_topologies()["cloverleaf_cd"]
    pairs = [(p.connector, p.loop) for p in round_loops(t)]
    assert pairs == [("oA1", "lB1"), ("oA2", "lB2"), ("oB1", "lA2"), ("oB2", "lA1")]
    st = LayoutSettings()
    feats = {r: RampFeatures(math.inf, 0.0) if r.startswith("c") else
             RampFeatures(150.0 if r.startswith("o") else 60.0, 4.0) for r in t.ramps}
    b = LayoutState(t, {}, feats, st, 0)
    order = b.order()
    for connector, loop in pairs:
        assert b.moves.is_outer_connector(connector, loop)
        assert order.index(loop) < order.index(connector)
    for ramp in order[: order.index("oA1")]:
        fit, _, _ = _fit_with_levels(b, b.spec(ramp, feats[ramp]), 1)
        b.record(ramp, fit)
    assert b.windows.loops.round_loops("oA1") == {"lB1"}


def _cd_state(feats):
    """cloverleaf_cd laid out as the build lays it out, up to (not including) oA1."""
    from flyover.geometry.build import _collector  # noqa: PLC0415

    t = catalog_topologies()["cloverleaf_cd"]
    b = LayoutState(t, {}, feats, LayoutSettings(), 7)
    order = b.order()
    for ramp in order[: order.index("oA1")]:
        spec = b.spec(ramp, feats[ramp])
        fit = _collector(b, ramp, spec) if b.moves.same_road(ramp) else None
        if fit is None or not fit.ok:
            fit, _, _ = _fit_with_levels(b, spec, 1)
        b.record(ramp, fit)
    return b


def _along(b, road, xy):
    r = b.roads[road]
    return (np.asarray(xy) - np.array(r.origin)) @ np.array([math.cos(r.heading),
                                                              math.sin(r.heading)])


def test_a_loop_on_a_cd_road_keeps_near_the_crossing_and_its_connector_goes_beyond_it():
    """A loop's window on a C-D road was 15 % of the road either side of its ``pos``: on a
    2 km C-D road it joined cA1 up to ~500 m before the crossing and swept the quadrant,
    and its connector, in its own 15 %, had no room outside it. Now the loop attaches
    within ``stub_window_m`` beyond the crossing's room, as on a road, and the connector
    where it clears it at 45 degrees (``round_loop`` along A1, as stations of cA1)."""
    t = catalog_topologies()["cloverleaf_cd"]
    feats = {r: RampFeatures(math.inf, 0.0) if r.startswith("c") else
             RampFeatures(210.0 if r.startswith("o") else 100.0, 4.0) for r in t.ramps}
    b = _cd_state(feats)
    st = b.st
    other = max(r.half_width for r in b.roads.values() if r.expressway != b.roads["A1"].expressway)
    tz = other + st.crossing_margin_m
    cd = b.fitted.stations["cA1"]
    joins = b.fits["lB1"].end_s  # station of cA1 where lB1 joins it
    t_join = float(np.interp(joins, cd["s"], _along(b, "A1", cd["xy"])))
    assert -tz - st.stub_window_m - 1.0 <= t_join <= -tz + 1.0
    start = b.spec("oA1", feats["oA1"]).start  # oA1 leaves cA1 before lB1 joins it
    bound = b.windows.loops.round_loop("lB1", "A1", b.width["oA1"], -1, feats["oA1"])
    t_hi = float(np.interp(start.hi, cd["s"], _along(b, "A1", cd["xy"])))
    assert t_hi <= bound + 1.0


#: the workflow's cloverleaf_cd feature set 2 (results/features, sampling version 5):
#: 280 m connectors round 210 m loops in every quadrant
CD_2_LANES = {"A1": 5, "A2": 3, "B1": 5, "B2": 5}
CD_2 = {"cA1": (210.0, 0.0), "cA2": (210.0, 0.0), "cB1": (210.0, 0.0), "cB2": (210.0, 0.0),
        "lA1": (210.0, 5.0), "lA2": (210.0, 1.0), "lB1": (210.0, 1.0), "lB2": (210.0, 3.0),
        "oA1": (280.0, 5.0), "oA2": (280.0, 4.0), "oB1": (280.0, 4.0), "oB2": (280.0, 5.0)}


def test_a_cd_road_runs_straight_to_where_its_wide_connector_clears_its_loop():
    """A C-D road's straight part reached only as far as its own ramps' radii need: where
    a 280 m connector clears a 210 m loop at 45 degrees (~1,060 m before the crossing)
    lay beyond it, so oA1's window on cA1 could not end there and it was lifted over
    lB1. Now the C-D road runs straight that far (``LevelPlan.collector_room``), and the
    window ends where the connector clears the loop, on the straight part."""
    feats = {r: RampFeatures(*v) for r, v in CD_2.items()}
    b = _cd_state(feats)
    cd = b.fitted.stations["cA1"]
    t_cd = np.maximum.accumulate(_along(b, "A1", cd["xy"]))
    start = b.spec("oA1", feats["oA1"]).start
    bound = b.windows.loops.round_loop("lB1", "A1", b.width["oA1"], -1, feats["oA1"])
    assert bound < -1000.0  # the loop reaches far out: the connector leaves early
    t_lo, t_hi = (float(np.interp(s, cd["s"], t_cd)) for s in (start.lo, start.hi))
    assert t_hi <= bound + 1.0 and t_hi - t_lo >= 1.0
    # on the straight part: cA1 runs beside A1 there (its reverse curve lies before)
    heading = np.interp(start.hi, cd["s"], cd["heading"])
    assert abs(heading - b.roads["A1"].heading) < 1e-6
    room = b.levels.collector_room("cA1")
    assert room[0] > 1000.0 and room[1] > 1000.0  # oB2 joins it after lA1 leaves: the same


def test_cloverleaf_cd_wide_connectors_go_round_their_loops():
    """Feature set 2 built as the workflow builds it (its seed): all four 280 m connectors
    went over their 210 m loops; now each goes round, within its targets."""
    _assert_all_round("cloverleaf_cd", CD_2, CD_2_LANES, seed=2726180586)


def test_a_cd_roads_round_room_follows_the_pair_at_each_end():
    """Each end of a C-D road is sized by the pair attached there: cA1's start by oA1
    leaving it round lB1, its end by oB2 joining it round lA1; a narrower pair at one end
    needs less room there and leaves the other end as it was. A ramp that is no C-D road
    gets none."""
    t = catalog_topologies()["cloverleaf_cd"]
    feats = {r: RampFeatures(*v) for r, v in CD_2.items()}
    wide = LayoutState(t, CD_2_LANES, feats, LayoutSettings(), 7).levels
    assert wide.collector_room("oA1") == (0.0, 0.0)
    small = dict(feats, oA1=RampFeatures(150.0, 5.0), lB1=RampFeatures(40.0, 5.0))
    narrow = LayoutState(t, CD_2_LANES, small, LayoutSettings(), 7).levels
    assert narrow.collector_room("cA1")[0] < wide.collector_room("cA1")[0] - 300.0
    assert narrow.collector_room("cA1")[1] == wide.collector_room("cA1")[1]


def test_a_cd_road_end_with_a_narrow_pair_is_as_long_as_that_pair_needs():
    """Both ends of a C-D road ran straight for twice its widest ramp's radius: a 40 m
    connector round a 30 m loop had ~1 km of C-D road before the crossing because the
    connector at its other end was 280 m wide. Each end with a pair now runs straight as
    far as that pair's connector needs to go round its loop, shorter here, longer for the
    wide pair at the other end."""
    feats = {r: RampFeatures(*v) for r, v in CD_2.items()}
    feats |= {"oA1": RampFeatures(40.0, 5.0), "lB1": RampFeatures(30.0, 5.0)}
    b = _cd_state(feats)
    st = b.st
    before, after = b.levels.collector_room("cA1")
    theta = math.acos(1.0 - st.cd_offset_m / (2.0 * 210.0))
    s_curve = 2.0 * 210.0 * math.sin(theta)
    t_cd = _along(b, "A1", b.fitted.stations["cA1"]["xy"])
    assert math.isclose(t_cd[0], -(before + s_curve), abs_tol=1.0)
    assert math.isclose(t_cd[-1], after + s_curve, abs_tol=1.0)
    # its own ramps' radii alone: twice the widest (280 m) beyond the rails' inner end
    own = b.spec("cA1", feats["cA1"]).start.hi - s_curve - 2.0 * (280.0 + st.gap_m)
    assert t_cd[0] > own + 300.0 and after > before + 300.0
    # and oA1 still leaves it where it goes round lB1
    start = b.spec("oA1", feats["oA1"]).start
    bound = b.windows.loops.round_loop("lB1", "A1", b.width["oA1"], -1, feats["oA1"])
    t_hi = float(np.interp(start.hi, b.fitted.stations["cA1"]["s"], np.maximum.accumulate(t_cd)))
    assert t_hi <= bound + 1.0
