"""The export and validation rules of the Snakemake workflow (one job per class), run for
real on a class of two small interchanges, one of which cannot be written."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from flyover.geometry.batch import failed_rows
from flyover.geometry.layout import RampFeatures
from flyover.geometry.model import write_geometry
from flyover.geometry.tables import GEOMETRY_SCHEMA
from flyover.opendrive.pipeline import PIPELINE_CHECKS, VALIDATION_SCHEMA
from flyover.opendrive.samples import sample_geometry
from flyover.opendrive.writer import xodr_bytes
from flyover.topology.tables import write_parquet

pytestmark = pytest.mark.integration

REPO = Path(__file__).resolve().parents[1]
CLASS = "c0123456789"


def _unwritable(g):
    """``g`` with its first ramp starting 30 m from its attachment (the writer refuses it)."""
    ramp = g.ramps[0]
    moved = type(ramp.start)(ramp.start.parent, ramp.start.label, ramp.start.s_m + 30.0,
                             ramp.start.offset_m, ramp.start.heading_rad, ramp.start.z_m)
    return type(g)(g.class_id, g.sample, g.seed, g.lane_width_m, g.shoulder_width_m,
                   g.ramp_lane_width_m, g.levels_m, g.roads,
                   (type(ramp)(**{**ramp.__dict__, "start": moved}), *g.ramps[1:]))


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """Sample 0 is the loop, sample 1 a T the writer refuses, sample 2 was never built (its
    geometry job recorded why); the class's geometry stage is done (its table and the
    geometry.json files), as the geometry job leaves it. (The hand-made T's left turn merges
    across its carriageway: its clearance row fails too.)"""
    wd = tmp_path_factory.mktemp("wf")
    shutil.copytree(REPO / "config", wd / "config", symlinks=True)
    results = wd / "results"
    base = results / "interchanges" / CLASS
    write_geometry(sample_geometry("loop"), base / "0" / "geometry.json")
    write_geometry(_unwritable(sample_geometry("t")), base / "1" / "geometry.json")
    (base / "7").mkdir()  # a sample the class no longer has: not the export stage's business
    rows = [{"class_id": CLASS, "sample": s, "ramp": "r1", "target_radius_m": 50.0,
             "target_slope_pct": 3.0, "min_radius_m": 50.0, "max_slope_pct": 3.0,
             "length_m": 200.0, "ok": True, "evaluations": 1,
             "first_try_ok": True, "resamples": 0, "infeasible": None, "conflicts": 0,
             "first_target_radius_m": 50.0, "first_target_slope_pct": 3.0} for s in (0, 1)]
    rows += failed_rows(CLASS, 2, {"r1": RampFeatures(30.0, 5.0)}, "not built: r1: no way")
    write_parquet(rows, GEOMETRY_SCHEMA, results / "geometry" / f"{CLASS}.parquet")
    targets = [f"results/validation/{CLASS}.parquet"]
    proc = subprocess.run([sys.executable, "-m", "snakemake", "-s", str(REPO / "Snakefile"),
                           "-d", str(wd), "-j2", *targets],
                          capture_output=True, text=True, cwd=wd, check=False)
    return wd, proc


def _rows(wd, sample):
    table = pq.read_table(wd / "results" / "validation" / f"{CLASS}.parquet")
    assert table.schema.equals(VALIDATION_SCHEMA, check_metadata=False)
    return {r["check"]: r for r in table.to_pylist() if r["sample"] == sample}


def test_one_failed_interchange_leaves_the_rest_of_its_class_built(run):
    wd, proc = run
    assert proc.returncode == 0, proc.stderr[-3000:]
    rows = pq.read_table(wd / "results" / "validation" / f"{CLASS}.parquet").to_pylist()
    assert sorted((r["sample"], r["check"]) for r in rows) == sorted(
        (s, c) for s in (0, 1, 2) for c in PIPELINE_CHECKS)
    assert "export c0123456789: 3/3 interchanges, 2 failed" in proc.stderr


def test_the_good_interchange_passes_every_check_and_is_built(run):
    wd, proc = run
    rows = _rows(wd, 0)
    assert all(r["ok"] for r in rows.values()), rows
    folder = wd / "results" / "interchanges" / CLASS / "0"
    assert (folder / "interchange.xodr").read_bytes() == xodr_bytes(sample_geometry("loop"))
    assert (folder / "interchange.net.xml").stat().st_size > 0
    assert (folder / "plan.png").read_bytes()[:4] == b"\x89PNG"
    assert (wd / "logs" / "benchmarks" / "export" / f"{CLASS}.tsv").exists()
    assert "asam_qc" in rows and "1.7 (written from geometry.json" in rows["asam_qc"]["detail"]


def test_the_refused_interchange_is_failed_rows_and_no_files(run):
    wd, proc = run
    rows = _rows(wd, 1)
    geometry = f"results/interchanges/{CLASS}/1/geometry.json"
    assert not rows["export"]["ok"]
    assert rows["export"]["detail"].startswith(geometry + ": r1: ")
    assert not any(r["ok"] for r in rows.values())
    assert all(rows[c]["detail"].startswith("not run") for c in ("xsd", "asam_qc", "routes"))
    folder = wd / "results" / "interchanges" / CLASS / "1"
    assert sorted(p.name for p in folder.iterdir()) == ["geometry.json"]
    assert f"{geometry}: r1: " in (wd / "logs" / "export" / f"{CLASS}.log").read_text()


def test_an_interchange_the_geometry_stage_could_not_build_is_rows_with_its_reason(run):
    wd, proc = run
    rows = _rows(wd, 2)
    assert rows["export"]["detail"] == f"results/interchanges/{CLASS}/2/geometry.json: not built: r1: no way"
    assert not any(r["ok"] for r in rows.values())
    assert not (wd / "results" / "interchanges" / CLASS / "2").exists()
