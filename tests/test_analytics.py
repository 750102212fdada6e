"""DuckDB analytics: views over the Parquet where it lies, named queries, ``flyover query``."""

from __future__ import annotations

import csv
import io
import json

import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from flyover.analytics import NAMED_QUERIES, AnalyticsError, MissingTableError, query
from flyover.cli import main as flyover_main

FUEL = [  # class_id, sample, ramp, direction, min_radius_m, max_slope_pct, fuel_ml_per_km, completed
    ("c0000000001", 0, "r1", "up", 31.0, 3.9, 1400.0, True),
    ("c0000000001", 0, "r2", "down", 61.0, 2.1, 0.0, True),
    ("c0000000001", 1, "r1", "up", 29.0, 4.0, 1600.0, True),
    ("c0000000002", 0, "a", "up", 150.0, 1.0, 600.0, True),
    ("c0000000002", 0, "b", "level", 210.0, 0.0, 330.0, False),
]


@pytest.fixture
def results(tmp_path):
    res = tmp_path / "results"
    res.mkdir()
    pq.write_table(pa.table({
        "city": ["catalog", "catalog", "x"], "interchange": ["j1", "trumpet", "t2"],
        "class_id": ["c0000000001", "c0000000002", "c0000000002"],
        "class_name": ["j1", "trumpet", "trumpet"]}), res / "classes.parquet")
    pq.write_table(pa.table({
        "class_id": [r[0] for r in FUEL], "sample": [r[1] for r in FUEL],
        "ramp": [r[2] for r in FUEL],
        "target_radius_m": [30.0, 60.0, 30.0, 150.0, float("inf")],
        "target_slope_pct": [4.0, 2.0, 4.0, 1.0, 0.0]}), res / "geometry.parquet")
    for c, s in {(r[0], r[1]) for r in FUEL}:
        rows = [r for r in FUEL if r[:2] == (c, s)]
        part = res / "fuel" / f"class_id={c}" / f"sample={s}"
        part.mkdir(parents=True)
        pq.write_table(pa.table({
            "ramp": [r[2] for r in rows], "direction": [r[3] for r in rows],
            "length_m": [1000.0] * len(rows), "min_radius_m": [r[4] for r in rows],
            "max_slope_pct": [r[5] for r in rows], "fuel_ml_per_km": [r[6] for r in rows],
            "fuel_ml": [r[6] for r in rows], "mean_speed_mps": [10.0] * len(rows),
            "max_lateral_error_m": [0.01] * len(rows),
            "max_lateral_accel_mps2": [1.0] * len(rows),
            "completed": [r[7] for r in rows], "reason": [""] * len(rows)}),
            part / "part-0.parquet")
    return res


def test_fuel_view_reads_hive_partitions_as_columns(results):
    t = query("SELECT class_id, sample, count(*) AS n FROM fuel GROUP BY ALL ORDER BY ALL",
              results)
    assert t.to_pylist() == [
        {"class_id": "c0000000001", "sample": 0, "n": 2},
        {"class_id": "c0000000001", "sample": 1, "n": 1},
        {"class_id": "c0000000002", "sample": 0, "n": 2}]


def test_a_missing_table_names_the_workflow_target_that_makes_it(results):
    with pytest.raises(MissingTableError) as err:
        query("SELECT * FROM throughput", results)
    assert err.value.table == "throughput" and err.value.target == "throughput"
    assert "./dev run throughput" in str(err.value)


def test_bad_sql_is_an_analytics_error(results):
    with pytest.raises(AnalyticsError, match="(?i)parser|syntax"):
        query("SELEC 1", results)


def test_fuel_by_class_joins_class_names_and_takes_completed_rows(results):
    rows = query(NAMED_QUERIES["fuel-by-class"].sql, results).to_pylist()
    by = {(r["class_name"], r["direction"]): r for r in rows}
    assert by[("j1", "up")]["ramps"] == 2 and by[("j1", "up")]["median_ml_per_km"] == 1500.0
    assert by[("trumpet", "level")]["completed_share"] == 0.0
    assert by[("trumpet", "level")]["median_ml_per_km"] is None  # not completed: no figure


def test_fuel_totals_sum_litres_per_class_over_completed_ramps(results):
    rows = {r["class_name"]: r for r in
            query(NAMED_QUERIES["fuel-totals"].sql, results).to_pylist()}
    assert rows["j1"]["ramps"] == 3 and rows["j1"]["litres"] == 3.0   # 1400 + 0 + 1600 ml
    assert rows["j1"]["ml_per_km"] == 1000.0
    assert rows["trumpet"]["ramps"] == 1                               # one not completed


def test_fuel_grid_groups_by_the_ramps_target_radius_and_slope(results):
    rows = query(NAMED_QUERIES["fuel-grid"].sql, results).to_pylist()
    cells = {(r["radius_m"], r["slope_pct"], r["direction"]): r["mean_ml_per_km"]
             for r in rows}
    assert cells == {(30, 4, "up"): 1500.0, (60, 2, "down"): 0.0, (150, 1, "up"): 600.0}


@pytest.mark.parametrize("fmt", ["csv", "json", "table"])
def test_query_command_formats(results, capsys, fmt):
    status = flyover_main(["query", "--results", str(results), "--format", fmt,
                           "SELECT ramp, fuel_ml_per_km FROM fuel WHERE class_id = "
                           "'c0000000002' ORDER BY ramp"])
    out = capsys.readouterr().out
    assert status == 0
    if fmt == "csv":
        assert list(csv.DictReader(io.StringIO(out))) == [
            {"ramp": "a", "fuel_ml_per_km": "600"}, {"ramp": "b", "fuel_ml_per_km": "330"}]
    elif fmt == "json":
        assert json.loads(out) == [{"ramp": "a", "fuel_ml_per_km": 600.0},
                                   {"ramp": "b", "fuel_ml_per_km": 330.0}]
    else:
        assert out.splitlines()[0].split() == ["ramp", "fuel_ml_per_km"]
        assert out.splitlines()[2].split() == ["a", "600"]


def test_query_command_lists_named_queries_and_reports_missing_tables(results, capsys):
    assert flyover_main(["query", "--list"]) == 0
    out = capsys.readouterr().out
    for name in ("fuel-by-class", "fuel-grid", "throughput-by-class"):
        assert name in out
    assert flyover_main(["query", "--results", str(results), "--named",
                         "throughput-by-class"]) == 1
    assert "./dev run throughput" in capsys.readouterr().err
