"""Coverage-guided sampling: orthogonal arrays, covering arrays, constraints, profiles, tables, CLI.

Every array the tests make is checked by :func:`independent_coverage`, which
shares no code with the generator: plain itertools and sets.
"""

from __future__ import annotations

import itertools
import json
import math

import numpy as np
import pyarrow.parquet as pq
import pytest

from flyover.cli import main
from flyover.errors import ConfigError
from flyover.sampling import Forbidden, SearchBudget, UnsatisfiableError, covering_array
from flyover.sampling.galois import galois_field, orthogonal_array
from flyover.sampling.model import (
    DEFAULT_PROFILE,
    Feature,
    default_profile,
    feature_model,
    profile_from_dict,
)
from flyover.sampling.sample import FEATURES_SCHEMA, sample_topology, sampling_seed
from flyover.sampling.settings import settings_from_config
from flyover.sampling.tuples import TupleSpace, measure_coverage
from flyover.topology.catalog import catalog_topologies
from flyover.topology.model import Kind

# -- the independent checker -------------------------------------------------------------


def _holds(assign: dict[int, int], forbidden) -> bool:
    """Whether the (partial) assignment holds some forbidden combination entirely."""
    return any(all(p in assign and assign[p] in vs for p, vs in f) for f in forbidden)


def independent_coverage(rows, levels, t, forbidden=(), required=None) -> tuple[int, int]:
    """(covered, total) required t-tuples, by brute force.

    ``forbidden``: lists of ``(parameter, set of values)``. A tuple is required
    when ``required(assign)`` says so, by default when it holds no forbidden
    combination (exact when no combination forces a value, as in the models
    below; the implied-constraint test passes ``required`` by enumeration).
    Rows that hold a forbidden combination cover nothing.
    """
    rows = [tuple(int(v) for v in r) for r in rows]
    valid = [r for r in rows if not _holds(dict(enumerate(r)), forbidden)]
    required = required or (lambda a: not _holds(a, forbidden))
    covered = total = 0
    for cols in itertools.combinations(range(len(levels)), min(t, len(levels))):
        seen = {tuple(r[c] for c in cols) for r in valid}
        for vals in itertools.product(*(range(levels[c]) for c in cols)):
            if required(dict(zip(cols, vals))):
                total += 1
                covered += vals in seen
    return covered, total


def cells(forbidden: list[Forbidden]):
    return [[(p, set(vs)) for p, vs in f.cells] for f in forbidden]


def paper_levels(roads: int, ramps: int) -> list[int]:
    return [3] * roads + [8, 5] * ramps


# -- finite fields and orthogonal arrays -------------------------------------------------


@pytest.mark.parametrize("q", [2, 3, 4, 5, 7, 8, 9])
def test_galois_field_tables_obey_the_field_laws(q):
    gf = galois_field(q)
    a, b, c = np.meshgrid(range(q), range(q), range(q), indexing="ij")
    assert (gf.mul[a, gf.add[b, c]] == gf.add[gf.mul[a, b], gf.mul[a, c]]).all()
    assert all(sorted(gf.mul[x, 1:]) == list(range(1, q)) for x in range(1, q))
    assert all(sorted(gf.add[x]) == list(range(q)) for x in range(q))


@pytest.mark.parametrize("q,t", [(2, 2), (3, 3), (4, 2), (5, 3), (7, 2), (8, 2), (8, 3), (9, 2)])
def test_bush_orthogonal_array_holds_every_t_tuple_exactly_once(q, t):
    oa = orthogonal_array(q, t)
    assert oa.shape == (q ** t, q + 1)
    for cols in itertools.combinations(range(q + 1), t):
        assert len({tuple(r) for r in oa[:, cols]}) == q ** t


def test_field_of_non_prime_power_order_is_refused():
    with pytest.raises(ValueError, match="not a prime power"):
        galois_field(12)


# -- covering arrays ---------------------------------------------------------------------


@pytest.mark.parametrize("roads,ramps", [(3, 3), (4, 1), (4, 4), (4, 6), (4, 8), (3, 8), (6, 8)])
def test_pairwise_arrays_reach_the_lower_bound_up_to_8_ramps(roads, ramps):
    levels = paper_levels(roads, ramps)
    ca = covering_array(levels, 2, seed=7)
    covered, total = independent_coverage(ca.rows, levels, 2)
    assert covered == total == ca.coverage.tuples_total
    bound = 64 if ramps > 1 else 40
    assert ca.coverage.lower_bound == bound
    assert len(ca.rows) == bound


def test_larger_class_needs_at_most_four_fifths_of_picts_rows():
    levels = paper_levels(4, 12)
    ca = covering_array(levels, 2, seed=3)
    assert independent_coverage(ca.rows, levels, 2)[0] == ca.coverage.tuples_total
    assert len(ca.rows) <= 0.8 * 126  # PICT: 126 rows


def test_strength_3_covers_every_triple_within_picts_rows():
    levels = paper_levels(4, 4)
    ca = covering_array(levels, 3, seed=11)
    covered, total = independent_coverage(ca.rows, levels, 3)
    assert covered == total == ca.coverage.tuples_total
    assert ca.coverage.lower_bound == 512
    assert len(ca.rows) <= 691  # PICT: 691 rows


def test_strength_3_works_for_8_ramps():
    levels = paper_levels(4, 8)
    ca = covering_array(levels, 3, seed=2, budget=SearchBudget(work=100_000_000))
    covered, total = independent_coverage(ca.rows, levels, 3)
    assert covered == total == ca.coverage.tuples_total
    assert 512 <= len(ca.rows) < 1140  # PICT: 1140 rows


def test_removed_row_is_detected_as_lost_coverage():
    levels = paper_levels(4, 4)
    ca = covering_array(levels, 2, seed=1)
    fewer = np.delete(ca.rows, 17, axis=0)
    covered, total = independent_coverage(fewer, levels, 2)
    assert covered < total
    measured = measure_coverage(fewer, TupleSpace(levels, 2))
    assert not measured.complete and measured.tuples_covered == covered


def test_values_stay_in_their_domains_and_all_appear():
    levels = paper_levels(3, 5)
    rows = covering_array(levels, 2, seed=2).rows
    for p, n in enumerate(levels):
        assert set(rows[:, p]) == set(range(n))


def test_same_seed_gives_the_same_array():
    levels = paper_levels(4, 12)
    budget = SearchBudget(work=20_000_000)
    a = covering_array(levels, 2, seed=5, budget=budget).rows
    b = covering_array(levels, 2, seed=5, budget=budget).rows
    assert np.array_equal(a, b)


def test_forbidden_combinations_are_never_written_and_only_allowed_tuples_count():
    roads, ramps = 4, 5
    levels = paper_levels(roads, ramps)
    radius, slope = (lambda j: roads + 2 * j), (lambda j: roads + 2 * j + 1)
    forbidden = [Forbidden.of({radius(j): [6, 7], slope(j): [3, 4]}) for j in range(ramps)]
    forbidden += [Forbidden.of({0: [2], radius(0): [0]}), Forbidden.of({radius(1): [7], radius(2): [7]})]
    for t in (2, 3):
        ca = covering_array(levels, t, forbidden=forbidden, seed=4)
        assert not any(_holds(dict(enumerate(r)), cells(forbidden)) for r in ca.rows)
        covered, total = independent_coverage(ca.rows, levels, t, cells(forbidden))
        assert covered == total == ca.coverage.tuples_total
        assert total < TupleSpace(levels, t).n_tuples


def test_implied_constraints_leave_tuples_no_valid_row_can_hold():
    levels = [2, 2, 3, 3]
    forbidden = [Forbidden.of({0: [0], 1: [0]}), Forbidden.of({0: [0], 1: [1]}),
                 Forbidden.of({2: [0], 3: [0, 1]})]
    valid = [r for r in itertools.product(*map(range, levels))
             if not _holds(dict(enumerate(r)), cells(forbidden))]

    def required(assign):
        return any(all(r[p] == v for p, v in assign.items()) for r in valid)

    ca = covering_array(levels, 2, forbidden=forbidden, seed=0)
    assert set(ca.rows[:, 0]) == {1}  # parameter 0 can never be 0
    covered, total = independent_coverage(ca.rows, levels, 2, cells(forbidden), required)
    assert covered == total == ca.coverage.tuples_total


def test_constraints_that_forbid_everything_are_refused():
    with pytest.raises(UnsatisfiableError):
        covering_array([2, 2], 2, forbidden=[Forbidden.of({0: [0, 1]})])


# -- profiles and the feature model ------------------------------------------------------


def test_default_profile_is_the_papers_domains():
    p = default_profile()
    assert p.domain(Kind.ROAD) == {Feature.LANES: (3.0, 4.0, 5.0)}
    ramp = p.domain(Kind.RAMP)
    assert ramp[Feature.RADIUS_M] == (math.inf, 280, 210, 150, 100, 60, 40, 30)
    assert ramp[Feature.SLOPE_PCT] == (1, 2, 3, 4, 5)


def test_a_profile_added_in_config_is_used_without_code():
    config = {"sampling": {"profile": "gentle", "profiles": {"gentle": {
        "road": {"lanes": [2, 3]}, "ramp": {"radius_m": [400, 250, 120], "slope_pct": [2, 4]},
        "forbid": [{"elements": [{"kind": "ramp", "radius_m": 120, "slope_pct": 4}]}]}}}}
    settings = settings_from_config(config)
    j1 = catalog_topologies()["j1"]
    model = feature_model(j1, settings.profile)
    assert model.levels == (2, 2, 2, 2, 3, 2, 3, 2, 3, 2, 3, 2)
    assert len(model.forbidden) == 4  # one per ramp
    s = sample_topology(j1, settings.profile, t=2, seed=1)
    assert {r["radius_m"] for r in s.feature_rows() if r["kind"] == "ramp"} == {400.0, 250.0, 120.0}
    assert not any(r["radius_m"] == 120 and r["slope_pct"] == 4 for r in s.feature_rows())


def test_cross_element_rule_applies_to_connected_pairs_only():
    doc = {**DEFAULT_PROFILE, "forbid": [
        {"where": "connected", "elements": [{"kind": "road", "lanes": 5}, {"kind": "ramp", "radius_m": 30}]}]}
    j1 = catalog_topologies()["j1"]
    model = feature_model(j1, profile_from_dict("x", doc))
    pairs = {(model.parameters[f.params[0]].element, model.parameters[f.params[1]].element)
             for f in model.forbidden}
    assert pairs == {(u, v) for u, v in j1.graph.edges if u.startswith("R") and v.startswith("r")}
    s = sample_topology(j1, model.profile, seed=2)
    lanes = {(r["sample"], r["element"]): r["lanes"] for r in s.feature_rows()}
    radius = {(r["sample"], r["element"]): r["radius_m"] for r in s.feature_rows()}
    for u, v in pairs:
        assert not any(lanes[i, u] == 5 and radius[i, v] == 30 for i in range(s.coverage.rows))


@pytest.mark.parametrize("doc,element", [
    ({"road": {"width": [3]}}, "sampling.profiles.bad.road.width"),
    ({"ramp": {"radius_m": [30, 30]}}, "sampling.profiles.bad.ramp.radius_m"),
    ({**DEFAULT_PROFILE, "forbid": [{"elements": [{"kind": "ramp", "radius_m": 35}]}]},
     "sampling.profiles.bad.forbid[0].elements[0].radius_m"),
    ({**DEFAULT_PROFILE, "forbid": [{"elements": [{"kind": "road", "slope_pct": 1}]}]},
     "sampling.profiles.bad.forbid[0].elements[0].slope_pct"),
])
def test_bad_profiles_name_the_key_at_fault(doc, element):
    with pytest.raises(ConfigError) as err:
        profile_from_dict("bad", doc, source="config.yaml")
    assert err.value.element == element and err.value.source == "config.yaml"


def test_unknown_profile_is_a_config_error():
    with pytest.raises(ConfigError, match="unknown profile 'nope'"):
        settings_from_config({"sampling": {"profiles": {}}}, profile="nope")


# -- a class's feature sets --------------------------------------------------------------


def test_feature_rows_are_one_per_sample_and_element_with_the_right_columns(tmp_path):
    from flyover.topology.tables import write_parquet

    j1 = catalog_topologies()["j1"]
    s = sample_topology(j1, default_profile(), t=2, seed=20231024)
    rows = s.feature_rows()
    assert len(rows) == 64 * 8 and {r["sample"] for r in rows} == set(range(64))
    roads = [r for r in rows if r["kind"] == "road"]
    ramps = [r for r in rows if r["kind"] == "ramp"]
    assert all(r["lanes"] in (3, 4, 5) and r["radius_m"] is None for r in roads)
    assert all(r["lanes"] is None and r["slope_pct"] in (1, 2, 3, 4, 5) for r in ramps)
    assert any(math.isinf(r["radius_m"]) for r in ramps)
    path = tmp_path / "f.parquet"
    write_parquet(rows, FEATURES_SCHEMA, path)
    assert pq.read_table(path).column_names == ["class_id", "sample", "element", "kind", "lanes",
                                                "radius_m", "slope_pct"]
    assert s.coverage_row() == {"class_id": s.class_id, "t": 2, "n_params": 12, "rows": 64,
                                "tuples_total": 1852, "tuples_covered": 1852, "lower_bound": 64}


def test_class_seed_depends_on_master_seed_and_class():
    assert sampling_seed(1, "c0000000000") == sampling_seed(1, "c0000000000")
    assert sampling_seed(1, "c0000000000") != sampling_seed(2, "c0000000000")
    assert sampling_seed(1, "c0000000000") != sampling_seed(1, "c0000000001")


# -- command line ------------------------------------------------------------------------


def test_cli_sample_prints_rows_and_coverage_for_a_catalog_design(capsys):
    assert main(["sample", "j1", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    # inf is no radius of J1's ramps (they all turn: flyover.geometry.feasibility), so
    # 7 radii x 7 radii bound the array from below; the pairs of all other values are covered
    assert out["rows"] == 51 and out["lower_bound"] == 49
    assert out["tuples_covered"] == out["tuples_total"] == 1634
    assert out["t"] == 2 and out["profile"] == "china"


def test_cli_sample_strength_3_on_a_topology_file_writes_features(capsys, tmp_path):
    from flyover.topology.catalog import catalog_dir

    out_file = tmp_path / "features.parquet"
    assert main(["sample", str(catalog_dir() / "trumpet.yaml"), "--t", "3",
                 "--features", str(out_file)]) == 0
    text = capsys.readouterr().out
    assert "t=3" in text and "tuples covered (100.0 %)" in text
    table = pq.read_table(out_file)
    assert table.num_rows > 0 and set(table.column("kind").to_pylist()) == {"road", "ramp"}


def test_cli_sample_rejects_an_unknown_argument(capsys):
    assert main(["sample", "no_such_design"]) == 1
    assert "no_such_design" in capsys.readouterr().err


def test_rule_naming_one_element_applies_to_that_element_only():
    from flyover.sampling.model import ElementCondition, ForbidRule

    j1 = catalog_topologies()["j1"]
    rule = ForbidRule((ElementCondition(Kind.RAMP, ((Feature.RADIUS_M, frozenset({30.0})),
                                                    (Feature.SLOPE_PCT, frozenset({5.0}))), "r3"),))
    model = feature_model(j1, default_profile(), extra=[rule])
    assert [{model.parameters[p].element for p in f.params} for f in model.forbidden] == [{"r3"}]
    s = sample_topology(j1, default_profile(), seed=3, extra=[rule])
    assert not any(r["element"] == "r3" and r["radius_m"] == 30 and r["slope_pct"] == 5
                   for r in s.feature_rows())
    assert s.coverage.complete


def test_profile_rule_may_name_an_element():
    doc = {**DEFAULT_PROFILE, "forbid": [{"elements": [{"kind": "ramp", "element": "r1", "radius_m": 30}]}]}
    model = feature_model(catalog_topologies()["j1"], profile_from_dict("x", doc))
    assert len(model.forbidden) == 1 and model.parameters[model.forbidden[0].params[0]].element == "r1"
