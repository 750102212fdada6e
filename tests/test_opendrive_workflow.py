"""The export rules of the Snakemake workflow, run for real on two small interchanges,
one of which cannot be written."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from flyover.geometry.model import write_geometry
from flyover.opendrive.pipeline import PIPELINE_CHECKS, VALIDATION_SCHEMA
from flyover.opendrive.samples import sample_geometry
from flyover.opendrive.writer import xodr_bytes

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
    """Sample 0 is the loop, sample 1 a T the writer refuses; the plan lists both. (The
    hand-made T's left turn merges across its carriageway: its clearance row fails too.)"""
    wd = tmp_path_factory.mktemp("wf")
    shutil.copytree(REPO / "config", wd / "config", symlinks=True)
    base = wd / "results" / "interchanges" / CLASS
    write_geometry(sample_geometry("loop"), base / "0" / "geometry.json")
    write_geometry(_unwritable(sample_geometry("t")), base / "1" / "geometry.json")
    (wd / "results" / "geometry").mkdir(parents=True)
    (wd / "results" / "geometry" / "plan.json").write_text(json.dumps({CLASS: [0, 1]}))
    targets = ["results/validation.parquet"] + [
        f"results/interchanges/{CLASS}/{s}/{n}" for s in (0, 1)
        for n in ("interchange.xodr", "interchange.net.xml", "plan.png")]
    # no --keep-going here: the workflow's default profile must supply it
    proc = subprocess.run([sys.executable, "-m", "snakemake", "-s", str(REPO / "Snakefile"),
                           "-d", str(wd), "-j2", *targets],
                          capture_output=True, text=True, cwd=wd, check=False)
    return wd, proc


def test_the_failed_export_fails_the_run_but_the_validation_table_is_built(run):
    wd, proc = run
    assert proc.returncode != 0, "the interchange the writer refuses must fail its job"
    assert "export_xodr" in proc.stderr
    rows = pq.read_table(wd / "results" / "validation.parquet").to_pylist()
    assert pq.read_table(wd / "results" / "validation.parquet").schema.equals(
        VALIDATION_SCHEMA, check_metadata=False)
    assert sorted((r["sample"], r["check"]) for r in rows) == sorted(
        (s, c) for s in (0, 1) for c in PIPELINE_CHECKS)


def test_the_good_interchange_passes_every_check_and_is_built(run):
    wd, proc = run
    rows = [r for r in pq.read_table(wd / "results" / "validation.parquet").to_pylist() if r["sample"] == 0]
    assert all(r["ok"] for r in rows), rows
    folder = wd / "results" / "interchanges" / CLASS / "0"
    assert (folder / "interchange.xodr").read_bytes() == xodr_bytes(sample_geometry("loop"))
    assert (folder / "interchange.net.xml").stat().st_size > 0
    assert (folder / "plan.png").read_bytes()[:4] == b"\x89PNG"
    assert (wd / "logs" / "benchmarks" / "export_sumo" / CLASS / "0.tsv").exists()


def test_the_refused_interchange_is_failed_rows_and_no_files(run):
    wd, proc = run
    rows = {r["check"]: r for r in pq.read_table(wd / "results" / "validation.parquet").to_pylist()
            if r["sample"] == 1}
    geometry = f"results/interchanges/{CLASS}/1/geometry.json"
    assert not rows["export"]["ok"]
    assert rows["export"]["detail"].startswith(geometry + ": r1: ")
    assert not any(r["ok"] for r in rows.values())
    folder = wd / "results" / "interchanges" / CLASS / "1"
    assert sorted(p.name for p in folder.iterdir()) == ["geometry.json", "validation.parquet"]
    assert f"{geometry}: r1: " in (wd / "logs" / "export" / CLASS / "1" / "xodr.log").read_text()
