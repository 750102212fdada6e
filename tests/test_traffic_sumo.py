"""Throughput experiment on real SUMO runs (libsumo in-process) on small interchanges."""

from __future__ import annotations

import json
from dataclasses import replace

import pyarrow.parquet as pq
import pytest

from flyover.cli import main
from flyover.geometry.model import write_geometry
from flyover.opendrive.samples import sample_geometry
from flyover.opendrive.writer import write_xodr
from flyover.sumo.netconvert import run_netconvert
from flyover.traffic.batch import THROUGHPUT_SCHEMA, aggregate_tables, run_class, run_interchange
from flyover.traffic.settings import ThroughputSettings

pytestmark = pytest.mark.integration


def _interchange(folder, geometry, net_geometry=None):
    """geometry.json, interchange.xodr and interchange.net.xml of ``geometry`` in ``folder``
    (the network made from ``net_geometry`` if given)."""
    folder.mkdir(parents=True, exist_ok=True)
    write_geometry(geometry, folder / "geometry.json")
    write_xodr(net_geometry or geometry, folder / "interchange.xodr")
    assert run_netconvert(folder / "interchange.xodr", folder / "interchange.net.xml").ok
    return folder / "interchange.net.xml"


@pytest.fixture(scope="module")
def t_net(tmp_path_factory):
    """The two-ramp T sample: C1 ends into r1 (to A1) with r2 leaving it for A2."""
    return _interchange(tmp_path_factory.mktemp("t") / "ct" / "0", sample_geometry("t"))


def test_below_capacity_throughput_is_the_sum_of_the_flows(t_net):
    # 4 movements (C1->A1, C1->A2, A1->A1, A2->A2) x 450 veh/h = 1800 veh/h, far below the
    # capacity of two-lane carriageways and one-lane ramps (HCM ~2000 pc/h/lane)
    s = ThroughputSettings(densities=(450.0,), duration_s=1200.0)
    rows, series = run_interchange(t_net, s, class_id="ct", sample=0)
    (r,) = rows
    assert r["ok"] and r["movements"] == 4 and r["demand_veh_h"] == 1800.0
    assert r["throughput_veh_h"] == pytest.approx(1800.0, rel=0.12)
    assert r["entering_veh_h"] == pytest.approx(r["throughput_veh_h"], rel=0.05)
    assert r["balanced"] and r["stable_from_s"] <= 300.0
    assert r["not_inserted"] <= 2 and r["teleports"] == 0 and r["collisions"] == 0
    assert not r["flagged"]
    # arrivals: Poisson with mean 1800 / h over 1200 s, all but the last few in the network
    assert abs(r["entered"] - 600) < 4 * 600 ** 0.5
    assert 0 <= r["entered"] - r["left"] == r["running_end"] < 40
    assert len(series) == 60 and series[-1]["in_network"] == r["running_end"]


def test_same_seed_gives_the_same_table_bytes(t_net, tmp_path):
    s = ThroughputSettings(densities=(900.0,), duration_s=400.0, interval_s=20.0,
                           min_stable_s=100.0)
    out = []
    for k in range(2):
        run_class([(0, t_net)], "ct", s, tmp_path / f"{k}.parquet", tmp_path / f"{k}/series.parquet")
        out.append(((tmp_path / f"{k}.parquet").read_bytes(),
                    (tmp_path / f"{k}/series.parquet").read_bytes()))
    assert out[0] == out[1]
    run_class([(0, t_net)], "ct", replace(s, seed=s.seed + 1), tmp_path / "x.parquet",
              tmp_path / "x/series.parquet")
    assert (tmp_path / "x/series.parquet").read_bytes() != out[0][1]


def test_a_movement_without_a_route_is_a_failed_row(tmp_path):
    g = sample_geometry("t")
    no_r2 = replace(g, ramps=g.ramps[:1])  # the network lacks the ramp C1 -> A2
    net = _interchange(tmp_path / "ct" / "0", g, net_geometry=no_r2)
    s = ThroughputSettings(densities=(450.0, 900.0), duration_s=200.0)
    rows, series = run_interchange(net, s, class_id="ct", sample=0)
    assert [r["ok"] for r in rows] == [False, False] and series == []
    assert "C1->A2" in rows[0]["reason"] and "1 of 4 movements have no route" in rows[0]["reason"]


def test_a_missing_or_broken_network_is_a_row_and_the_class_goes_on(t_net, tmp_path):
    bad = tmp_path / "cx" / "1" / "interchange.net.xml"
    bad.parent.mkdir(parents=True)
    bad.write_text("<net><edge id='x'")
    s = ThroughputSettings(densities=(450.0,), duration_s=200.0, interval_s=20.0)
    rows = run_class([(0, t_net), (1, bad), (2, tmp_path / "none.net.xml")], "ct", s,
                     tmp_path / "ct.parquet", tmp_path / "ct" / "series.parquet")
    assert [r["ok"] for r in rows] == [True, False, False]
    assert "cannot read SUMO network" in rows[1]["reason"]
    assert "no SUMO network" in rows[2]["reason"]
    table = pq.read_table(tmp_path / "ct.parquet")
    assert table.schema.names[:10] == ["class_id", "sample", "density_veh_h", "throughput_veh_h",
                                       "entered", "left", "not_inserted", "teleports",
                                       "collisions", "stable_from_s"]
    tp, st, _ = aggregate_tables([tmp_path / "ct.parquet"], [tmp_path / "ct" / "series.parquet"],
                                 tmp_path / "throughput.parquet",
                                 tmp_path / "throughput_stats.parquet")
    assert len(tp) == 3 and pq.read_table(tmp_path / "throughput.parquet").schema.equals(
        THROUGHPUT_SCHEMA)
    assert any(r["scope"] == "inter_class_std" for r in st)


def test_cli_prints_throughput_and_counts(t_net, capsys):
    code = main(["throughput", str(t_net), "--density", "450", "--duration", "300", "--json"])
    rows = json.loads(capsys.readouterr().out)
    assert code == 0 and len(rows) == 1
    assert rows[0]["movements"] == 4 and rows[0]["teleports"] == 0
    assert set(rows[0]) >= {"throughput_veh_h", "stable_from_s", "not_inserted", "collisions"}
    code = main(["throughput", str(t_net), "--density", "450", "--duration", "300"])
    out = capsys.readouterr().out
    assert "450 veh/h x 4 movements (demand 1800 veh/h): throughput" in out


def _aux_lengths(net_path, road_lanes):
    """Lengths of the stretches (runs of consecutive edges of one OpenDRIVE road) on which
    the SUMO network has more lanes than the road's own ``road_lanes``."""
    import sumolib

    from flyover.sumo.routes import road_edges

    runs = []
    for edges in road_edges(sumolib.net.readNet(str(net_path))).values():
        run = 0.0
        for e in edges:
            if e.getLaneNumber() > road_lanes:
                run += e.getLength()
            elif run:
                runs.append(run)
                run = 0.0
        if run:
            runs.append(run)
    return sorted(runs)


def test_auxiliary_lanes_leave_room_to_change_lanes(tmp_path):
    # the loop sample: A1 (2 lanes) has a deceleration lane before r1 leaves it, B1 an
    # acceleration lane after r1 joins it. With tapers alone (the former export) a vehicle had
    # ~70 m, mostly taper, to get in or out: SUMO jammed at every cloverleaf loop at 1800 veh/h
    from flyover.opendrive.writer import ExportOptions, xodr_bytes

    lengths = {}
    for name, opts in (("tapers", ExportOptions(decel_length_m=0.0, accel_length_m=0.0)),
                       ("parallel", ExportOptions())):
        (tmp_path / f"{name}.xodr").write_bytes(xodr_bytes(sample_geometry("loop"), opts))
        assert run_netconvert(tmp_path / f"{name}.xodr", tmp_path / f"{name}.net.xml").ok
        lengths[name] = _aux_lengths(tmp_path / f"{name}.net.xml", 2)
    assert len(lengths["tapers"]) == len(lengths["parallel"]) == 2
    assert max(lengths["tapers"]) < 80.0
    opts = ExportOptions()
    decel, accel = lengths["parallel"]
    assert decel >= opts.decel_length_m + opts.taper_length_m / 3
    assert accel >= opts.accel_length_m + opts.taper_length_m / 3


def test_class_rows_follow_sample_and_density_whatever_the_run_order(t_net, tmp_path):
    # runs start densest first (the longest first, for the workers' balance); the tables list
    # them by sample, then density, the same bytes for one worker or two
    s = ThroughputSettings(densities=(450.0, 900.0), duration_s=200.0, interval_s=20.0)
    out = []
    for workers in (1, 2):
        rows = run_class([(1, t_net), (0, t_net)], "ct", s, tmp_path / f"{workers}.parquet",
                         tmp_path / f"{workers}/series.parquet", workers=workers)
        assert [(r["sample"], r["density_veh_h"]) for r in rows] == \
            [(0, 450.0), (0, 900.0), (1, 450.0), (1, 900.0)]
        out.append(((tmp_path / f"{workers}.parquet").read_bytes(),
                    (tmp_path / f"{workers}/series.parquet").read_bytes()))
    assert out[0] == out[1]
