"""The sampling stage of the Snakemake workflow, run for real on a small city."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pyarrow.parquet as pq
import pytest
import yaml

from flyover.topology.catalog import catalog_dir
from tests.conftest import REPO

pytestmark = pytest.mark.integration

SNAKEMAKE = [sys.executable, "-m", "snakemake", "-s", str(REPO / "Snakefile")]


def snakemake(workdir: Path, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([*SNAKEMAKE, "-d", str(workdir), *args], capture_output=True,
                          text=True, check=False, cwd=workdir)


def make_workdir(root: Path, **sampling) -> Path:
    """A work dir whose only city holds J1 and the trumpet."""
    (root / "config" / "cities" / "town").mkdir(parents=True)
    config = yaml.safe_load((REPO / "config" / "config.yaml").read_text())
    config["sampling"].update(sampling)
    (root / "config" / "config.yaml").write_text(yaml.safe_dump(config))
    for name in ("j1", "trumpet"):
        shutil.copy(catalog_dir() / f"{name}.yaml", root / "config" / "cities" / "town")
    return root


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    wd = make_workdir(tmp_path_factory.mktemp("wf"))
    run = snakemake(wd, "-j2", "sampling")
    assert run.returncode == 0, run.stderr[-3000:]
    return wd


def test_every_class_gets_feature_sets_and_a_complete_coverage_row(built):
    classes = pq.read_table(built / "results" / "classes.parquet").to_pylist()
    coverage = pq.read_table(built / "results" / "coverage.parquet").to_pylist()
    assert [r["class_id"] for r in coverage] == sorted({c["class_id"] for c in classes})
    assert pq.read_table(built / "results" / "coverage.parquet").column_names == [
        "class_id", "t", "n_params", "rows", "tuples_total", "tuples_covered", "lower_bound"]
    for row in coverage:
        assert row["t"] == 2 and row["tuples_covered"] == row["tuples_total"]
        # inf is forbidden on every ramp of J1 and the trumpet (they all turn): 7 x 7 radii
        # bound the arrays from below, within a few rows of it
        assert row["lower_bound"] == 49 and 49 <= row["rows"] <= 53
        features = pq.read_table(built / "results" / "features" / f"{row['class_id']}.parquet")
        cls = next(c for c in classes if c["class_id"] == row["class_id"])
        assert features.num_rows == row["rows"] * (cls["n_roads"] + cls["n_ramps"])


def test_rerun_has_nothing_to_do(built):
    dry = snakemake(built, "-n", "sampling")
    assert dry.returncode == 0 and "Nothing to be done" in dry.stdout + dry.stderr


def test_changing_strength_reruns_the_sampling_jobs(built, tmp_path):
    config = built / "config" / "config.yaml"
    doc = yaml.safe_load(config.read_text())
    doc["sampling"]["t"] = 3
    config.write_text(yaml.safe_dump(doc))
    try:
        dry = snakemake(built, "-n", "sampling")
        assert dry.returncode == 0
        assert "sample_class" in dry.stdout and "import_city" not in dry.stdout
    finally:
        doc["sampling"]["t"] = 2
        config.write_text(yaml.safe_dump(doc))


def test_same_config_gives_identical_feature_bytes(built, tmp_path):
    again = make_workdir(tmp_path)
    run = snakemake(again, "-j2", "sampling")
    assert run.returncode == 0, run.stderr[-3000:]
    for path in sorted((built / "results" / "features").glob("*.parquet")):
        assert (again / "results" / "features" / path.name).read_bytes() == path.read_bytes()
    assert (again / "results" / "coverage.parquet").read_bytes() == \
        (built / "results" / "coverage.parquet").read_bytes()
