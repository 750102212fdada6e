"""The plugin's rows on a real catalog interchange, its config, its commands and the HBEFA check."""

from __future__ import annotations

import csv
import math

import pytest

from flyover.errors import ConfigError
from flyover.geometry.model import (
    Attachment, BezierPiece, ElevationPoly, InterchangeGeometry, RampGeometry,
)
from flyover_truck_fuel.cli import main as cli_main
from flyover_truck_fuel.params import settings
from flyover_truck_fuel.plugin import COLUMNS, TruckFuelPlugin


def test_rows_of_a_catalog_interchange(j1_geometry):
    plugin = TruckFuelPlugin()
    rows = plugin.evaluate(j1_geometry, {})
    assert [r["ramp"] for r in rows] == [r.id for r in j1_geometry.ramps]
    table = __import__("pyarrow").Table.from_pylist(rows, schema=plugin.schema())
    assert table.column_names == list(COLUMNS)
    for row, ramp in zip(rows, j1_geometry.ramps):
        assert row["completed"] and row["reason"] == ""
        assert row["class_id"] == "c0000000j1x" and row["sample"] == 0
        assert row["length_m"] == pytest.approx(ramp.length_m, rel=0.05)
        assert row["direction"] == ("up" if row["climb_m"] > 0.5 else
                                    "down" if row["climb_m"] < -0.5 else "level")
        assert row["fuel_ml_per_km"] == pytest.approx(row["fuel_ml"] / row["length_m"] * 1000)
        assert row["duration_s"] == pytest.approx(row["length_m"] / row["mean_speed_mps"])
        assert row["max_lateral_error_m"] <= 0.3
        assert row["target_speed_mps"] == 10.0
    ups = [r["fuel_ml_per_km"] for r in rows if r["direction"] == "up"]
    downs = [r["fuel_ml_per_km"] for r in rows if r["direction"] == "down"]
    assert ups and min(ups) > 330.0      # more than on the flat (by hand: ~330 ml/km)
    assert all(d < min(ups) for d in downs)


def test_a_ramp_the_truck_cannot_drive_is_a_row_not_a_crash():
    k = 0.5522847498 * 8.0  # a quarter circle of 8 m: lane centre 10 m, tighter than 11 m
    piece = BezierPiece(((0.0, 0.0), (k, 0.0), (8.0, 8.0 - k), (8.0, 8.0)), 12.6)
    ramp = RampGeometry("tight", 1, (piece,), (ElevationPoly(0.0, 0.0, 0.0, 0.0, 0.0),),
                        Attachment("nowhere", "Out-R", 0.0, 0.0, 0.0, 0.0),
                        Attachment("nowhere", "In-R", 0.0, 0.0, 1.57, 0.0),
                        8.0, 0.0, 10.0, 0.0, 12.6)
    g = InterchangeGeometry("c0000000000", 3, 1, ramps=(ramp,))
    (row,) = TruckFuelPlugin().evaluate(g, {})
    assert row["completed"] is False and row["reason"]
    assert row["min_radius_m"] == pytest.approx(10.0, rel=0.02)


def test_config_errors_name_the_key():
    with pytest.raises(ConfigError) as err:
        settings({"truck": {"mass_kg": -1}})
    assert err.value.element == "plugins.truck_fuel.truck.mass_kg"
    with pytest.raises(ConfigError, match="bogus"):
        settings({"engine": {"bogus": 1}})


def test_grid_command_writes_table_and_heatmap(tmp_path):
    status = cli_main(["grid", "--out", str(tmp_path), "--radii", "40", "100",
                       "--slopes", "2"])
    assert status == 0
    rows = list(csv.DictReader(open(tmp_path / "fuel_grid.csv")))
    assert len(rows) == 4 and (tmp_path / "fuel_grid.png").stat().st_size > 10_000
    up = {float(r["radius_m"]): float(r["fuel_ml"]) for r in rows if r["direction"] == "up"}
    down = {float(r["radius_m"]): float(r["fuel_ml"]) for r in rows if r["direction"] == "down"}
    assert up[100.0] > up[40.0]                 # a larger radius is a longer ramp
    assert all(down[r] < up[r] for r in up)


@pytest.mark.integration
def test_hbefa4_cross_check_on_flat_and_grades(st):
    from flyover_truck_fuel.hbefa import crosscheck

    checks = {c.grade_pct: c for c in crosscheck(st, length_m=400.0, grades_pct=(0.0, 4.0, -4.0))}
    # SUMO's HBEFA4 40 t articulated truck at a steady 10 m/s (by hand: 574, 1114, 34 ml/km)
    assert checks[0.0].hbefa_ml_per_km == pytest.approx(574, rel=0.03)
    assert checks[4.0].hbefa_ml_per_km == pytest.approx(1114, rel=0.03)
    assert checks[-4.0].hbefa_ml_per_km == pytest.approx(34, abs=5)
    # ours: within 25 % uphill; below on the flat and zero downhill (README explains why)
    assert 1.0 < checks[4.0].ratio < 1.25
    assert 0.5 < checks[0.0].ratio < 0.7
    assert checks[-4.0].ours_ml_per_km == 0.0 and not math.isnan(checks[-4.0].ratio)


def test_interchange_command_prints_one_row_per_ramp(j1_geometry, tmp_path, capsys):
    from flyover.geometry.model import write_geometry

    path = tmp_path / "geometry.json"
    write_geometry(j1_geometry, path)
    assert cli_main(["interchange", str(path)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].split()[:2] == ["ramp", "direction"]
    assert [ln.split()[0] for ln in lines[1:]] == [r.id for r in j1_geometry.ramps]


def test_a_malformed_ramp_is_a_row_with_the_reason(j1_geometry):
    from dataclasses import replace

    broken = replace(j1_geometry.ramps[0], elevation=())
    g = replace(j1_geometry, ramps=(broken, *j1_geometry.ramps[1:2]))
    rows = TruckFuelPlugin().evaluate(g, {})
    assert rows[0]["completed"] is False and rows[0]["reason"].startswith("no route")
    assert rows[0]["direction"] is None
    assert rows[1]["completed"] is True
