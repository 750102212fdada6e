"""Real-world topologies the catalog does not have: geometry on their shapes.

Columbus I-70 / I-270 (../shared/osm/09, ODbL: read in place where that folder
exists, never copied; skipped elsewhere) and a synthetic 4-leg with its collector road
(no extract needed).
"""

import math
import os
from pathlib import Path

import numpy as np
import pytest

from flyover.geometry.build import _fit_with_levels
from flyover.geometry.feasibility import fixed_features, forbidden_features, level_ramps
from flyover.geometry.layout import LayoutSettings, RampFeatures, build_interchange
from flyover.geometry.settings import Z_MARGIN
from flyover.geometry.state import LayoutState
from flyover.sampling.model import Feature
from flyover.topology.model import Connection, Label, Ramp, Road, Topology

#: the team's shared extracts: FLYOVER_OSM_DIR, else ../shared/osm beside the checkout
OSM_DIR = Path(os.environ.get("FLYOVER_OSM_DIR")
               or Path(__file__).resolve().parents[2] / "shared" / "osm")
COLUMBUS = OSM_DIR / "09_us_oh_columbus_i70_i270_west.osm"


@pytest.mark.skipif(not COLUMBUS.is_file(), reason=f"no real OSM extract at {COLUMBUS}")
def test_a_collector_road_splitting_into_a_loop_ends_past_the_road_the_loop_goes_to():
    """Columbus: the collector road r13 leaves the stub r8 (off I-270 North, before I-70)
    on its left and splits into the loop r6 to I-70 West and r12. Its free end was placed
    60 m or more out, 3-40 m to the left of where r8 ended (toward I-270 North), at a
    third of the way up to its children's roads: it ended under I-70 (1.7 m below a
    6.5 m road) or across I-270, and r6 started there, in I-270 North's lanes (a 64 m
    same-level conflict). Now the chain stays low enough to pass under I-70 (r13 goes on
    level at r8's height, a level ramp), r13 ends past it by the loop's room and beside
    I-270 North, wherever in its ranges."""
    from flyover.osm import read_osm_topologies  # noqa: PLC0415

    topo = next(t for t in read_osm_topologies(COLUMBUS) if t.ramps)
    assert {"r8", "r13", "r6"} <= set(topo.ramps)
    st = LayoutSettings()
    feats = {r: RampFeatures(60.0, 4.0) for r in topo.ramps}
    b = LayoutState(topo, {}, feats, st, 0)
    low = b.roads["I70W"].z - st.fit.clearance_m - Z_MARGIN + 1e-9
    spec8 = b.spec("r8", feats["r8"])
    assert spec8.free.z <= low
    assert max(map(abs, spec8.free.turn)) <= 0.1 + 1e-12  # it ends along I-270
    fit, _, _ = _fit_with_levels(b, spec8, 1)
    b.record("r8", fit)
    spec = b.spec("r13", feats["r13"])
    assert spec.free.z == pytest.approx(fit.end_pose[3], abs=1e-6)  # one road: level
    assert "r13" in level_ramps(topo)
    # every free end r13's ranges allow, from where it starts (r8's free end)
    x0, y0, h, _ = fit.end_pose
    ys, xs = [], []
    for d in spec.free.forward:
        for e in spec.free.lateral:
            xs.append(x0 + d * np.cos(h) - e * np.sin(h))
            ys.append(y0 + d * np.sin(h) + e * np.cos(h))
    i70w, i270n = b.roads["I70W"], b.roads["I270N"]
    # past I-70 (it runs east-west, I-270 north) by 60 m (the loop's radius) and more
    assert min(ys) >= i70w.origin[1] + i70w.half_width + 60.0
    # right of I-270 North's band, by half r13's width
    edge = i270n.origin[0] + i270n.lanes * st.lane_width_m
    assert min(xs) >= edge + 0.5 * b.width["r13"]


@pytest.mark.skipif(not COLUMBUS.is_file(), reason=f"no real OSM extract at {COLUMBUS}")
def test_a_collector_road_leaving_a_stub_near_the_road_slides_clear_of_it():
    """Columbus drawn set 15: r8 ended 4.7 m right of I-270 North's band (lanes 3), inside
    the margin the collector road r13 keeps (half its 8 m and 1 m: 5 m), heading 0.0965 rad
    toward the road. Its free end kept its 3-40 m to the left of r8's end, as for a stub
    that does not run beside the road, so every free end its ranges allowed lay across
    I-270 (both carriageways): r13 missed its targets with 5 same-level conflict samples
    (and r2, r5 and r12 after it). A stub ending right of the band, within the margin,
    slides away like one ending beyond it."""
    from flyover.geometry.chains import ends  # noqa: PLC0415
    from flyover.osm import read_osm_topologies  # noqa: PLC0415

    topo = next(t for t in read_osm_topologies(COLUMBUS) if t.ramps)
    st = LayoutSettings()
    feats = {r: RampFeatures(150.0, 2.0) for r in topo.ramps}
    feats["r13"] = RampFeatures(150.0, 0.0)  # level (fixed_features)
    b = LayoutState(topo, {"I270N": 3}, feats, st, 0)
    fit, _, _ = _fit_with_levels(b, b.spec("r8", feats["r8"]), 1)
    b.record("r8", fit)
    fe = b.specs.free_ends
    q = b.roads["I270N"]
    n = np.array([-np.sin(q.heading), np.cos(q.heading)])  # left of I-270 North
    u = np.array([np.cos(q.heading), np.sin(q.heading)])
    band = -q.lanes * st.lane_width_m
    edge = band - 0.5 * b.width["r13"] - 1.0
    h = q.heading + 0.0965
    start, _ = ends(topo, "r13")
    for lat_p in (edge + 0.29, edge - 0.29):  # set 15's r8 end, and just beyond the margin
        p = np.array(q.origin) + lat_p * n - 275.0 * u
        b.fitted.start_pose = lambda ramp, s, p=p: (p, h)
        free, _ = fe.free_end("r13", start, None, feats["r13"], b.width["r13"])
        for d in free.forward:
            for e in free.lateral:
                xy = p + d * np.array([np.cos(h), np.sin(h)]) \
                    + e * np.array([-np.sin(h), np.cos(h)])
                assert float((xy - np.array(q.origin)) @ n) <= edge + 1e-6

def _collector_loop():
    """A 4-leg with Columbus's collector road: e leaves A1 before the crossing and splits
    into x (right turn to B1) and c, which goes on beside A1, under B, and splits into the
    loop k to B2 and y back to A1."""
    c = Connection
    return Topology.build(
        "collector_loop", [Road(r, r[0]) for r in ("A1", "A2", "B1", "B2")],
        [Ramp(x) for x in "eckxy"],
        [c("A1", "e", Label.OUT_R, 0.3), c("e", "c", Label.OUT_L), c("e", "x", Label.OUT_R),
         c("c", "k", Label.OUT_R), c("c", "y", Label.OUT_L), c("k", "B2", Label.IN_R, 0.4),
         c("x", "B1", Label.IN_R, 0.6), c("y", "A1", Label.IN_R, 0.9)])


def test_a_collector_roads_stubs_pass_under_the_road_its_loop_goes_to_and_go_on_level():
    """Both stubs of the collector road end under B (clearance and a margin below it), the
    second one level (its slope fixed at 0, not drawn: no slope target can be met on it)."""
    t = _collector_loop()
    st = LayoutSettings()
    feats = {r: RampFeatures(60.0, 4.0) for r in t.ramps}
    b = LayoutState(t, {}, feats, st, 0)
    assert b.moves.is_loop("k")
    assert b.levels.loop_road_z("e") == b.levels.loop_road_z("c") == b.roads["B2"].z > 0
    assert b.spec("e", feats["e"]).free.z <= b.roads["B2"].z - st.fit.clearance_m - Z_MARGIN
    assert level_ramps(t) == {"c"}
    assert fixed_features(t) == {("c", Feature.SLOPE_PCT): 0.0}


def test_a_ramp_merging_along_a_stub_adds_a_lane_beside_it_in_plan_and_in_the_file():
    """Columbus's r5 (a loop off I-70) merges into the collector road r13 halfway along it,
    before r13 splits at its free end. The layout put r5's end over r13's outer lane (as a
    join at a free start would be) while the writer's lane links add a lane beside r13
    there: the exported lanes were 4.0 m (one lane) off at that link. A merge along a
    stub's body now adds a lane in both (here m into c, on the synthetic 4-leg)."""
    from io import BytesIO  # noqa: PLC0415

    from flyover.opendrive.continuity import check_continuity  # noqa: PLC0415
    from flyover.opendrive.reader import read_xodr  # noqa: PLC0415
    from flyover.opendrive.writer import xodr_bytes  # noqa: PLC0415

    c = Connection
    t = Topology.build(
        "collector_merge", [Road(r, r[0]) for r in ("A1", "A2", "B1", "B2")],
        [Ramp(x) for x in "eckmxy"],
        [c("A1", "e", Label.OUT_R, 0.3), c("e", "c", Label.OUT_L), c("e", "x", Label.OUT_R),
         c("c", "k", Label.OUT_R), c("c", "y", Label.OUT_L), c("k", "B2", Label.IN_R, 0.4),
         c("x", "B1", Label.IN_R, 0.6), c("y", "A1", Label.IN_R, 0.9),
         c("B2", "m", Label.OUT_R, 0.2), c("m", "c", Label.IN_R)])
    feats = {r: RampFeatures(60.0, 4.0) for r in t.ramps}
    g = build_interchange(t, {}, feats).geometry
    m = next(r for r in g.ramps if r.id == "m")
    st = LayoutSettings()
    c_width = next(r for r in g.ramps if r.id == "c").lanes * st.ramp_lane_width_m
    assert m.end.parent == "c" and m.end.offset_m == pytest.approx(-c_width)
    ok, detail = check_continuity(read_xodr(BytesIO(xodr_bytes(g))))
    assert ok, detail


def _collector_round():
    """The synthetic 4-leg's collector road (e off A1, c beside A1 under B, the loop k to
    B2) with Columbus's other corner of that quadrant: the stub s leaves B2 and splits into
    o, the right turn to A1 round the loop k (Columbus's r11 off r1 round r6), and w, the
    left turn to A2 (r3); y leaves c and joins o on its left (r12)."""
    c = Connection
    return Topology.build(
        "collector_round", [Road(r, r[0]) for r in ("A1", "A2", "B1", "B2")],
        [Ramp(x) for x in "eckxysow"],
        [c("A1", "e", Label.OUT_R, 0.1), c("e", "c", Label.OUT_L), c("e", "x", Label.OUT_R),
         c("c", "k", Label.OUT_R), c("c", "y", Label.OUT_L), c("k", "B2", Label.IN_R, 0.55),
         c("x", "B1", Label.IN_R, 0.85), c("y", "o", Label.IN_L),
         c("B2", "s", Label.OUT_R, 0.15), c("s", "o", Label.OUT_R), c("s", "w", Label.OUT_L),
         c("o", "A1", Label.IN_R, 0.9), c("w", "A2", Label.IN_R, 0.85)])


def test_an_outer_connector_reaching_its_loops_roads_through_stubs_is_fitted_round_it():
    """o joins B2 and A1, the roads the loop k joins, the other way round, but shares no
    road with it: o leaves B2 through the stub s, k leaves A1 through e and c. It was not
    taken for k's outer connector (that needed a road both attach to), so it was fitted
    before k (in s's round, k after c) and k was then laid across it. Now o comes after k
    and is fitted with k kept out at every height."""
    t = _collector_round()
    st = LayoutSettings()
    feats = {r: RampFeatures(60.0, 4.0) for r in t.ramps}
    b = LayoutState(t, {}, feats, st, 0)
    assert b.moves.is_loop("k")
    order = b.order()
    assert order.index("k") < order.index("o") < order.index("y")
    assert b.moves.goes_round("o", "k")
    assert not b.moves.goes_round("w", "k") and not b.moves.goes_round("y", "k")
    for ramp in order[: order.index("o")]:  # everything before o, as the build fits it
        fit, _, _ = _fit_with_levels(b, b.spec(ramp, feats[ramp]), 1)
        b.record(ramp, fit)
    assert b.windows.loops.round_loops("o") == {"k"}


@pytest.mark.skipif(not COLUMBUS.is_file(), reason=f"no real OSM extract at {COLUMBUS}")
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_columbus_connector_goes_round_the_loop_off_the_collector_road(seed):
    """Columbus: r11 (I-70 West through the stub r1 to I-270 North) is the outer connector
    of the loop r6 (I-270 North through r8 and r13 to I-70 West). It was fitted before r6,
    so r6 and r12 had to find room round it (r11 under r6, r12 meeting r11 or r2 at its
    level). Now it goes round r6 and nothing meets anything at its level, whatever the
    seed: r1, which r11 leaves, is fitted after r6 and keeps out of where r11 turns round
    it (with r8 carrying 3 lanes, r1 fitted first ended where r11 could not go round r6
    on seed 0, and r11 went over it)."""
    from flyover.geometry.check import ramp_crossings, same_level_conflicts  # noqa: PLC0415
    from flyover.osm import read_osm_topologies  # noqa: PLC0415

    topo = next(t for t in read_osm_topologies(COLUMBUS) if t.ramps)
    feats = {r: RampFeatures(60.0, 4.0) for r in topo.ramps}
    feats["r13"] = RampFeatures(float("inf"), 0.0)  # level (fixed_features)
    feats["r11"] = RampFeatures(150.0, 4.0)  # wider than its loop (feasibility.RoundLoop)
    g = build_interchange(topo, {}, feats, seed=seed).geometry
    assert not {frozenset((c.ramp, c.other)) for c in ramp_crossings(g)} & {
        frozenset(("r11", "r6"))}
    assert not same_level_conflicts(g)


@pytest.mark.skipif(not COLUMBUS.is_file(), reason=f"no real OSM extract at {COLUMBUS}")
def test_columbus_r2_is_sampled_wider_than_the_loop_r5_joining_the_collector_road():
    """Columbus: r2 (I-270 North through the stub r8 to I-70 East through the stub r14)
    turns right round the outside of the loop r5 (I-70 East to the collector road r13):
    the real r2 turns 61 degrees at 232 m, r5 250 degrees at 63 m (OSM turn_deg,
    min_radius_m). r13 splits, so r5's chain reached no road and sampling drew r2 as
    tight as r5 or tighter. r13 collects for I-270 North (it leaves it through r8, and r12
    leads back onto it through r11), so to sampling r5 goes to I-270 North and r2 is its
    outer connector, wider than it. The layout does not fit r2 round r5 (yet): for it
    the chains end at r13 as before."""
    from flyover.geometry.feasibility import round_loops  # noqa: PLC0415
    from flyover.osm import read_osm_topologies  # noqa: PLC0415

    topo = next(t for t in read_osm_topologies(COLUMBUS) if t.ramps)
    feats = {r: RampFeatures(60.0, 4.0) for r in topo.ramps}
    b = LayoutState(topo, {}, feats, LayoutSettings(), 0)
    m = b.moves
    assert m.collects("r13") == "I270N" and m.collects("r5") is None
    assert m.through_stubs("r5", True, collectors=True) == "I270N"
    assert m.through_stubs("r5", True) is None
    assert m.is_outer_connector("r2", "r5", collectors=True)
    assert not m.is_outer_connector("r2", "r5")
    assert not m.is_outer_connector("r9", "r5", collectors=True)
    pairs = {(p.connector, p.loop): p for p in round_loops(topo)}
    assert set(pairs) == {("r1", "r6"), ("r11", "r6"), ("r14", "r5"), ("r2", "r5")}
    assert not pairs["r2", "r5"].allows(60.0, 60.0) and pairs["r2", "r5"].allows(150.0, 60.0)


def _continued_t():
    """A through expressway A and two ending here that continue one another on one line
    (DC's I-66 and Potomac Freeway, file 26): C1 ends into u, which joins B1 on its left;
    v leaves B2 on its left and C2 begins from it. B also ends into q and begins from p,
    ramps to A (it keeps its terminal, room for them to climb there)."""
    c = Connection
    return Topology.build(
        "continued_t", [Road(r, r[0]) for r in ("A1", "A2", "B1", "B2", "C1", "C2")],
        [Ramp(x) for x in "pquv"],
        [c("A1", "p", Label.OUT_L, 0.3), c("p", "B1", Label.IN_M),
         c("B2", "q", Label.OUT_M), c("q", "A2", Label.IN_R, 0.7),
         c("C1", "u", Label.OUT_M), c("u", "B1", Label.IN_L, 0.5),
         c("B2", "v", Label.OUT_L, 0.3), c("v", "C2", Label.IN_M)])


def test_expressways_that_continue_one_another_are_laid_out_as_one_line():
    """C goes on past the centre to 40 m short of B's terminal, in B's median beside its
    lanes: u and v, which join (leave) B on its left, are short level ramps along the
    line that move over by about a lane, as real ones do (DC's r3 and r4: 63 and 61 m).
    Before, C and B were two half lines each ending at its own terminal (682 m apart
    here), C's lanes across B's: u and v ran 841 and 753 m (seed 1), and their slope was
    drawn."""
    from flyover.geometry.chains import continuations  # noqa: PLC0415
    from flyover.geometry.check import same_level_conflicts  # noqa: PLC0415
    from flyover.geometry.roads import CONTINUATION_GAP_M  # noqa: PLC0415

    t = _continued_t()
    st = LayoutSettings()
    feats = {r: RampFeatures(200.0, 4.0) for r in t.ramps}
    b = LayoutState(t, {}, feats, st, 0)
    r = b.roads
    [cont] = continuations(t)
    assert (cont.kept, cont.through, cont.meets) == ("B", "C", True)

    def point(road, s):
        return np.array(road.origin) + s * np.array([np.cos(road.heading), np.sin(road.heading)])

    for ending, beginning in (("C1", "B1"), ("B2", "C2")):
        e, s = r[ending], r[beginning]
        assert abs(np.sin(e.heading - s.heading)) < 1e-9 and np.cos(e.heading - s.heading) > 0
        gap = point(s, s.t_lo) - point(e, e.t_hi)
        along = gap @ np.array([np.cos(s.heading), np.sin(s.heading)])
        assert along == pytest.approx(CONTINUATION_GAP_M)
    # C runs in B's median, its lanes just clear of B's: u and v move over by about a
    # lane (a real merge from the left); u joins B1 (v leaves B2) soon after its start
    # (before its end)
    left = np.array([-np.sin(r["B1"].heading), np.cos(r["B1"].heading)])
    side = (np.array(r["C1"].origin) - np.array(r["B1"].origin)) @ left
    assert 0.0 < side - r["C1"].lanes * st.lane_width_m <= 2.0
    rail = b.windows.rail("u", feats["u"], ("B1", Label.IN_L), False, False, st.ramp_lane_width_m)
    assert rail.hi - r["B1"].t_lo <= 1.5 * st.gap_m
    assert level_ramps(t) == {"u", "v"}
    ic = build_interchange(t, {}, {**feats, "u": RampFeatures(float("inf"), 0.0),
                                   "v": RampFeatures(float("inf"), 0.0)}, seed=1)
    fits = {o.ramp: o.fit for o in ic.outcomes}
    assert all(f.ok for f in fits.values()), {k: f.ok for k, f in fits.items()}
    assert fits["u"].length_m < 150.0 and fits["v"].length_m < 150.0
    assert not same_level_conflicts(ic.geometry)


def test_a_ramp_fitted_before_a_continuation_leaves_it_room_for_the_writers_junctions():
    """DC (file 26), drawn feature set 0: r14 joins I-66 North on its right, r3 (from the
    Potomac Freeway, straight on) on its left by its start. r14 was fitted first, with
    nothing on I-66 North yet, and ended 40.13 m from its start, in the window r3 is held
    to (40-60 m: by the road's start); r3's window, with no room left before r14, fell
    back to 40-240 m and r3 ended 0.45 m from r14, too close for the writer's junctions
    (``leaves no room for a junction (0.15 m)``: not exported). Here k plays r14 on B1,
    u plays r3: k's window keeps ``gap_m`` beyond u's, and u's window, were k already
    where r14 was, keeps ``gap_m`` from it."""
    c = Connection
    base = _continued_t()
    t = Topology.build(
        "continued_t_k", [Road(r, r[0]) for r in ("A1", "A2", "B1", "B2", "C1", "C2")],
        [Ramp(x) for x in "kpquv"],
        [c("A1", "p", Label.OUT_L, 0.3), c("p", "B1", Label.IN_M),
         c("B2", "q", Label.OUT_M), c("q", "A2", Label.IN_R, 0.7),
         c("C1", "u", Label.OUT_M), c("u", "B1", Label.IN_L, 0.5),
         c("B2", "v", Label.OUT_L, 0.3), c("v", "C2", Label.IN_M),
         c("A2", "k", Label.OUT_R, 0.2), c("k", "B1", Label.IN_R, 0.8)])
    assert set(base.ramps) < set(t.ramps)
    st = LayoutSettings()
    feats = {r: RampFeatures(200.0, 4.0) for r in t.ramps}
    b = LayoutState(t, {}, feats, st, 0)
    order = b.order()
    assert order.index("k") < order.index("u")  # as r14 before r3
    b1 = b.roads["B1"]
    u = b.windows.rail("u", feats["u"], ("B1", Label.IN_L), False, False, st.ramp_lane_width_m)
    k = b.windows.rail("k", feats["k"], ("B1", Label.IN_R), False, False, st.ramp_lane_width_m)
    assert u.hi - b1.t_lo <= 1.5 * st.gap_m  # u still by B1's start
    assert k.lo >= u.hi + st.gap_m - 1e-9
    # k where r14 was: u keeps the room from it
    t_k = b1.t_lo + 40.13
    b.fitted.attached.setdefault("B1", []).append((0.8, t_k, t_k, "k", t_k))
    u = b.windows.rail("u", feats["u"], ("B1", Label.IN_L), False, False, st.ramp_lane_width_m)
    assert u.lo >= t_k + st.gap_m - 1e-9 or u.hi <= t_k - st.gap_m + 1e-9, (u.lo, u.hi, t_k)
    assert u.lo >= b1.t_lo + st.gap_m - 1e-9


DC = OSM_DIR / "26_us_dc_i66_us50_e_st_expwy.osm"


@pytest.mark.skipif(not DC.is_file(), reason=f"no real OSM extract at {DC}")
def test_a_right_turn_between_two_roads_on_one_level_is_a_level_ramp():
    """DC (file 26): I-66 and the E Street Expressway both end here, on one level (6.5 m,
    above I-66 / US 50). r14 (E Street to I-66 North) leaves and joins on the right and
    turns right, with no crest planned: it was fitted level and every slope drawn for it
    was recorded infeasible (`level ramp (both ends at z=6.5 m) cannot have a 3 % slope`,
    sets 0-2 of 4 drawn). Now sampling fixes its slope at 0. Since E Street meets the
    I-66 line at a junction of its own (GEOMETRY_VERSION 37), r5 (I-66 North to E Street)
    is such a right turn by 90° too (before: 135° round E Street's diagonal leg, lifted
    over r14); the left turns r10, r12, r13 keep their slopes."""
    from flyover.osm import read_osm_topologies  # noqa: PLC0415

    topo = next(t for t in read_osm_topologies(DC) if t.ramps)
    level = level_ramps(topo)
    assert {"r14", "r5"} <= level
    assert not {"r10", "r12", "r13", "r1", "r2", "r6"} & level
    b = LayoutState(topo, {}, {r: RampFeatures(60.0, 0.0 if r in level else 4.0)
                               for r in topo.ramps}, LayoutSettings(), 0)
    spec = b.spec("r14", b.features["r14"])
    assert np.ptp(np.concatenate([spec.start.z, spec.end.z])) == 0.0
    assert spec.z_crest is None


def test_no_catalog_design_gains_a_level_ramp():
    """The catalog's through expressways are each on their own level and a T's ending one
    above them: only cloverleaf_cd's collector-distributor roads are level."""
    from flyover.topology.catalog import catalog_topologies  # noqa: PLC0415

    level = {name: sorted(level_ramps(t)) for name, t in catalog_topologies().items()}
    assert {n: v for n, v in level.items() if v} == {
        "cloverleaf_cd": ["cA1", "cA2", "cB1", "cB2"]}


@pytest.mark.skipif(not COLUMBUS.is_file(), reason=f"no real OSM extract at {COLUMBUS}")
def test_a_stub_carries_all_the_lanes_of_the_ramps_it_splits_into():
    """Columbus: r8 (off I-270 North) splits into r2 (one lane) and the collector road r13,
    which splits into r6 and r12 (two lanes). r8 had one lane per ramp it splits into (2):
    3 lanes out of 2, and r2's lane lay on one of r13's just past the fork (the dense check
    found r13/r2 at 15 m on drawn set 4). Now it carries 3."""
    from flyover.geometry.chains import Movements  # noqa: PLC0415
    from flyover.geometry.roads import layout_roads  # noqa: PLC0415
    from flyover.osm import read_osm_topologies  # noqa: PLC0415

    topo = next(t for t in read_osm_topologies(COLUMBUS) if t.ramps)
    moves = Movements(topo, layout_roads(topo, {}, LayoutSettings()))
    assert {r: moves.lanes(r) for r in ("r8", "r13", "r1", "r10", "r14", "r2")} == {
        "r8": 3, "r13": 2, "r1": 2, "r10": 2, "r14": 2, "r2": 1}


@pytest.mark.skipif(not COLUMBUS.is_file(), reason=f"no real OSM extract at {COLUMBUS}")
def test_the_stub_a_round_connector_leaves_is_fitted_after_the_loop_and_keeps_its_room():
    """Columbus: r1 (off I-70 West) splits into r11, the outer connector of the loop r6
    joining I-70 West. r1 was fitted first, before r6 was anywhere, and where it ended
    decided whether r11 could go round r6. Now r1 waits for r6 and, on I-70 West's right,
    keeps out of everything beyond where r11 must leave the road to go round r6 at its
    radius (the 45° rule, LoopRoom.round_loop); r11 joins I-270 North where it has gone
    round r6 as well."""
    from flyover.osm import read_osm_topologies  # noqa: PLC0415
    from flyover.topology.model import Label as L  # noqa: PLC0415

    topo = next(t for t in read_osm_topologies(COLUMBUS) if t.ramps)
    st = LayoutSettings()
    feats = {r: RampFeatures(60.0, 4.0) for r in topo.ramps}
    feats["r13"] = RampFeatures(float("inf"), 0.0)
    feats["r11"] = RampFeatures(150.0, 4.0)
    b = LayoutState(topo, {}, feats, st, 0)
    order = b.order()
    assert order.index("r6") < order.index("r1") < order.index("r11")
    assert b.windows.loops.connector_fences("r1") == []  # r6 not fitted yet
    for ramp in order[: order.index("r1")]:
        fit, _, _ = _fit_with_levels(b, b.spec(ramp, feats[ramp]), 1)
        b.record(ramp, fit)
    w11 = b.width["r11"]
    t_cap = b.windows.loops.round_loop("r6", "I70W", w11, -1, feats["r11"])
    [fence] = b.windows.loops.connector_fences("r1")
    assert fence[4] == pytest.approx(t_cap) and fence[5] > t_cap + 1e3  # beyond, toward r6
    assert fence[7] < -b.roads["I70W"].lanes * st.lane_width_m  # on its right, off its lanes
    fit, _, _ = _fit_with_levels(b, b.spec("r1", feats["r1"]), 1, fences=(fence,))
    b.record("r1", fit)
    rail = b.windows.rail("r11", feats["r11"], ("I270N", L.IN_R), False, False, w11)
    assert rail.lo >= b.windows.loops.round_loop("r6", "I270N", w11, +1, feats["r11"]) - 1e-6


@pytest.mark.skipif(not COLUMBUS.is_file(), reason=f"no real OSM extract at {COLUMBUS}")
def test_a_ramp_running_straight_on_between_two_ramps_is_sampled_without_a_radius():
    """Columbus: r12 runs from the collector road r13's end, beside I-270 North, on into
    r11 just before r11 joins I-270 North (real: 570 m, radius 1,066 m). A finite radius
    target could be met on it only by a bend no real one has (30 m came out as 22-27 m on
    2 of 8 drawn sets): sampling fixes it at inf, and resampling keeps it. No catalog
    design has such a ramp."""
    from flyover.geometry.feasibility import straight_connectors  # noqa: PLC0415
    from flyover.geometry.tables import domain_resampler  # noqa: PLC0415
    from flyover.osm import read_osm_topologies  # noqa: PLC0415
    from flyover.topology.catalog import catalog_topologies  # noqa: PLC0415

    topo = next(t for t in read_osm_topologies(COLUMBUS) if t.ramps)
    assert straight_connectors(topo) == {"r12"}
    assert fixed_features(topo)[("r12", Feature.RADIUS_M)] == float("inf")
    assert not any(straight_connectors(t) for t in catalog_topologies().values())
    sets = {0: ({}, {r: RampFeatures(float("inf") if r == "r12" else 60.0, 4.0)
                     for r in topo.ramps}),
            1: ({}, {r: RampFeatures(30.0, 3.0) if r != "r12" else RampFeatures(
                float("inf"), 3.0) for r in topo.ramps})}
    res = domain_resampler(sets, 7, topo)
    assert all(res("r12", k, {}).radius_m == float("inf") for k in range(1, 6))


@pytest.mark.skipif(not COLUMBUS.is_file(), reason=f"no real OSM extract at {COLUMBUS}")
def test_columbus_stubs_keep_room_for_the_connector_climbing_between_their_free_ends():
    """Columbus: r2 runs from the stub r8's free end (0.5 m, under I-70) to the stub r14's
    (12 m, where r9 comes down from its crest), a low connector without a crest. The two
    free ends kept room for its turn alone: 544-549 m of least path for 1,190 m of climb
    at 1 % (drawn sets 4-6), and r2 came out at its least, 2.1-2.2 % steep. Now r14's
    free end keeps half its climb from the crossing, whatever the seed. r8, whose child
    r13 is a collector road running on level from its free end past I-70, keeps none:
    with half the climb (595 m) its end lay 644 m out on drawn set 6, r13's at the nearest
    point its loop room allowed (97 m past I-70), and the loop r6 beside I-70 left r11 no
    room to go round it."""
    from flyover.geometry.profile import climb_distance  # noqa: PLC0415
    from flyover.osm import read_osm_topologies  # noqa: PLC0415

    topo = next(t for t in read_osm_topologies(COLUMBUS) if t.ramps)
    st = LayoutSettings()
    feats = {r: RampFeatures(60.0, 4.0) for r in topo.ramps}
    feats["r13"] = RampFeatures(float("inf"), 0.0)  # level (fixed_features)
    feats["r2"] = RampFeatures(60.0, 1.0)
    b = LayoutState(topo, {}, feats, st, 0)
    fe = b.specs.free_ends
    assert (fe.stub_free_z("r8"), fe.stub_free_z("r14")) == pytest.approx((0.5, 12.0))
    climb = float(climb_distance(11.5, 0.01, st.fit.transition_m))
    assert fe.connector_room("r14", 12.0) == pytest.approx(0.5 * climb)
    assert fe.connector_room("r8", 0.5) == 0.0
    for seed, ramp in enumerate(("r14", "r8")):
        fit, _, _ = _fit_with_levels(b, b.spec(ramp, feats[ramp]), seed)
        b.record(ramp, fit)
    # r8's end lies where r13 needs it, not 0.5 * climb (595 m) and more short of I-70
    q = b.specs.roads["I70E"]
    d = np.array([np.cos(q.heading), np.sin(q.heading)])
    rel = np.array(b.fitted.fits["r8"].end_pose[:2]) - np.array(q.origin)
    assert abs(rel[0] * d[1] - rel[1] * d[0]) < 0.5 * climb
    assert b.spec("r2", feats["r2"]).least_m >= 0.5 * climb
    # a connector between two stubs at one height keeps no such room
    assert fe.connector_room("r14", 0.5) == pytest.approx(0.0)


def _dc():
    from flyover.osm import read_osm_topologies  # noqa: PLC0415

    return next(t for t in read_osm_topologies(DC) if t.ramps)


@pytest.mark.skipif(not DC.is_file(), reason=f"no real OSM extract at {DC}")
def test_a_t_whose_ramps_all_run_to_one_line_meets_it_at_a_junction_of_its_own():
    """DC (file 26): the E Street Expressway ends here and its ramps (r5, r7, r10-r14) all
    run to or from the I-66 / Potomac Freeway line. On the map it meets that line square,
    ~330 m north of US 50, a T junction of its own. It was placed on the first free
    diagonal at the centre, where all four tied: r5, r7, r9, r11-r13 turned by 135°. Now
    it meets the line square beyond I-66's terminal, on the side its ramps' ends imply
    (right exits turning right), its stations counted from that junction."""
    from flyover.geometry.chains import Movements  # noqa: PLC0415
    from flyover.geometry.roads import layout_roads  # noqa: PLC0415

    topo = _dc()
    roads = layout_roads(topo, {}, LayoutSettings(), {r: 4.0 for r in topo.ramps})
    moves = Movements(topo, roads)
    turns = {r: round(float(np.degrees(moves.movement(r)))) for r in
             ("r5", "r7", "r10", "r12", "r13", "r14")}
    assert turns == {"r5": -90, "r7": -90, "r10": 90, "r12": 90, "r13": 90, "r14": -90}
    n, e = roads["I66N"], roads["way50428544E"]
    j = np.array(getattr(e, "junction", None) or (np.nan, np.nan))
    d = np.array([np.cos(n.heading), np.sin(n.heading)])
    along = float(j @ d)  # on I-66 North's line, beyond its start (the line's terminal)
    assert along > n.t_lo + LayoutSettings().gap_m
    assert abs(float(j @ np.array([-d[1], d[0]]))) < 1.0
    assert abs(np.cos(e.heading - n.heading)) < 1e-9
    # E Street's carriageways pass through the junction, its terminal out from it
    for r in ("way50428544E", "way50428544W"):
        x = roads[r]
        foot = np.array(x.origin) + float((j - np.array(x.origin))
                                          @ np.array([np.cos(x.heading), np.sin(x.heading)])) \
            * np.array([np.cos(x.heading), np.sin(x.heading)])
        assert np.hypot(*(foot - j)) < 5.0
    # r8 and r13 join on the left: direct left turns, not loops
    assert not moves.is_loop("r8") and not moves.is_loop("r13")


@pytest.mark.skipif(not DC.is_file(), reason=f"no real OSM extract at {DC}")
def test_ramps_to_a_t_at_a_junction_of_its_own_keep_their_room_from_that_junction():
    """DC (file 26): on I-66 North r5 leaves for E Street before E Street's junction and
    r14 joins after it; r10 leaves I-66 South before it. Counted from the centre, their
    windows lay round US 50's crossing, far from E Street. And the left turns between the
    line and E Street cross each other: those into E Street (r10) fly a level above those
    leaving it (r12, r13), as at a directional T."""
    topo = _dc()
    st = LayoutSettings()
    feats = {r: RampFeatures(60.0, 0.0 if r in level_ramps(topo) else 4.0)
             for r in topo.ramps}
    b = LayoutState(topo, {}, feats, st, 0)
    n, s = b.roads["I66N"], b.roads["I66S"]
    j = np.array(getattr(b.roads["way50428544E"], "junction", None) or (np.nan, np.nan))
    jn = float((j - np.array(n.origin)) @ np.array([np.cos(n.heading), np.sin(n.heading)]))
    js = float((j - np.array(s.origin)) @ np.array([np.cos(s.heading), np.sin(s.heading)]))
    w = st.ramp_lane_width_m
    r5 = b.windows.rail("r5", feats["r5"], ("I66N", Label.OUT_R), True, False, w)
    r14 = b.windows.rail("r14", feats["r14"], ("I66N", Label.IN_R), False, False, w)
    r10 = b.windows.rail("r10", feats["r10"], ("I66S", Label.OUT_L), True, False, w)
    assert n.t_lo < r5.lo <= r5.hi < jn
    assert jn < r14.lo <= r14.hi
    assert r10.hi < js
    assert b.plan["r10"] > b.plan["r12"] == b.plan["r13"] > 6.5


@pytest.mark.skipif(not DC.is_file(), reason=f"no real OSM extract at {DC}")
def test_a_continuations_ramp_is_not_ordered_by_pos():
    """DC (file 26): r4 (I-66 South to the Potomac Freeway, straight on) is held by I-66
    South's end; r10 (to E Street, ``pos`` 0.46 against r4's 0.24) leaves I-66 South
    beyond E Street's junction. Fitted first, r10 held r4 to before it by ``pos``: r4 left
    1.4 km out and ran back along I-66 South, 1,158 m for its real 61 m (drawn set 0)."""
    topo = _dc()
    st = LayoutSettings()
    feats = {r: RampFeatures(60.0, 4.0) for r in topo.ramps}
    b = LayoutState(topo, {}, feats, st, 0)
    s = b.roads["I66S"]
    t10 = s.t_hi - 900.0
    b.fitted.attached.setdefault("I66S", []).append((0.4628, t10, t10, "r10", t10))
    r4 = b.windows.rail("r4", feats["r4"], ("I66S", Label.OUT_L), True, False,
                        st.ramp_lane_width_m)
    assert s.t_hi - 1.5 * st.gap_m - 1e-9 <= r4.lo <= r4.hi <= s.t_hi - st.gap_m + 1e-9


def test_no_catalog_design_has_a_t_at_a_junction_of_its_own():
    """Only a T whose ramps all run to a line of two expressways continuing one another
    (DC's) gets a junction of its own: the catalog's roads all meet at the centre."""
    from flyover.geometry.roads import layout_roads  # noqa: PLC0415
    from flyover.topology.catalog import catalog_topologies  # noqa: PLC0415

    for name, t in catalog_topologies().items():
        roads = layout_roads(t, {}, LayoutSettings(), {r: 3.0 for r in t.ramps})
        assert all(getattr(r, "junction", None) is None for r in roads.values()), name


def _forbids(model, assigned: dict) -> bool:
    """Whether the feature model forbids the partial row ``{(element, feature): value}``."""
    index = {(p.element, p.feature): i for i, p in enumerate(model.parameters)}
    row = {index[k]: model.parameters[index[k]].values.index(v) for k, v in assigned.items()}
    return any(f.matches(row) for f in model.forbidden)


@pytest.mark.skipif(not DC.is_file(), reason=f"no real OSM extract at {DC}")
def test_a_continuations_ramp_is_sampled_only_radii_its_shift_can_be_built_with():
    """DC (file 26): r3 / r4 run straight on between I-66 and the Potomac Freeway, which
    runs in I-66's median beside its lanes: each attaches by one road's end and within
    ``gap_m / 2`` beyond ``gap_m`` from the other's start, so it shifts sideways by the
    Potomac Freeway's lanes (3.75 m each) + 1 m - its own 4 m within a run of 80-100 m.
    An S of two arcs R: run 2 R sin θ, shift 2 R (1 - cos θ), so R <= (L² + d²) / (4 d):
    4 lanes, d = 12 m: 211 m; 5 lanes, d = 15.75 m: 163 m; 3 lanes, 8.25 m: 305 m. A 280 m
    radius was drawn on 4 of 56 ramps of 4 drawn sets and resampled (met at 30-40 m).
    Sampling now forbids what that room cannot hold (at 0.95 × the radius, as the fit's
    least length does), and inf (it must shift)."""
    from flyover.sampling.model import default_profile, feature_model  # noqa: PLC0415

    topo = _dc()
    prof = default_profile()
    model = feature_model(topo, prof, forbidden_features(topo, prof, LayoutSettings()),
                          fixed_features(topo))
    for ramp, road in (("r3", "way50427247N"), ("r4", "way50427247S")):
        def forbidden(radius, lanes, ramp=ramp, road=road):
            return _forbids(model, {(ramp, Feature.RADIUS_M): radius,
                                    (road, Feature.LANES): lanes})
        assert forbidden(280.0, 4.0) and forbidden(280.0, 5.0) and forbidden(210.0, 5.0)
        assert not forbidden(210.0, 4.0) and not forbidden(150.0, 5.0)
        assert not forbidden(280.0, 3.0)
        assert all(forbidden(float("inf"), n) for n in (3.0, 4.0, 5.0))
        assert not any(forbidden(r, n) for r in (30.0, 40.0) for n in (3.0, 4.0, 5.0))


@pytest.mark.skipif(not DC.is_file(), reason=f"no real OSM extract at {DC}")
def test_the_radius_bound_of_a_continuations_ramp_is_the_s_shift_its_windows_hold():
    """The hand check of the rule above on r3's windows (way50427247N with 4 lanes): run
    L 80-100 m, shift d 12 m; the largest S-shift radius is (100² + 12²) / (4 · 12) =
    211.3 m: 210 m is held (0.95 × 210 = 199.5 m), 280 m is not (266 m)."""
    from flyover.geometry.feasibility import fixed_window_ramps, shift_rooms  # noqa: PLC0415

    topo = _dc()
    assert fixed_window_ramps(topo) == {"r3", "r4"}
    b = LayoutState(topo, {"way50427247N": 4}, {}, LayoutSettings(), 0)
    spec = b.spec("r3", RampFeatures(210.0, 0.0))
    pa, _, _ = spec.start.at(np.array([spec.start.lo, spec.start.hi]))
    pb, _, _ = spec.end.at(np.array([spec.end.lo, spec.end.hi]))
    run, shift = np.abs(pb[:, 0] - pa[0, 0]), np.abs(pb[:, 1] - pa[0, 1])
    assert run == pytest.approx([80.0, 100.0]) and shift == pytest.approx([12.0, 12.0])
    assert (run.max() ** 2 + 12.0 ** 2) / 48.0 == pytest.approx(211.33, abs=0.01)
    rooms = {r.ramp: r for r in shift_rooms(topo)}
    assert rooms["r3"].road == "way50427247N" and rooms["r4"].road == "way50427247S"
    assert rooms["r3"].allows(210.0, 4) and not rooms["r3"].allows(280.0, 4)
    assert rooms["r3"].allows(280.0, 3) and not rooms["r3"].allows(float("inf"), 3)


@pytest.mark.skipif(not DC.is_file(), reason=f"no real OSM extract at {DC}")
def test_a_continuations_windows_are_the_same_for_every_radius():
    """shift_rooms lays out once per lanes combination and tests every radius against one
    spec's windows: held by the roads' ends, they must not move with the radius target
    (else a radius would be tested against another's windows)."""
    from flyover.geometry.feasibility import fixed_window_ramps  # noqa: PLC0415

    topo = _dc()
    radii = (float("inf"), 280.0, 210.0, 150.0, 100.0, 60.0, 40.0, 30.0)
    for lanes in ({}, {"way50427247N": 5, "I66N": 3}, {"way50427247S": 3, "I66S": 5}):
        b = LayoutState(topo, lanes, {}, LayoutSettings(), 0)
        for ramp in sorted(fixed_window_ramps(topo)):
            specs = [b.spec(ramp, RampFeatures(r, 0.0)) for r in radii]
            for rail in ("start", "end"):
                got = {(getattr(s, rail).lo, getattr(s, rail).hi,
                        tuple(np.round(getattr(s, rail).at(np.array([getattr(s, rail).lo]))[0]
                                       .ravel(), 9))) for s in specs}
                assert len(got) == 1, (ramp, rail, lanes)


@pytest.mark.skipif(not DC.is_file(), reason=f"no real OSM extract at {DC}")
def test_a_continuations_ramp_is_resampled_only_radii_its_shift_can_be_built_with():
    """Sampling forbids r3 280 m and inf with 4 lanes on way50427247N, and 210 m too with 5
    (:func:`flyover.geometry.feasibility.shift_rooms`). The resampler, given the topology
    and the sample, draws from the same rules with that sample's lanes (it drew 280 m
    and inf again); with 3 lanes 280 m is drawn."""
    from flyover.geometry.tables import DomainResampler, domain_resampler  # noqa: PLC0415

    topo = _dc()
    level = {r for r, f in fixed_features(topo) if f is Feature.SLOPE_PCT}
    radii = (30.0, 40.0, 60.0, 100.0, 150.0, 210.0, 280.0, float("inf"))
    sets = {n - 3: ({r: n for r in topo.roads},
                    {r: RampFeatures(radii[(n + i) % 8], 0.0 if r in level else float(n))
                     for i, r in enumerate(topo.ramps)}) for n in (3, 4, 5)}
    drawn = {}
    for k, n in enumerate((3, 4, 5)):
        res = domain_resampler(sets, 5, topo, LayoutSettings(), sample=k)
        drawn[n] = {res("r3", a, {}).radius_m for a in range(1, 81)}
        assert all(res("r3", a, {}).slope_pct == 0.0 for a in range(1, 4))
    assert float("inf") not in drawn[3] and 280.0 in drawn[3]
    assert not drawn[4] & {280.0, float("inf")} and 210.0 in drawn[4]
    assert not drawn[5] & {210.0, 280.0, float("inf")} and 150.0 in drawn[5]
    # the draws without the rules do break them (so the assertions above can fail)
    plain = DomainResampler(radii, (3.0, 4.0, 5.0), frozenset(level), 5)
    assert {plain("r3", a, {}).radius_m for a in range(1, 81)} >= {280.0, float("inf")}


def test_no_catalog_design_has_a_ramp_between_fixed_windows():
    """Only DC's continuation ramps have both windows fixed by the layout: the catalog's
    domains are unchanged."""
    from flyover.geometry.feasibility import fixed_window_ramps, shift_rooms  # noqa: PLC0415
    from flyover.topology.catalog import catalog_topologies  # noqa: PLC0415

    for name, t in catalog_topologies().items():
        assert not fixed_window_ramps(t) and not shift_rooms(t), name


@pytest.mark.slow
@pytest.mark.skipif(not COLUMBUS.is_file(), reason=f"no real OSM extract at {COLUMBUS}")
def test_columbus_r12_joins_r11_straight_where_r11_runs_beside_i270_north():
    """Columbus: r12 runs from the collector road r13's end straight on into r11 (real:
    570 m, radius 1,066 m; sampling fixes its radius at inf). r11 merged into I-270 North
    right after turning round its loop r6 (15-55 m beside it), so r12 joined it where it
    still turned (heading 115-162 deg against 85-106 deg): "ok" as a 29-117 m reverse bend
    while the fit held inf to 0.95 x 30 m, 16 m once it held it to 0.95 x 250 m as the
    benchmark does. Now r11 runs beside I-270 North a lane off its edge before it merges
    and r12 joins it there, nowhere tighter than 0.95 x 250 m (drawn set 0 of
    benchmarks/geometry.py --osm, at its seed)."""
    from flyover.geometry.straight import inf_met  # noqa: PLC0415
    from flyover.osm import read_osm_topologies  # noqa: PLC0415

    topo = next(t for t in read_osm_topologies(COLUMBUS) if t.ramps)
    lanes = {"I270N": 4, "I270S": 4, "I70E": 4, "I70W": 3}
    inf = float("inf")
    feats = {r: RampFeatures(*v) for r, v in {
        "r1": (100.0, 4.0), "r10": (280.0, 5.0), "r11": (210.0, 3.0), "r12": (inf, 5.0),
        "r13": (inf, 0.0), "r14": (inf, 3.0), "r2": (30.0, 2.0), "r3": (150.0, 3.0),
        "r4": (60.0, 4.0), "r5": (30.0, 4.0), "r6": (30.0, 3.0), "r7": (60.0, 4.0),
        "r8": (30.0, 3.0), "r9": (60.0, 3.0)}.items()}
    ic = build_interchange(topo, lanes, feats, class_id="cd9e4c3eca6", sample=0,
                           seed=2318073955)
    fits = {o.ramp: o.fit for o in ic.outcomes}
    r11, r12 = fits["r11"], fits["r12"]
    assert r12.ok and r11.ok
    assert inf_met(min(r12.min_radius_m, r12.point_radius_m))
    # r12 comes in along I-270 North's heading (pi / 2 here), as r13 ends
    road = LayoutState(topo, lanes, feats, LayoutSettings(), 0).roads["I270N"]
    assert abs(r12.end_pose[2] % (2 * np.pi) - road.heading) < 0.15


@pytest.mark.slow
@pytest.mark.skipif(not COLUMBUS.is_file(), reason=f"no real OSM extract at {COLUMBUS}")
@pytest.mark.parametrize("sample,seed,lanes,feats", [
    (2, 1680171343, (4, 3, 3, 3), {"r1": (100.0, 1.0), "r10": (60.0, 2.0), "r11": (40.0, 1.0),
                                   "r12": (math.inf, 5.0), "r13": (60.0, 0.0),
                                   "r14": (math.inf, 2.0), "r2": (60.0, 2.0),
                                   "r3": (100.0, 4.0), "r4": (100.0, 1.0), "r5": (40.0, 4.0),
                                   "r6": (30.0, 1.0), "r7": (210.0, 2.0), "r8": (210.0, 1.0),
                                   "r9": (210.0, 4.0)}),
    (9, 4093098183, (3, 4, 4, 3), {"r1": (210.0, 2.0), "r10": (100.0, 3.0),
                                   "r11": (150.0, 4.0), "r12": (math.inf, 1.0),
                                   "r13": (210.0, 0.0), "r14": (280.0, 3.0),
                                   "r2": (150.0, 3.0), "r3": (40.0, 3.0), "r4": (280.0, 3.0),
                                   "r5": (40.0, 4.0), "r6": (60.0, 3.0), "r7": (150.0, 5.0),
                                   "r8": (math.inf, 2.0), "r9": (40.0, 1.0)}),
])
def test_columbus_r12_joins_r11_in_its_run_beside_i270_north_at_its_height(sample, seed,
                                                                          lanes, feats,
                                                                          monkeypatch):
    """Drawn sets 2 and 9 of benchmarks/geometry.py --osm (their seeds): r12 missed its first
    try. r11 ran beside I-270 North (its run, from its end window's start plus its
    radius), but r12 joined it only where it headed within 0.15 rad of r13's end: past the
    run, where r11 merged along the road's edge and left r12 no room on its left (set 2:
    1 conflict), or on r11 still 7 m up before it came down to I-270 North at its end (set
    9: r12 at 1 % came out 1.9 %). Now r11 comes down to I-270 North's height first and r12
    joins it within its run, straight (nowhere tighter than 0.95 x 250 m) and at 0.5 m of
    the collector road r13's end. Pinned to GEOMETRY_VERSION 39's r2 (no loop room,
    LayoutState.loop_room): with it r2 takes another shape on both sets, and set 2
    misses r12, set 9 r3 and r7 first try (a reshuffle downstream, not r12's window)."""
    from flyover.geometry.straight import inf_met  # noqa: PLC0415

    monkeypatch.setattr(LayoutState, "loop_room", lambda self, ramp: ())
    topo, lanes, feats = _columbus_set(lanes, feats)
    ic = build_interchange(topo, lanes, feats, class_id="cd9e4c3eca6", sample=sample,
                           seed=seed)
    out = {o.ramp: o for o in ic.outcomes}
    assert all(o.first_try_ok for o in ic.outcomes), [r for r, o in out.items()
                                                      if not o.first_try_ok]
    r12 = out["r12"].fit
    assert inf_met(min(r12.min_radius_m, r12.point_radius_m))
    assert abs(r12.end_pose[3] - r12.start_pose[3]) < 1.0  # level with r13's end
    # r11 joins its road at the road's height, and came down to it before r12 joined
    assert out["r11"].fit.end_pose[3] == pytest.approx(0.0, abs=1e-6)


@pytest.fixture(scope="module")
def columbus_set_26():
    """Drawn set 26 of benchmarks/geometry.py --osm, built at its seed: ramp -> outcome."""
    topo, lanes, feats = _columbus_set((3, 4, 4, 5), {
        "r1": (100.0, 4.0), "r10": (30.0, 5.0), "r11": (150.0, 5.0), "r12": (math.inf, 5.0),
        "r13": (60.0, 0.0), "r14": (60.0, 1.0), "r2": (210.0, 1.0), "r3": (60.0, 4.0),
        "r4": (210.0, 2.0), "r5": (40.0, 3.0), "r6": (40.0, 3.0), "r7": (210.0, 2.0),
        "r8": (100.0, 5.0), "r9": (60.0, 5.0)})
    ic = build_interchange(topo, lanes, feats, class_id="cd9e4c3eca6", sample=26,
                           seed=4223599476)
    return {o.ramp: o for o in ic.outcomes}


@pytest.mark.slow
@pytest.mark.skipif(not COLUMBUS.is_file(), reason=f"no real OSM extract at {COLUMBUS}")
def test_columbus_r2_leaves_the_loop_r5_room_where_it_leaves_i70_east(columbus_set_26):
    """Drawn set 26 of benchmarks/geometry.py --osm (its seed): r2 (210 m / 1 %, between
    the free ends of r8 and r14, fitted before the loop r5) climbed beside I-70 East, and
    r5 (40 m / 3 %, from I-70 East at 6.5 m down to r13) met it there at its level (4
    samples) and missed its first try. Now r2 keeps off where r5 leaves I-70 East
    (LayoutState.loop_room) and both are first try with no conflict."""
    out = columbus_set_26
    for r in ("r2", "r5"):
        assert out[r].first_try_ok and out[r].fit.conflicts == 0, r


@pytest.mark.slow
@pytest.mark.skipif(not COLUMBUS.is_file(), reason=f"no real OSM extract at {COLUMBUS}")
def test_columbus_r7_start_window_holds_its_climb_to_r3s_plateau(columbus_set_26):
    """Drawn set 26 of benchmarks/geometry.py --osm (its seed): r7 (210 m / 2 %) leaves
    I-70 East at 6.5 m and joins the flyover r3 where r3 is level: on its 19.5 m plateau.
    Its start window on I-70 East reaches no farther back than 1.5 x what it needs beyond
    the crossing's room (34.5 m), and the climb in that was read to r3's mean height
    (about 13 m): 702 m back, and r7 turned at 171.5 m (2.19 %) and missed its first
    try. Then the climb was read at r3's height in r7's window: 13 m at 2 % with a 40 m
    vertical curve is 690 m, and 40 m tapers: 34.5 + 1.5 x 770 = 1,189.5 m back; now
    its turn (1.55 rad x 210 m) counts on top of that (RampSpecs.need_m), beyond the
    window's reach: 1,500 m back (settings reach_m)."""
    out = columbus_set_26
    r7 = out["r7"].fit
    assert out["r7"].first_try_ok and r7.conflicts == 0
    assert r7.end_pose[3] == pytest.approx(19.5, abs=0.01)  # on r3's plateau
    assert r7.spec.start.lo == pytest.approx(-1500.0, abs=1.0)


@pytest.mark.slow
@pytest.mark.skipif(not COLUMBUS.is_file(), reason=f"no real OSM extract at {COLUMBUS}")
def test_columbus_r7_start_window_holds_its_turn_and_its_climb_to_r3(monkeypatch):
    """Drawn set 15 of benchmarks/geometry.py --osm (its seed): r7 (210 m / 4 %) leaves
    I-70 East at 6.5 m, turns 2.24 rad and joins the flyover r3 along it on its 19.5 m
    plateau. Its start window reached back the larger of its turn (2.24 x 210 m = 471 m)
    and its climb (13 m at 4 % and a 40 m vertical curve: 365 m) and its tapers: 38.25 +
    1.5 x (471 + 80) = 865 m, and every start nearer the crossing met r3 or I-70 East
    (the benchmark's first build); the one from 857 m back held 195.9 m in 2,264 m. A
    ramp joining a fitted ramp along it, neither a loop nor straight-on, now counts both,
    one after the other: 38.25 + 1.5 x (471 + 365 + 80) = 1,412 m back, and r7 is first
    try. (Built with r2 fitted before r5, :func:`_before_collector_round`, as found: with
    r2 round r5 this set's window reaches 1,297 m back, r7 still first try. The
    first build only: in it r2 crosses r5, which since GEOMETRY_VERSION 46 builds it again.)"""
    _before_collector_round(monkeypatch)
    out = _columbus_outcomes((3, 5, 5, 5), {
        "r1": (280.0, 1.0), "r10": (30.0, 3.0), "r11": (210.0, 4.0), "r12": (math.inf, 5.0),
        "r13": (150.0, 0.0), "r14": (60.0, 5.0), "r2": (100.0, 5.0), "r3": (30.0, 1.0),
        "r4": (100.0, 5.0), "r5": (40.0, 3.0), "r6": (40.0, 2.0), "r7": (210.0, 4.0),
        "r8": (210.0, 2.0), "r9": (150.0, 4.0)}, 15, 1234895117,
        LayoutSettings(rebuilds=0))
    r7 = out["r7"].fit
    assert r7.spec.end.parent == "r3"
    assert out["r7"].first_try_ok and r7.conflicts == 0
    assert r7.spec.start.lo == pytest.approx(-1411.8, abs=1.0)


@pytest.mark.slow
@pytest.mark.skipif(not COLUMBUS.is_file(), reason=f"no real OSM extract at {COLUMBUS}")
@pytest.mark.parametrize("sample,seed,lanes,feats", [
    (18, 925531568, (4, 4, 3, 3), {"r1": (math.inf, 1.0), "r10": (280.0, 4.0),
                                   "r11": (60.0, 5.0), "r12": (math.inf, 4.0),
                                   "r13": (150.0, 0.0), "r14": (100.0, 5.0), "r2": (150.0, 2.0),
                                   "r3": (40.0, 4.0), "r4": (100.0, 2.0), "r5": (30.0, 3.0),
                                   "r6": (40.0, 5.0), "r7": (150.0, 5.0), "r8": (60.0, 3.0),
                                   "r9": (60.0, 4.0)}),
])
def test_columbus_r11_at_60m_keeps_its_run_beside_i270_north_for_r12(sample, seed, lanes,
                                                                       feats):
    """Drawn set 18 of benchmarks/geometry.py --osm (its seed): r11 at 60 m, round
    the loop r6, could not keep within the child's room (RUN_SLACK_M 4: the edge strip
    and the run's band left its centre a 4 m slot over the run's first 40 m; every try
    grazed one or the other in 2-3 samples), so it was fitted without them, merged
    before its run at r1's 7 m, and r12 (inf) bent to 18 m to join it there (set 8, the
    same cause, builds r12 first try here on main too: without the benchmark's resampler
    r2 is not resampled before r11). Now r11 tries a slot twice as wide
    (beside.run_slacks) before it drops the child's room: it keeps its run, and r12
    joins it there straight."""
    from flyover.geometry.straight import inf_met  # noqa: PLC0415

    topo, lanes, feats = _columbus_set(lanes, feats)
    ic = build_interchange(topo, lanes, feats, class_id="cd9e4c3eca6", sample=sample,
                           seed=seed)
    out = {o.ramp: o for o in ic.outcomes}
    assert out["r11"].first_try_ok and out["r12"].first_try_ok
    r11, r12 = out["r11"].fit, out["r12"].fit
    assert r11.spec.end_z_first  # fitted within its run, not on the plain spec
    assert r11.end_pose[3] == pytest.approx(0.0, abs=1e-6)
    assert inf_met(min(r12.min_radius_m, r12.point_radius_m))
    assert abs(r12.end_pose[3] - r12.start_pose[3]) < 1.0  # level with r13's end


@pytest.mark.slow
@pytest.mark.skipif(not COLUMBUS.is_file(), reason=f"no real OSM extract at {COLUMBUS}")
def test_columbus_r11_runs_straight_beside_i270_north_where_r12_joins():
    """Drawn set 16 of benchmarks/geometry.py --osm (its seed): r11 (100 m) kept its run's
    band, but only the run's first gap_m was also kept off the road's edge, so it was
    still turning over the rest (97.4 -> 94.0 deg against the road's 90 deg). r12 (inf)
    from r13's end (at 89.1 deg, about on r11's line) got 44 m of window on it, wound
    1,800-2,000 m east and back and met r11. Now r11 is first held off the edge over the
    whole run (beside.run_slacks): it runs straight there and r12 joins it first try."""
    from flyover.geometry.straight import inf_met  # noqa: PLC0415

    out = _columbus_outcomes((3, 5, 5, 4), {
        "r1": (150.0, 4.0), "r10": (210.0, 4.0), "r11": (100.0, 1.0), "r12": (math.inf, 2.0),
        "r13": (math.inf, 0.0), "r14": (210.0, 2.0), "r2": (150.0, 5.0), "r3": (150.0, 4.0),
        "r4": (60.0, 5.0), "r5": (30.0, 2.0), "r6": (60.0, 3.0), "r7": (40.0, 2.0),
        "r8": (210.0, 2.0), "r9": (210.0, 2.0)}, sample=16, seed=3499249847)
    assert out["r11"].first_try_ok and out["r12"].first_try_ok
    r12 = out["r12"].fit
    assert inf_met(min(r12.min_radius_m, r12.point_radius_m))
    assert r12.length_m < 1000.0  # straight on, not round and back


def _columbus_set(lanes, feats):
    from flyover.osm import read_osm_topologies  # noqa: PLC0415

    topo = next(t for t in read_osm_topologies(COLUMBUS) if t.ramps)
    return (topo, dict(zip(("I270N", "I270S", "I70E", "I70W"), lanes)),
            {r: RampFeatures(*v) for r, v in feats.items()})


def _columbus_outcomes(lanes, feats, sample, seed, settings=None):
    """Columbus built with ``lanes`` (I270N, I270S, I70E, I70W) and ``feats`` (ramp ->
    (radius, slope)) at a drawn set's sample and seed: ramp -> outcome."""
    topo, lanes, feats = _columbus_set(lanes, feats)
    ic = build_interchange(topo, lanes, feats, class_id="cd9e4c3eca6", sample=sample,
                           seed=seed, settings=settings)
    return {o.ramp: o for o in ic.outcomes}


@pytest.mark.slow
@pytest.mark.skipif(not COLUMBUS.is_file(), reason=f"no real OSM extract at {COLUMBUS}")
def test_columbus_r12_window_takes_in_r11s_whole_run_beside_i270_north():
    """Drawn set 25 of benchmarks/geometry.py --osm (its seed): r11 (210 m) goes round
    the loop r6 and runs beside I-270 North near its end, at 1,759-1,836 m of 2,085 m;
    r12's window on it was 40-85 % of r11 (rails.RampWindows.window), so only
    14 m of the run was left and r12 (inf) turned into it at 66 m. Now the window takes
    in the whole run (RampWindows.reach_run): r12 joins it straight."""
    from flyover.geometry.straight import inf_met  # noqa: PLC0415

    topo, lanes, feats = _columbus_set((5, 5, 5, 3), {
        "r1": (280.0, 1.0), "r10": (math.inf, 1.0), "r11": (210.0, 1.0),
        "r12": (math.inf, 3.0), "r13": (100.0, 0.0), "r14": (150.0, 3.0), "r2": (150.0, 5.0),
        "r3": (60.0, 1.0), "r4": (150.0, 1.0), "r5": (30.0, 1.0), "r6": (30.0, 2.0),
        "r7": (280.0, 5.0), "r8": (30.0, 5.0), "r9": (60.0, 4.0)})
    ic = build_interchange(topo, lanes, feats, class_id="cd9e4c3eca6", sample=25,
                           seed=1656115918)
    out = {o.ramp: o for o in ic.outcomes}
    assert out["r12"].first_try_ok
    r12 = out["r12"].fit
    assert inf_met(min(r12.min_radius_m, r12.point_radius_m))
    assert r12.spec.end.hi - r12.spec.end.lo > 50.0  # most of the 80 m run


@pytest.mark.slow
@pytest.mark.skipif(not COLUMBUS.is_file(), reason=f"no real OSM extract at {COLUMBUS}")
def test_columbus_r11_is_not_restarted_in_the_narrow_slot_it_grazes(monkeypatch):
    """Drawn set 13 of benchmarks/geometry.py --osm (its seed): r11 (280 m) round the loop
    r6, held off I-270 North's edge over its whole run in the 4 m slot
    (beside.run_slacks' first try), grazed it with both quick fits, then was lifted and
    restarted 7 times more (1.4 of the set's 4-5 s CPU) and grazed it still; the slot
    twice as wide then took it first time. On 32 drawn sets the lifts and restarts in
    the narrow slot never met the fences (the third seed did once, set 25), nor in the
    two slots over the run's first gap_m (sets 14, 18): only the wide slot to the run's
    end (sets 2, 8, 16, 30) and the plain spec keep them (build._round_fit). (Built with
    r2 fitted before r5, :func:`_before_collector_round`, as found: with r2 round r5,
    r13 is longer and r12 at inf / 1 % misses its slope on this set.)"""
    import flyover.geometry.build as build  # noqa: PLC0415

    _before_collector_round(monkeypatch)

    calls = []

    def counted(b, spec, seed, keep_out=frozenset(), *args, **kw):
        calls.append((spec.id, bool(keep_out)))
        return _fit_with_levels(b, spec, seed, keep_out, *args, **kw)

    monkeypatch.setattr(build, "_fit_with_levels", counted)
    out = _columbus_outcomes((5, 4, 5, 5), {
        "r1": (math.inf, 1.0), "r10": (150.0, 4.0), "r11": (280.0, 2.0), "r12": (math.inf, 1.0),
        "r13": (40.0, 0.0), "r14": (math.inf, 2.0), "r2": (100.0, 4.0), "r3": (280.0, 2.0),
        "r4": (210.0, 5.0), "r5": (100.0, 1.0), "r6": (210.0, 1.0), "r7": (150.0, 3.0),
        "r8": (30.0, 1.0), "r9": (30.0, 1.0)}, sample=13, seed=2700649528)
    assert out["r11"].first_try_ok and out["r12"].first_try_ok
    assert out["r11"].fit.spec.end_z_first  # kept its run for r12
    assert ("r11", True) not in calls  # no lifts nor restarts round r6


@pytest.mark.slow
@pytest.mark.skipif(not COLUMBUS.is_file(), reason=f"no real OSM extract at {COLUMBUS}")
def test_columbus_r1_a_stub_is_not_restarted_round_its_loop(monkeypatch):
    """Drawn set 0 of benchmarks/geometry.py --osm (its seed): r1 (100 m / 4 %, a stub)
    round the loop r6 missed its radius (57-85 m) or its length bound (713 m) with both
    quick fits, then with the third seed and five restarts (8 searches, 1.5 s of the
    set's 2.7 s CPU), then met its targets first time as any other ramp (212 m). On 32
    drawn sets the restarts met them on 2 (3, 20): a stub is no longer lifted nor
    restarted round its loop (build._round_fit)."""
    import flyover.geometry.build as build  # noqa: PLC0415

    calls = []

    def counted(b, spec, seed, keep_out=frozenset(), *args, **kw):
        calls.append((spec.id, bool(keep_out)))
        return _fit_with_levels(b, spec, seed, keep_out, *args, **kw)

    monkeypatch.setattr(build, "_fit_with_levels", counted)
    out = _columbus_outcomes((4, 4, 4, 3), {
        "r1": (100.0, 4.0), "r10": (280.0, 5.0), "r11": (210.0, 3.0), "r12": (math.inf, 5.0),
        "r13": (math.inf, 0.0), "r14": (math.inf, 3.0), "r2": (30.0, 2.0), "r3": (150.0, 3.0),
        "r4": (60.0, 4.0), "r5": (30.0, 4.0), "r6": (30.0, 3.0), "r7": (60.0, 4.0),
        "r8": (30.0, 3.0), "r9": (60.0, 3.0)}, sample=0, seed=2318073955)
    assert all(o.first_try_ok for o in out.values())
    assert ("r1", True) not in calls  # no lifts nor restarts round r6


@pytest.mark.slow
@pytest.mark.skipif(not COLUMBUS.is_file(), reason=f"no real OSM extract at {COLUMBUS}")
def test_columbus_r2_climbing_further_than_its_shortest_path_detours_for_its_climb(
        monkeypatch):
    """Drawn set 29 of benchmarks/geometry.py --osm (its seed): r2 (60 m / 1 %, from r8's
    free end at 0.5 m to r14's at 12 m, 626 m apart at least) needs 1,190 m to climb
    11.5 m at 1 %; every restart started near the shortest path and came out 629-825 m
    long at 1.46-1.95 % with no conflict (or with one), so it missed its first try. Now a
    search started from detours as long as its climb (build._detours) meets its targets,
    no longer than twice its climb (build.DETOUR_LENGTH_RATIO). (Built with r2 fitted
    before r5, :func:`_before_collector_round`, as found: round r5 it is first try at
    1,128 m, its ends elsewhere.)"""
    from flyover.osm import read_osm_topologies  # noqa: PLC0415

    _before_collector_round(monkeypatch)

    topo = next(t for t in read_osm_topologies(COLUMBUS) if t.ramps)
    lanes = dict(zip(("I270N", "I270S", "I70E", "I70W"), (4, 4, 5, 5)))
    feats = {r: RampFeatures(*v) for r, v in {
        "r1": (280.0, 1.0), "r10": (210.0, 3.0), "r11": (280.0, 2.0), "r12": (math.inf, 4.0),
        "r13": (math.inf, 0.0), "r14": (math.inf, 2.0), "r2": (60.0, 1.0), "r3": (30.0, 2.0),
        "r4": (280.0, 2.0), "r5": (40.0, 4.0), "r6": (30.0, 5.0), "r7": (280.0, 3.0),
        "r8": (60.0, 1.0), "r9": (150.0, 3.0)}.items()}
    ic = build_interchange(topo, lanes, feats, class_id="cd9e4c3eca6", sample=29,
                           seed=1795170021)
    r2 = {o.ramp: o for o in ic.outcomes}["r2"]
    assert r2.first_try_ok and r2.fit.conflicts == 0
    assert r2.fit.max_slope_pct == pytest.approx(1.0, abs=0.2)
    assert 1_150.0 < r2.fit.length_m <= r2.fit.max_length_m <= 2.0 * 1_190.0 + 80.0


@pytest.mark.slow
@pytest.mark.skipif(not COLUMBUS.is_file(), reason=f"no real OSM extract at {COLUMBUS}")
@pytest.mark.parametrize("sample,seed,lanes,feats", [
    (17, 2811584545, (5, 4, 3, 3), {
        "r1": (150.0, 4.0), "r10": (280.0, 2.0), "r11": (210.0, 5.0), "r12": (math.inf, 5.0),
        "r13": (280.0, 0.0), "r14": (150.0, 2.0), "r2": (100.0, 4.0), "r3": (40.0, 1.0),
        "r4": (150.0, 1.0), "r5": (40.0, 4.0), "r6": (60.0, 5.0), "r7": (210.0, 2.0),
        "r8": (math.inf, 3.0), "r9": (60.0, 3.0)}),
    (21, 1708889815, (4, 5, 4, 5), {
        "r1": (60.0, 5.0), "r10": (150.0, 4.0), "r11": (60.0, 2.0), "r12": (math.inf, 2.0),
        "r13": (60.0, 0.0), "r14": (100.0, 5.0), "r2": (100.0, 2.0), "r3": (40.0, 2.0),
        "r4": (60.0, 4.0), "r5": (40.0, 3.0), "r6": (40.0, 3.0), "r7": (40.0, 5.0),
        "r8": (100.0, 5.0), "r9": (30.0, 4.0)}),
])
def test_columbus_r11s_run_moves_along_i270_north_for_r12_that_cannot_come_round(
        sample, seed, lanes, feats):
    """Drawn sets 17 and 21 of benchmarks/geometry.py --osm (their seeds): r13 ends 3.7°
    and 12.6° off I-270 North toward it (set 21: 10 m off its edge) and r11 still turns
    in its run (98 -> 94° on set 17), so r12 (inf), 240-630 m from r13's end to the run,
    swung away and back to come round to r11's heading: radius 226-233 m and 57 m, and
    missed its first try (set 21 recorded infeasible). Now r11 is fitted again with its
    run half, then all of r12's 250 m farther along (build._moved_run) and r12 then joins
    it straight."""
    from flyover.geometry.straight import inf_met  # noqa: PLC0415

    topo, lanes, feats = _columbus_set(lanes, feats)
    ic = build_interchange(topo, lanes, feats, class_id="cd9e4c3eca6", sample=sample,
                           seed=seed)
    out = {o.ramp: o for o in ic.outcomes}
    assert out["r12"].first_try_ok and out["r11"].first_try_ok
    r12 = out["r12"].fit
    assert inf_met(min(r12.min_radius_m, r12.point_radius_m))
    assert r12.spec.end.parent == "r11" and out["r11"].fit.ok


BANGOR = OSM_DIR / "06_us_me_bangor_i95_i395.osm"


@pytest.mark.skipif(not BANGOR.is_file(), reason=f"no real OSM extract at {BANGOR}")
def test_the_bangor_cloverleaf_is_laid_out_as_it_turns_not_mirrored(tmp_path):
    """Bangor (file 06) is a cloverleaf: every ramp leaves and joins on the right, so both
    orientations of I-95 score the same turn sides, and the first one was the mirror of
    the real interchange: r1-r4 (real outer connectors, turning right by 39-139 deg between
    the roads) turned left and, leaving before the crossing, were 1.4-3 km flyovers, and
    r5-r8 (the real loops, -237 to -268 deg) were right turns; 16 of 128 first tries missed.
    The reader's ``turn_deg`` of each ramp decides the tie, also read back from the
    GraphML the workflow writes, and makes r7 a loop though it leaves at 0.35 (a left turn
    leaving before 0.4 is a flyover where the real turn is unknown). Each loop is fitted
    before the outer connector that goes round it (by id the connectors came first and
    then went over or under their loops)."""
    from flyover.geometry.chains import Movements  # noqa: PLC0415
    from flyover.geometry.feasibility import round_loops  # noqa: PLC0415
    from flyover.geometry.roads import layout_roads  # noqa: PLC0415
    from flyover.osm import read_osm_topologies  # noqa: PLC0415
    from flyover.topology.io import read_graphml, write_graphml  # noqa: PLC0415

    write_graphml(next(t for t in read_osm_topologies(BANGOR) if t.ramps), tmp_path / "b.graphml")
    topo = read_graphml(tmp_path / "b.graphml")
    turn = {r: topo.graph.nodes[r]["turn_deg"] for r in topo.ramps}
    assert all(-100 < turn[r] < -40 for r in ("r1", "r2", "r3", "r4")), turn
    assert all(-280 < turn[r] < -230 for r in ("r5", "r6", "r7", "r8")), turn
    moves = Movements(topo, layout_roads(topo, {}, LayoutSettings()))
    assert all(moves.movement(r) < 0 for r in ("r1", "r2", "r3", "r4"))  # right turns
    assert all(moves.movement(r) > 0 for r in ("r5", "r6", "r7", "r8"))
    assert {r for r in topo.ramps if moves.is_loop(r)} == {"r5", "r6", "r7", "r8"}
    pairs = {(p.connector, p.loop) for p in round_loops(topo)}
    assert pairs == {("r1", "r6"), ("r2", "r7"), ("r3", "r8"), ("r4", "r5")}
    order = LayoutState(topo, {}, {}, LayoutSettings(), 0).order()
    assert all(order.index(loop) < order.index(c) for c, loop in pairs), order


@pytest.mark.parametrize("path", sorted(OSM_DIR.glob("*.osm")), ids=lambda p: p.stem[:2])
def test_every_real_interchange_is_laid_out_turning_as_its_ramps_really_turn(path):
    """Each ramp between two roads with a real turn of 20-160 deg either way (its
    ``turn_deg`` wrapped) turns to that side in the layout, on every shared extract (before,
    Bangor, Sydney, Portland Marquam and Boston I-93 / US 1 were laid out mirrored)."""
    from flyover.geometry.chains import ends, wrap  # noqa: PLC0415
    from flyover.geometry.roads import layout_roads  # noqa: PLC0415
    from flyover.osm import read_osm_topologies  # noqa: PLC0415

    for topo in (t for t in read_osm_topologies(path) if t.ramps):
        roads = layout_roads(topo, {}, LayoutSettings())
        for ramp in topo.ramps:
            start, end = ends(topo, ramp)
            if start is None or end is None or not {start[0], end[0]} <= roads.keys() \
                    or start[0] == end[0]:
                continue
            real = wrap(math.radians(topo.graph.nodes[ramp]["turn_deg"]))
            laid = wrap(roads[end[0]].heading - roads[start[0]].heading)
            if math.radians(20) < abs(real) < math.radians(160):
                assert real * laid > 0, (topo.name, ramp, math.degrees(real), math.degrees(laid))



_SET_14 = ((5, 3, 4, 4), {
    "r1": (280.0, 2.0), "r10": (150.0, 2.0), "r11": (280.0, 4.0), "r12": (math.inf, 2.0),
    "r13": (150.0, 0.0), "r14": (210.0, 5.0), "r2": (100.0, 3.0), "r3": (280.0, 1.0),
    "r4": (150.0, 4.0), "r5": (40.0, 4.0), "r6": (210.0, 4.0), "r7": (210.0, 5.0),
    "r8": (150.0, 2.0), "r9": (60.0, 3.0)})
_SET_15 = ((5, 4, 3, 3), {
    "r1": (60.0, 1.0), "r10": (60.0, 5.0), "r11": (60.0, 1.0), "r12": (math.inf, 1.0),
    "r13": (30.0, 0.0), "r14": (280.0, 1.0), "r2": (210.0, 3.0), "r3": (60.0, 5.0),
    "r4": (280.0, 3.0), "r5": (150.0, 5.0), "r6": (40.0, 1.0), "r7": (100.0, 4.0),
    "r8": (math.inf, 2.0), "r9": (60.0, 2.0)})


def _without_swap(monkeypatch):
    from flyover.geometry import build  # noqa: PLC0415

    monkeypatch.setattr(build, "_swapped", lambda b, ramp, feat, fit, *a: fit)


def _before_collector_round(monkeypatch):
    """The layout of GEOMETRY_VERSION 44 (bytes checked): Columbus's r2 fitted before the
    loop r5 and not round it, r8 and r14 where they needed to be for themselves, r5's
    window on r13 at 40-85 % of it. Tests that pin a mechanism on a build found so."""
    from flyover.geometry.chains import Movements  # noqa: PLC0415

    monkeypatch.setattr(Movements, "round_by_collector", lambda self, ramp, loop: False)


@pytest.mark.slow
@pytest.mark.skipif(not COLUMBUS.is_file(), reason=f"no real OSM extract at {COLUMBUS}")
@pytest.mark.parametrize("swap", [True, False])
def test_columbus_r2_makes_way_round_the_loop_r5_fitted_first(swap, monkeypatch):
    """The workflow's Columbus set 15 (its sample seed): r2 (210 m / 3 %), fitted before
    the loop r5 (150 m / 5 %), ran across the quadrant the loop needs; r5 met it (one
    sample: r5, still at I-70's 6.5 m, 2.6 m above r2 climbing from the fork) and r2
    refitted round that bent curve met it again. Now r2 is taken out, r5 fitted without it and r2 fitted again round it
    (build._swapped): both first try, no conflict, r2 round the loop, not over it. With
    the swap off r5 misses as before."""
    from flyover.geometry.check import ramp_crossings  # noqa: PLC0415

    _before_collector_round(monkeypatch)  # the layout the swap was found on
    if not swap:
        _without_swap(monkeypatch)
    topo, lanes, feats = _columbus_set(*_SET_15)
    ic = build_interchange(topo, lanes, feats, class_id="cd9e4c3eca6", sample=15,
                           seed=1234895117, settings=LayoutSettings(rebuilds=0))
    out = {o.ramp: o for o in ic.outcomes}
    assert out["r5"].first_try_ok is swap
    if swap:
        assert out["r2"].first_try_ok and out["r2"].fit.conflicts == 0
        assert not [c for c in ramp_crossings(ic.geometry) if {c.ramp, c.other} == {"r2", "r5"}]


@pytest.mark.slow
@pytest.mark.skipif(not COLUMBUS.is_file(), reason=f"no real OSM extract at {COLUMBUS}")
@pytest.mark.parametrize("swap", [True, False])
def test_columbus_r5_missing_with_nothing_met_is_fitted_before_what_can_move(swap,
                                                                             monkeypatch):
    """The workflow's Columbus set 14 (its sample seed): the loop r5 (40 m / 4 %) met
    nothing but came out 28 m tight at a point, bent to keep off ramps fitted before it.
    Now, missing with nothing met, it is fitted without every fitted ramp that can move,
    and those it then meets are fitted again round it (build._swapped): every ramp first
    try and no conflict. With the swap off r5 misses as before."""
    _before_collector_round(monkeypatch)  # the layout the swap was found on
    if not swap:
        _without_swap(monkeypatch)
    topo, lanes, feats = _columbus_set(*_SET_14)
    ic = build_interchange(topo, lanes, feats, class_id="cd9e4c3eca6", sample=14,
                           seed=1050423707, settings=LayoutSettings(rebuilds=0))
    out = {o.ramp: o for o in ic.outcomes}
    assert out["r5"].first_try_ok is swap
    if swap:
        assert all(o.first_try_ok and o.fit.conflicts == 0 for o in out.values())


_SET_25 = ((5, 3, 5, 4), {
    "r1": (60.0, 5.0), "r10": (30.0, 2.0), "r11": (40.0, 3.0), "r12": (math.inf, 3.0),
    "r13": (math.inf, 0.0), "r14": (math.inf, 1.0), "r2": (210.0, 4.0), "r3": (30.0, 5.0),
    "r4": (30.0, 2.0), "r5": (150.0, 3.0), "r6": (30.0, 4.0), "r7": (60.0, 3.0),
    "r8": (150.0, 4.0), "r9": (280.0, 2.0)})


@pytest.mark.skipif(not COLUMBUS.is_file(), reason=f"no real OSM extract at {COLUMBUS}")
def test_only_columbus_r2_goes_round_a_loop_by_a_collector_road_and_its_stubs_keep_out():
    """Of the catalog and every interchange of the shared extracts, only Columbus's r2
    goes round a loop (r5) joining a collector road (r13); the stubs it leaves and joins,
    r8 and r14, keep their free ends beyond the loop's reach from the crossing, farther
    for a wider loop and for a wider connector."""
    from flyover.geometry.state import LayoutState  # noqa: PLC0415
    from flyover.osm import read_osm_topologies  # noqa: PLC0415
    from flyover.topology.catalog import catalog_topologies  # noqa: PLC0415

    topos = list(catalog_topologies().items()) + [
        (f"{p.stem[:2]}:{k}", t) for p in sorted(OSM_DIR.glob("*.osm"))
        for k, t in enumerate(t for t in read_osm_topologies(p) if t.ramps)]
    found = {}
    for name, t in topos:
        b = LayoutState(t, {}, {r: RampFeatures(150.0, 4.0) for r in t.ramps},
                        LayoutSettings(), 0)
        pairs = [(c, k) for c in t.ramps for k in t.ramps if b.moves.round_by_collector(c, k)]
        reach = {r: b.windows.loops.quadrant.reach(r) for r in t.ramps}
        found[name] = (pairs, sorted(r for r, q in reach.items() if q is not None))
    assert {n: v for n, v in found.items() if v != ([], [])} == {
        "09:0": ([("r2", "r5")], ["r14", "r8"])}

    topo, lanes, feats = _columbus_set(*_SET_25)

    def reach(**change):
        f = dict(feats, **{r: RampFeatures(*v) for r, v in change.items()})
        loops = LayoutState(topo, lanes, f, LayoutSettings(), 0).windows.loops
        (_, _, _, t8, r8), (_, _, _, t14, r14) = (loops.quadrant.reach(r) for r in ("r8", "r14"))
        assert abs(t8) < 5.0 and abs(t14) < 5.0  # from the crossing, on both roads
        return r8, r14

    r8, r14 = reach()
    assert r8 == pytest.approx(r14, abs=5.0) and 600.0 < r8 < 1_000.0
    assert reach(r5=(210.0, 3.0))[0] > r8 + 100.0  # a wider loop
    assert reach(r2=(280.0, 4.0))[0] > r8 + 20.0  # a wider connector


@pytest.mark.slow
@pytest.mark.skipif(not COLUMBUS.is_file(), reason=f"no real OSM extract at {COLUMBUS}")
@pytest.mark.parametrize("quadrant", [True, False])
def test_columbus_r2_goes_round_the_loop_r5_in_a_quadrant_laid_out_for_both(quadrant,
                                                                           monkeypatch):
    """The workflow's Columbus set 25 (its sample seed): the loop r5 (150 m / 3 %) left
    I-70 East 400 m past the crossing and swept 610 m along it, past r14's free end; r2
    (210 m / 4 %), fitted before it, ran straight across the quadrant from r8's free end
    to r14's and passed over r5 twice. Now r5 is fitted first, joining r13 near the
    crossing; r8 and r14 end beyond the loop's reach, and r2 is fitted round r5
    (Movements.round_by_collector): every ramp first try, r2 not over nor under r5. With
    that off r2 crosses r5 as before."""
    from flyover.geometry.check import ramp_crossings  # noqa: PLC0415
    from flyover.geometry.state import LayoutState  # noqa: PLC0415

    if not quadrant:
        _before_collector_round(monkeypatch)
    topo, lanes, feats = _columbus_set(*_SET_25)
    ic = build_interchange(topo, lanes, feats, class_id="cd9e4c3eca6", sample=25,
                           seed=1656115918)
    crossed = {frozenset((c.ramp, c.other)) for c in ramp_crossings(ic.geometry)}
    assert (frozenset(("r2", "r5")) not in crossed) is quadrant
    if quadrant:
        assert all(o.first_try_ok and o.fit.conflicts == 0 for o in ic.outcomes)
        # the stubs attach to their roads beyond the loop's reach and their tapers (their
        # free ends are kept beyond the reach by fences, as long as they meet their
        # targets so); stations from the crossing, I-270 North northward, I-70 East eastward
        need = LayoutState(topo, lanes, feats, LayoutSettings(), 0).windows.loops \
            .quadrant.reach("r8")[4] + 1.5 * LayoutSettings().gap_m
        out = {o.ramp: o.fit.spec for o in ic.outcomes}
        assert out["r8"].start.hi <= -need + 5.0 and out["r14"].end.lo >= need - 5.0
        r8_end = np.asarray(ic.geometry.ramps[[r.id for r in ic.geometry.ramps].index(
            "r8")].plan[-1].p)[-1]
        assert r8_end[1] <= -need + 1.5 * LayoutSettings().gap_m + 2.0


_SET_53 = ((3, 5, 4, 4), {
    "r1": (210.0, 1.0), "r10": (30.0, 4.0), "r11": (210.0, 2.0), "r12": (math.inf, 5.0),
    "r13": (100.0, 0.0), "r14": (60.0, 3.0), "r2": (60.0, 5.0), "r3": (40.0, 2.0),
    "r4": (210.0, 3.0), "r5": (40.0, 3.0), "r6": (150.0, 1.0), "r7": (210.0, 4.0),
    "r8": (280.0, 4.0), "r9": (60.0, 1.0)})


@pytest.mark.slow
@pytest.mark.skipif(not COLUMBUS.is_file(), reason=f"no real OSM extract at {COLUMBUS}")
def test_an_outer_connector_over_its_loop_is_built_again_with_other_seeds():
    """The workflow's Columbus set 53 (its sample seed): the first build, with no ramp at
    another's level, takes r2 (60 m / 5 %) over the loop r5 (40 m / 3 %); that is a
    bridge the design does not have, so the interchange is built again with other seeds,
    as one with a same-level conflict, and the build kept has r2 round r5, every ramp
    within its targets; first try stays the first build's."""
    from flyover.geometry.check import ramp_crossings  # noqa: PLC0415

    topo, lanes, feats = _columbus_set(*_SET_53)
    builds = {}
    for rebuilds in (0, LayoutSettings().rebuilds):
        ic = build_interchange(topo, lanes, feats, class_id="cd9e4c3eca6", sample=53,
                               seed=3298058556, settings=LayoutSettings(rebuilds=rebuilds))
        crossed = {frozenset((c.ramp, c.other)) for c in ramp_crossings(ic.geometry)}
        builds[rebuilds] = (ic, frozenset(("r2", "r5")) in crossed)
    (first, first_across), (kept, kept_across) = builds.values()
    assert first_across and not kept_across
    assert first.geometry.seed == 3298058556 and kept.geometry.seed != 3298058556
    assert all(o.fit.ok and o.fit.conflicts == 0 for o in kept.outcomes)
    assert [o.first_try_ok for o in kept.outcomes] == [o.first_try_ok for o in first.outcomes]
