"""The export rules of the Snakemake workflow, run for real on one small interchange."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from flyover.geometry.model import write_geometry
from flyover.opendrive.pipeline import VALIDATION_SCHEMA, collect_validation
from flyover.opendrive.samples import sample_geometry
from flyover.opendrive.validate import CHECKS

pytestmark = pytest.mark.integration

REPO = Path(__file__).resolve().parents[1]
CLASS = "c0123456789"


def test_export_rules_build_xodr_network_plan_and_validation(tmp_path):
    shutil.copytree(REPO / "config", tmp_path / "config", symlinks=True)
    folder = tmp_path / "results" / "interchanges" / CLASS / "0"
    write_geometry(sample_geometry("t"), folder / "geometry.json")
    targets = [f"results/interchanges/{CLASS}/0/{n}" for n in
               ("interchange.xodr", "interchange.net.xml", "plan.png", "validation.parquet")]
    run = subprocess.run([sys.executable, "-m", "snakemake", "-s", str(REPO / "Snakefile"),
                          "-d", str(tmp_path), "-j2", *targets],
                         capture_output=True, text=True, cwd=tmp_path, check=False)
    assert run.returncode == 0, run.stderr[-3000:]
    rows = pq.read_table(folder / "validation.parquet").to_pylist()
    assert [r["check"] for r in rows] == list(CHECKS)
    assert all(r["ok"] for r in rows), rows
    assert {(r["class_id"], r["sample"]) for r in rows} == {(CLASS, 0)}
    assert (tmp_path / "logs" / "benchmarks" / "export_sumo" / CLASS / "0.tsv").exists()
    out = tmp_path / "results" / "validation.parquet"
    assert collect_validation([folder / "validation.parquet"], out) == len(CHECKS)
    assert pq.read_table(out).schema.equals(VALIDATION_SCHEMA, check_metadata=False)
