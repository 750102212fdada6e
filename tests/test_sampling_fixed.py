"""Fixed features: what geometry knows up front (slope 0 on level ramps) is written, not sampled.

Coverage is checked by the sampling tests' independent brute-force checker.
"""

from __future__ import annotations

import io
import json
import math
from dataclasses import replace

import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from flyover.cli import main
from flyover.errors import ConfigError
from flyover.geometry.feasibility import (
    fixed_features, forbidden_features, level_ramps, round_loops, turning_ramps,
)
from flyover.geometry.layout import LayoutSettings, RampFeatures
from flyover.geometry.tables import build_sample, domain_resampler
from flyover.sampling.constraints import Constraints
from flyover.sampling.model import ElementCondition, Feature, ForbidRule, default_profile, feature_model
from flyover.sampling.sample import FEATURES_SCHEMA, sample_topology
from flyover.topology.catalog import catalog_topologies
from flyover.topology.model import Connection, Kind, Label, Ramp, Road, Topology
from tests.test_geometry_osm_topologies import COLUMBUS, _collector_round
from tests.test_sampling import cells, independent_coverage

CD_ROADS = {"cA1", "cA2", "cB1", "cB2"}


@pytest.fixture(scope="module")
def cloverleaf_cd():
    return catalog_topologies()["cloverleaf_cd"]


@pytest.fixture(scope="module")
def cd_sampling(cloverleaf_cd):
    return sample_topology(cloverleaf_cd, default_profile(), t=2, seed=11,
                           fixed=fixed_features(cloverleaf_cd))


def _bytes(sampling) -> bytes:
    buf = io.BytesIO()
    pq.write_table(pa.Table.from_pylist(sampling.feature_rows(), schema=FEATURES_SCHEMA), buf)
    return buf.getvalue()


# -- which ramps are level ----------------------------------------------------------------


def test_level_ramps_are_the_collector_distributor_roads_of_cloverleaf_cd(cloverleaf_cd):
    assert level_ramps(cloverleaf_cd) == CD_ROADS
    assert fixed_features(cloverleaf_cd) == {(r, Feature.SLOPE_PCT): 0.0 for r in CD_ROADS}


def test_ramps_between_different_roads_or_from_a_ramp_are_not_level():
    # r1 leaves and rejoins A1 (level); r2 leaves r1 and rejoins A1 (not both on one road);
    # r3 goes A1 -> B1 (different roads)
    t = Topology.build("x", roads=[Road("A1", "A"), Road("A2", "A"), Road("B1", "B"), Road("B2", "B")],
                       ramps=[Ramp("r1"), Ramp("r2"), Ramp("r3")],
                       connections=[Connection("A1", "r1", Label.OUT_R), Connection("r1", "A1", Label.IN_R),
                                    Connection("r1", "r2", Label.OUT_R), Connection("r2", "A1", Label.IN_R),
                                    Connection("A1", "r3", Label.OUT_R), Connection("r3", "B1", Label.IN_R)])
    assert level_ramps(t) == {"r1"}
    assert level_ramps(catalog_topologies()["j1"]) == frozenset()


# -- sampling with fixed features ------------------------------------------------------------


def test_cloverleaf_cd_rows_have_slope_0_on_exactly_the_cd_roads(cd_sampling, cloverleaf_cd):
    rows = cd_sampling.feature_rows()
    assert len(rows) == cd_sampling.coverage.rows * (cloverleaf_cd.n_roads + cloverleaf_cd.n_ramps)
    ramps = [r for r in rows if r["kind"] == "ramp"]
    assert {r["element"] for r in ramps if r["slope_pct"] == 0.0} == CD_ROADS
    assert all(r["slope_pct"] == 0.0 for r in ramps if r["element"] in CD_ROADS)
    assert all(r["slope_pct"] in (1, 2, 3, 4, 5) for r in ramps if r["element"] not in CD_ROADS)
    # their radius is still sampled, over its whole domain
    assert {r["radius_m"] for r in ramps if r["element"] == "cA1"} == set(
        default_profile().domain(Kind.RAMP)[Feature.RADIUS_M])


def test_fixed_features_are_no_parameters_and_the_rest_is_fully_covered(cd_sampling, cloverleaf_cd):
    model = cd_sampling.model
    unfixed = feature_model(cloverleaf_cd, default_profile())
    assert len(model.parameters) == len(unfixed.parameters) - len(CD_ROADS)
    assert not any(p.element in CD_ROADS and p.feature is Feature.SLOPE_PCT for p in model.parameters)
    covered, total = independent_coverage(cd_sampling.array.rows, model.levels, 2, cells(model.forbidden))
    assert covered == total > 0
    c = cd_sampling.coverage
    assert (c.n_params, c.tuples_total, c.tuples_covered) == (len(model.parameters), total, covered)
    assert c.rows >= c.lower_bound


def test_a_design_without_level_ramps_samples_the_same_bytes():
    j1 = catalog_topologies()["j1"]
    assert fixed_features(j1) == {}
    plain = sample_topology(j1, default_profile(), t=2, seed=5)
    fixed = sample_topology(j1, default_profile(), t=2, seed=5, fixed=fixed_features(j1))
    assert fixed.model.fixed == ()
    assert _bytes(fixed) == _bytes(plain)


def test_a_rule_on_a_fixed_feature_applies_only_where_the_fixed_value_matches(cloverleaf_cd):
    fixed = fixed_features(cloverleaf_cd)

    def rule(slope):
        return ForbidRule((ElementCondition(Kind.RAMP, ((Feature.RADIUS_M, frozenset({30.0})),
                                                        (Feature.SLOPE_PCT, frozenset({slope})))),),)

    model = feature_model(cloverleaf_cd, default_profile(), extra=[rule(0.0)], fixed=fixed)
    constrained = [model.parameters[f.params[0]] for f in model.forbidden]
    assert sorted(p.element for p in constrained) == sorted(CD_ROADS)  # 0 matches only there
    assert all(p.feature is Feature.RADIUS_M and len(f.params) == 1
               for p, f in zip(constrained, model.forbidden))
    s = sample_topology(cloverleaf_cd, default_profile(), seed=2, extra=[rule(0.0)], fixed=fixed)
    assert not any(r["element"] in CD_ROADS and r["radius_m"] == 30 for r in s.feature_rows())
    # a slope-5 rule never holds on a ramp fixed at 0: it constrains only the others
    model5 = feature_model(cloverleaf_cd, default_profile(), extra=[rule(5.0)], fixed=fixed)
    assert {model5.parameters[f.params[0]].element for f in model5.forbidden} == \
        set(cloverleaf_cd.ramps) - CD_ROADS


def test_bad_fixed_features_are_config_errors_naming_the_element(cloverleaf_cd):
    with pytest.raises(ConfigError) as err:
        feature_model(cloverleaf_cd, default_profile(), fixed={("zz", Feature.SLOPE_PCT): 0.0})
    assert err.value.element == "zz"
    only_fixed = ForbidRule((ElementCondition(Kind.RAMP, ((Feature.SLOPE_PCT, frozenset({0.0})),),
                                              "cA1"),))
    with pytest.raises(ConfigError, match="forbidden combination") as err:
        feature_model(cloverleaf_cd, default_profile(), extra=[only_fixed],
                      fixed=fixed_features(cloverleaf_cd))
    assert err.value.element == "cA1"


def test_cli_sample_reports_the_fixed_slopes(capsys):
    assert main(["sample", "cloverleaf_cd", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["fixed"] == {f"{r}.slope_pct": 0.0 for r in sorted(CD_ROADS)}
    assert out["tuples_covered"] == out["tuples_total"]


# -- geometry meets the fixed slope --------------------------------------------------------


def test_resampling_keeps_a_level_ramp_level_and_never_draws_0_for_others():
    sets = {0: ({}, {"c": RampFeatures(100.0, 0.0), "r": RampFeatures(60.0, 3.0)}),
            1: ({}, {"c": RampFeatures(30.0, 0.0), "r": RampFeatures(40.0, 5.0)})}
    draw = domain_resampler(sets, seed=1)
    assert all(draw("c", k).slope_pct == 0.0 for k in range(1, 20))
    assert {draw("r", k).slope_pct for k in range(1, 40)} == {3.0, 5.0}


@pytest.mark.slow
def test_a_cloverleaf_cd_feature_set_builds_its_cd_roads_level_and_ok(cd_sampling, cloverleaf_cd):
    from flyover.geometry.tables import read_feature_sets

    buf = io.BytesIO(_bytes(cd_sampling))
    sets = read_feature_sets(buf)
    ic = build_sample(cloverleaf_cd, sets[0], class_id=cd_sampling.class_id, sample=0, seed=1,
                      settings=LayoutSettings())
    cd = {o.ramp: o for o in ic.outcomes if o.ramp in CD_ROADS}
    assert set(cd) == CD_ROADS
    for o in cd.values():
        assert o.fit.spec.target_slope_pct == 0.0
        assert o.fit.max_slope_pct == pytest.approx(0.0, abs=1e-9)
        assert o.fit.ok and o.first_try_ok and o.infeasible == ""


# -- ramps that must turn: no inf radius -------------------------------------------------


def test_ramps_that_must_turn_are_every_ramp_but_stubs_cd_roads_and_straight_ones():
    topos = catalog_topologies()
    stack = topos["stack4"]
    assert sorted(set(stack.ramps) - turning_ramps(stack)) == \
        ["eA1", "eA2", "eB1", "eB2", "mA1", "mA2", "mB1", "mB2"]  # the stubs
    assert turning_ramps(topos["cloverleaf_cd"]) == \
        frozenset(topos["cloverleaf_cd"].ramps) - CD_ROADS
    assert turning_ramps(topos["trumpet"]) == frozenset(topos["trumpet"].ramps)


def test_inf_is_forbidden_on_turning_ramps_and_the_rest_is_fully_covered(cloverleaf_cd):
    profile = default_profile()
    extra = forbidden_features(cloverleaf_cd, profile)
    s = sample_topology(cloverleaf_cd, profile, t=2, seed=11,
                        fixed=fixed_features(cloverleaf_cd), extra=extra)
    rows = [r for r in s.feature_rows() if r["kind"] == "ramp"]
    turning = turning_ramps(cloverleaf_cd)
    assert not [r for r in rows if r["element"] in turning and r["radius_m"] == math.inf]
    # every other radius still occurs on every turning ramp but what its loop (connector)
    # rules out (round_loops: no loop of 280 m, no connector of 30 m), and the C-D roads
    # keep inf
    pairs = round_loops(cloverleaf_cd)
    for ramp in turning:
        ruled_out = {280.0} if ramp in {p.loop for p in pairs} else \
            {30.0} if ramp in {p.connector for p in pairs} else set()
        assert {r["radius_m"] for r in rows if r["element"] == ramp} == \
            set(profile.domain(Kind.RAMP)[Feature.RADIUS_M]) - {math.inf} - ruled_out
    assert any(r["element"] in CD_ROADS and r["radius_m"] == math.inf for r in rows)
    model = s.model
    # a connector of 30 m and a loop of 280 m are in no valid row (implied)
    covered, total = independent_coverage(s.array.rows, model.levels, 2, cells(model.forbidden),
                                          Constraints(model.levels, model.forbidden).extendable)
    assert covered == total == s.coverage.tuples_total > 0


def test_a_profile_without_inf_forbids_only_tight_connector_loop_pairs(cloverleaf_cd):
    p = default_profile()
    domains = tuple((k, tuple((f, tuple(v for v in vs if v != math.inf)) for f, vs in fs))
                    for k, fs in p.domains)
    # only the pairs of an outer connector and its loop (round_loops) are left
    without = forbidden_features(cloverleaf_cd, replace(p, domains=domains))
    assert without and all(len(r.elements) == 2 for r in without)
    assert len(forbidden_features(cloverleaf_cd, p)) == \
        len(turning_ramps(cloverleaf_cd)) + len(without) + len(round_loops(cloverleaf_cd))


def test_resampling_keeps_a_turning_ramp_finite():
    inf = float("inf")
    sets = {0: ({}, {"t": RampFeatures(100.0, 3.0), "s": RampFeatures(inf, 3.0)}),
            1: ({}, {"t": RampFeatures(30.0, 4.0), "s": RampFeatures(40.0, 5.0)})}
    draw = domain_resampler(sets, seed=1)
    assert draw.finite == frozenset({"t"})
    assert all(draw("t", k).radius_m != inf for k in range(1, 40))
    assert all(draw.clearing("t", k).radius_m != inf for k in range(1, 40))
    assert inf in {draw("s", k).radius_m for k in range(1, 40)}


# -- outer connectors round their loops: wider than the loop ---------------------------------


def _pair_allowed(model, connector: str, loop: str) -> dict[tuple[float, float], bool]:
    """(connector radius, loop radius) → whether some valid row holds it."""
    cons = Constraints(model.levels, model.forbidden)
    col = {p.element: i for i, p in enumerate(model.parameters) if p.feature is Feature.RADIUS_M}
    vc, vl = model.parameters[col[connector]].values, model.parameters[col[loop]].values
    return {(a, b): cons.extendable({col[connector]: i, col[loop]: j})
            for i, a in enumerate(vc) for j, b in enumerate(vl)}


@pytest.mark.parametrize("design, pairs", [
    ("cloverleaf", [("oA1", "lB1"), ("oA2", "lB2"), ("oB1", "lA2"), ("oB2", "lA1")]),
    ("cloverstack", [("oA1", "lB1"), ("oA2", "lB2")]),
    # through its collector-distributor roads (each the carriageway it runs beside)
    ("cloverleaf_cd", [("oA1", "lB1"), ("oA2", "lB2"), ("oB1", "lA2"), ("oB2", "lA1")]),
])
def test_an_outer_connector_must_be_wider_than_its_loop_and_nothing_else_is_forbidden(
        design, pairs):
    topo = catalog_topologies()[design]
    assert [(p.connector, p.loop) for p in round_loops(topo)] == pairs
    profile = default_profile()
    model = feature_model(topo, profile, forbidden_features(topo, profile))
    # one lane each: the connector's 4 m, half the loop's and 1 m between centre lines
    assert {p.margin_m for p in round_loops(topo)} == {7.0}
    for connector, loop in pairs:
        allowed = _pair_allowed(model, connector, loop)
        assert allowed == {(a, b): math.isfinite(a) and math.isfinite(b) and a >= b + 7.0
                           for a, b in allowed}
        assert allowed[(40.0, 30.0)] and not allowed[(40.0, 40.0)] and not allowed[(30.0, 40.0)]
    # a connector and another pair's loop are not constrained together: only what their
    # own loop / connector implies (no connector of 30 m: no loop is tighter by 7 m; no
    # loop of 280 m: no connector is wider)
    connector, other = pairs[0][0], pairs[1][1]
    assert _pair_allowed(model, connector, other) == {
        (a, b): 30.0 < a < math.inf and b < 280.0
        for a, b in _pair_allowed(model, connector, other)}
    # without the rule the same model allows the tight pairs (the rule is what forbids them)
    loose = feature_model(topo, profile, [r for r in forbidden_features(topo, profile)
                                          if len(r.elements) == 1])
    assert _pair_allowed(loose, *pairs[0])[(30.0, 280.0)]


def test_designs_without_loops_or_without_outer_connectors_have_no_pairs():
    topos = catalog_topologies()
    for design in ("j1", "trumpet", "stack4", "diamond", "turbine"):
        if design in topos:
            assert round_loops(topos[design]) == (), design


def test_the_pairs_come_from_the_topology_not_its_names(tmp_path):
    from tests.test_osm import cloverleaf_ways, only, write_osm

    osm = only(write_osm(tmp_path / "clover.osm", cloverleaf_ways()))
    pairs = round_loops(osm)
    assert len(pairs) == 4 and len({p.connector for p in pairs} | {p.loop for p in pairs}) == 8
    renamed = catalog_topologies()["cloverstack"].relabeled(
        {r: f"w{k}" for k, r in enumerate(catalog_topologies()["cloverstack"].ramps)})
    names = dict(zip(catalog_topologies()["cloverstack"].ramps, renamed.ramps))
    assert [(p.connector, p.loop) for p in round_loops(renamed)] == \
        [(names["oA1"], names["lB1"]), (names["oA2"], names["lB2"])]


def test_the_sampled_array_keeps_every_connector_wider_and_covers_the_rest():
    topo = catalog_topologies()["cloverstack"]
    profile = default_profile()
    s = sample_topology(topo, profile, t=2, seed=11, fixed=fixed_features(topo),
                        extra=forbidden_features(topo, profile))
    radius = {}
    for r in s.feature_rows():
        radius[r["sample"], r["element"]] = r["radius_m"]
    for p in round_loops(topo):
        held = {(radius[k, p.connector], radius[k, p.loop]) for k in range(s.coverage.rows)}
        assert all(p.allows(a, b) for a, b in held)
        # every allowed pair of the domain's finite radii is in some row (2-way coverage)
        finite = [v for v in profile.domain(Kind.RAMP)[Feature.RADIUS_M] if math.isfinite(v)]
        assert held == {(a, b) for a in finite for b in finite if p.allows(a, b)}
    # connector 30 and loop 280 are in no valid row (implied): required = extendable
    cons = Constraints(s.model.levels, s.model.forbidden)
    covered, total = independent_coverage(s.array.rows, s.model.levels, 2,
                                          cells(s.model.forbidden), cons.extendable)
    assert covered == total == s.coverage.tuples_total


def test_a_connector_reaching_its_loops_roads_through_stubs_must_be_wider_than_it():
    """o joins B2 and A1, the roads the loop k joins, the other way round, each through a
    stub (o leaves B2 through s, k leaves A1 through e and c), and shares no road with k.
    The layout fits o round k (chains.Movements.is_outer_connector); sampling must keep
    o wider than k by the same rule, else o is drawn tighter than the loop it goes round."""
    topo = _collector_round()
    assert ("o", "k") in [(p.connector, p.loop) for p in round_loops(topo)]
    profile = default_profile()
    model = feature_model(topo, profile, forbidden_features(topo, profile))
    allowed = _pair_allowed(model, "o", "k")
    assert allowed[(60.0, 40.0)] and not allowed[(40.0, 40.0)] and not allowed[(40.0, 60.0)]


@pytest.mark.skipif(not COLUMBUS.is_file(), reason=f"no real OSM extract at {COLUMBUS}")
def test_columbus_connector_round_its_loop_through_stubs_is_sampled_wider():
    """Columbus: r11 (I-70 West through the stub r1 to I-270 North) goes round the loop r6
    (I-270 North through r8 and r13 to I-70 West); the layout fits it round r6, so every
    sampled row has r11 wider than r6 by the room between them (one lane each: 7 m)."""
    from flyover.osm import read_osm_topologies  # noqa: PLC0415

    topo = next(t for t in read_osm_topologies(COLUMBUS) if t.ramps)
    pair = next(p for p in round_loops(topo) if (p.connector, p.loop) == ("r11", "r6"))
    assert pair.margin_m == 7.0
    profile = default_profile()
    s = sample_topology(topo, profile, t=2, seed=11, fixed=fixed_features(topo),
                        extra=forbidden_features(topo, profile))
    radius = {(r["sample"], r["element"]): r["radius_m"] for r in s.feature_rows()}
    held = {(radius[k, "r11"], radius[k, "r6"]) for k in range(s.coverage.rows)}
    assert all(pair.allows(a, b) for a, b in held)
    assert any(b >= 40.0 for _, b in held)  # the loop still takes wide radii
    # r2 goes round the loop r5, which joins the collector road r13 (Movements.collects)
    r2 = next(p for p in round_loops(topo) if (p.connector, p.loop) == ("r2", "r5"))
    assert all(r2.allows(radius[k, "r2"], radius[k, "r5"]) for k in range(s.coverage.rows))


def test_fixed_features_lay_out_the_roads_once(monkeypatch, cloverleaf_cd):
    """``fixed_features`` reads the level ramps and the straight connectors off one road
    layout: each used to lay the roads out (and build their ``Movements``) on its own."""
    import flyover.geometry.feasibility as feasibility  # noqa: PLC0415

    calls = []
    real = feasibility.layout_roads

    def counted(*args, **kwargs):
        calls.append(args[0].name)
        return real(*args, **kwargs)

    monkeypatch.setattr(feasibility, "layout_roads", counted)
    for name, topo in catalog_topologies().items():
        calls.clear()
        fixed = fixed_features(topo)
        assert len(calls) == 1, name
        assert fixed == {**{(r, Feature.SLOPE_PCT): 0.0 for r in level_ramps(topo)},
                         **{(r, Feature.RADIUS_M): math.inf
                            for r in feasibility.straight_connectors(topo)}}
