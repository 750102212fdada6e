"""The topology stage of the Snakemake workflow, run for real on small cities."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from flyover.topology.catalog import catalog_dir
from tests.conftest import REPO

pytestmark = pytest.mark.integration

SNAKEMAKE = [sys.executable, "-m", "snakemake", "-s", str(REPO / "Snakefile")]


def snakemake(workdir: Path, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([*SNAKEMAKE, "-d", str(workdir), *args], capture_output=True,
                          text=True, check=False, cwd=workdir)


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    """A work dir with the catalog city and a small second city, topology stage built."""
    wd = tmp_path_factory.mktemp("wf")
    (wd / "config" / "cities").mkdir(parents=True)
    shutil.copy(REPO / "config" / "config.yaml", wd / "config" / "config.yaml")
    shutil.copytree(catalog_dir(), wd / "config" / "cities" / "catalog")
    city = wd / "config" / "cities" / "smalltown"
    city.mkdir()
    shutil.copy(catalog_dir() / "trumpet.yaml", city / "east.yaml")
    (city / "broken.yaml").write_text("expressways: {A: [A1\n")
    (city / "bad_edge.yaml").write_text(
        "expressways: {A: [A1, A2]}\nramps:\n  u: {from: A1 right, to: A2 right}\n  v: {from: A1 right}\n")
    run = snakemake(wd, "-j2", "topology")
    assert run.returncode == 0, run.stderr[-3000:]
    return wd, run


def test_classes_table_has_every_interchange_with_design_columns(built):
    wd, _ = built
    table = pq.read_table(wd / "results" / "classes.parquet").to_pylist()
    assert [c for c in table[0]] == ["city", "interchange", "source_file", "class_id", "class_name",
                                     "n_roads", "n_ramps", "shape"]
    catalog = [r for r in table if r["city"] == "catalog"]
    assert len(catalog) == len(list(catalog_dir().glob("*.yaml")))
    assert len({r["class_id"] for r in catalog}) == len(catalog)
    east = next(r for r in table if r["city"] == "smalltown")
    assert east["interchange"] == "trumpet" and east["class_name"] == "trumpet" and east["shape"] == "T"


def test_each_class_gets_graphml_and_drawing(built):
    wd, _ = built
    classes = {r["class_id"] for r in pq.read_table(wd / "results" / "classes.parquet").to_pylist()}
    for cid in classes:
        png = wd / "results" / "classes" / cid / "topology.png"
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert (wd / "results" / "classes" / cid / "topology.graphml").stat().st_size > 0
    assert (wd / "results" / "topology" / "smalltown" / "trumpet.graphml").exists()


def test_bad_files_are_rejected_reported_and_others_still_built(built):
    wd, run = built
    rejected = pq.read_table(wd / "results" / "rejected.parquet").to_pylist()
    by_file = {Path(r["source_file"]).name: r for r in rejected}
    assert set(by_file) == {"broken.yaml", "bad_edge.yaml"}
    assert "malformed YAML" in by_file["broken.yaml"]["reason"]
    assert by_file["bad_edge.yaml"]["element"] == "v" and "no way out" in by_file["bad_edge.yaml"]["reason"]
    assert "bad_edge.yaml: v: ramp has no way out" in run.stderr


def test_rerun_does_nothing_and_new_city_runs_only_its_jobs(built):
    wd, _ = built
    again = snakemake(wd, "-n", "topology")
    assert "Nothing to be done" in again.stdout + again.stderr
    new = wd / "config" / "cities" / "newcity"
    new.mkdir()
    shutil.copy(catalog_dir() / "stack4.yaml", new / "stack.yaml")
    try:
        dry = snakemake(wd, "-n", "topology")
        out = dry.stdout + dry.stderr
        assert dry.returncode == 0, out[-2000:]
        assert "city=newcity" in out
        assert "city=catalog" not in out and "city=smalltown" not in out
        stats = out.split("Job stats:")[1]
        assert "import_city        1" in stats and "classify           1" in stats
    finally:
        shutil.rmtree(new)


def test_same_inputs_give_identical_bytes(built, tmp_path):
    wd, _ = built
    copy = tmp_path / "again"
    shutil.copytree(wd / "config", copy / "config")
    run = snakemake(copy, "-j1", "topology")
    assert run.returncode == 0, run.stderr[-2000:]
    for rel in ["results/classes.parquet", "results/rejected.parquet", "results/classes/manifest.json",
                "results/topology/catalog/stack4.graphml"]:
        assert (copy / rel).read_bytes() == (wd / rel).read_bytes(), rel


def test_workflow_lints_clean():
    run = subprocess.run([*SNAKEMAKE, "--lint"], capture_output=True, text=True, cwd=REPO)
    assert "Congratulations, your workflow is in a good condition" in run.stdout + run.stderr
