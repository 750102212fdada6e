"""The workflow on a real one-node Slurm, through the executor plugin and profiles/slurm.

tests/cluster/slurm.sh brings up munged, slurmctld and slurmd on this machine (Debian's
slurm-wlm and munge, installed if missing and we are root); a city of one interchange (the
directional Y, two ramps, t = 1: 8 interchanges) goes through topology, sampling, geometry,
export and validation as Slurm jobs, and every file under results/ must be the bytes a local
run (`snakemake -j2`) makes, apart from the fitting times. Opt-in (`-m slurm`, about
2.5 minutes on 2 cores); skipped with the reason where Slurm cannot be installed or started.

The cluster has no accounting database, so the executor asks squeue for job states; with
FLYOVER_SLURM_ACCOUNTING=1 it gets one (slurmdbd, MariaDB) and the profile runs as it is
shipped, job states from sacct.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from tests.small_city import NOT_REPRODUCIBLE, Y

pytestmark = [pytest.mark.slurm, pytest.mark.integration, pytest.mark.slow]

REPO = Path(__file__).resolve().parents[2]
SLURM_SH = REPO / "tests" / "cluster" / "slurm.sh"
SNAKEMAKE = [sys.executable, "-m", "snakemake", "-s", str(REPO / "Snakefile")]
TARGETS = ["topology", "sampling", "export"]
ACCOUNTING = os.environ.get("FLYOVER_SLURM_ACCOUNTING") == "1"
#: the first status query 2 s after a submission (the default 40 s suits a busy cluster);
#: a cluster without an accounting database: job states from squeue, no account to guess
CLUSTER_ARGS = ["--profile", str(REPO / "profiles" / "slurm"),
                "--slurm-init-seconds-before-status-checks", "2",
                *([] if ACCOUNTING else ["--slurm-status-command", "squeue", "--slurm-no-account"])]
@pytest.fixture(scope="module")
def slurm(tmp_path_factory):
    """A one-node Slurm for this module: the environment its clients need."""
    pytest.importorskip("snakemake_executor_plugin_slurm",
                        reason='the executor plugin is not installed (pip install -e ".[slurm]")')
    state = tmp_path_factory.mktemp("slurm")
    up = subprocess.run([str(SLURM_SH), "up", str(state)], capture_output=True, text=True,
                        check=False)
    if up.returncode == 2:  # what did start is stopped
        subprocess.run([str(SLURM_SH), "down", str(state)], check=False)
        pytest.skip(f"Slurm cannot start here: {up.stderr.strip().splitlines()[-1]}")
    try:
        assert up.returncode == 0, up.stderr
        yield dict(os.environ, SLURM_CONF=str(state / "slurm.conf"))
    finally:
        subprocess.run([str(SLURM_SH), "down", str(state)], check=False)


def _workdir(root: Path) -> Path:
    """A workflow folder: the repository's config, a city of one interchange, t = 1."""
    shutil.copytree(REPO / "config", root / "config", symlinks=True)
    city = root / "config" / "cities" / "one"
    city.mkdir()
    (city / "y.yaml").write_text(Y, encoding="utf-8")
    cfg = yaml.safe_load((root / "config" / "config.yaml").read_text(encoding="utf-8"))
    cfg["cities"] = ["one"]
    cfg["sampling"]["t"] = 1
    (root / "config" / "config.yaml").write_text(yaml.safe_dump(cfg), encoding="utf-8")
    return root


def _snakemake(wd: Path, *args: str, env=None) -> subprocess.CompletedProcess:
    proc = subprocess.run([*SNAKEMAKE, "-d", str(wd), *args], cwd=wd, capture_output=True,
                          text=True, check=False, env=env)
    assert proc.returncode == 0, proc.stderr[-4000:]
    return proc


def _files(wd: Path) -> dict[str, bytes]:
    return {str(p.relative_to(wd)): p.read_bytes()
            for p in sorted((wd / "results").rglob("*")) if p.is_file()}


def test_a_city_built_as_slurm_jobs_is_the_local_run_byte_for_byte(slurm, tmp_path):
    local = _workdir(tmp_path / "local")
    _snakemake(local, "-j2", *TARGETS)
    cluster = _workdir(tmp_path / "cluster")
    run = _snakemake(cluster, *CLUSTER_ARGS, *TARGETS, env=slurm)
    log = run.stdout + run.stderr

    # every job but the target rules went through sbatch and ended COMPLETED in Slurm
    submitted = re.findall(r"has been submitted with SLURM jobid (\d+)", log)
    rules = set(re.findall(r"^(?:rule|checkpoint) (\w+):", log, re.M))
    assert {"import_city", "classify", "class_topology", "sample_class", "coverage_table",
            "geometry_class", "export_class", "validate_class", "validation"} <= rules
    assert len(submitted) == len(re.findall(r"^(?:rule|checkpoint) \w+:", log, re.M))
    states = subprocess.run(["squeue", "--states=all", "--noheader", "--format=%i %T"],
                            capture_output=True, text=True, check=True, env=slurm).stdout
    state = dict(line.split() for line in states.splitlines())
    assert {state.get(job) for job in submitted} == {"COMPLETED"}

    mine, theirs = _files(cluster), _files(local)
    assert sorted(mine) == sorted(theirs)
    differ = [f for f in mine if mine[f] != theirs[f] and not f.startswith(NOT_REPRODUCIBLE)]
    assert differ == []
    assert any(f.endswith("interchange.net.xml") for f in mine)
    # the validation jobs found the ASAM checker's environment from the compute node
    validation = mine["results/validation.parquet"]
    import pyarrow as pa
    import pyarrow.parquet as pq
    table = pq.read_table(pa.BufferReader(validation)).to_pylist()
    qc = [row for row in table if row["check"] == "asam_qc"]
    assert qc and all(row["ok"] for row in qc), qc[:1]
