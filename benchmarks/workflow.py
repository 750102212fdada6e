"""The main job, measured as a user runs it: from a fresh clone, `snakemake -j2`.

Usage::

    .venv/bin/python benchmarks/workflow.py                 # everything below, in a temp clone
    .venv/bin/python benchmarks/workflow.py --keep DIR      # clone into DIR and keep it

Steps (each printed with its wall time):

1. ``git clone`` of this repository's HEAD (the working tree's uncommitted changes are not
   in it) into a temporary folder; the clone uses this ``.venv``, ``.venv-qc`` and
   ``.venv-clients`` and
   compiles its numba kernels first (``python -m flyover.warmup``, as ``./dev setup`` does);
2. the main job: ``snakemake -j2`` (everything ``rule all`` asks);
3. a no-op rerun (``snakemake -j2`` again);
4. one class's feature sets changed (its last feature set removed from
   ``results/features/{class}.parquet``): the job list of a dry run, then the run;
5. a new city with one interchange (a class the catalog does not have): the job list, then
   the run.

Then per stage of the main job the CPU seconds per interchange and the peak memory of any
job, from the line every workflow script's log ends with (``resource usage: cpu_s=…
children_cpu_s=… max_rss_mb=…``, :mod:`flyover.workflow_log`; Snakemake's own ``benchmark:``
files sample the process tree and miss short child processes such as netconvert).
"""

from __future__ import annotations

import argparse
import os
import re
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pyarrow.parquet as pq

REPO = Path(__file__).resolve().parents[1]

#: a city of one interchange in a class the catalog has not: expressway A ends at B, with
#: the two directional ramps of a Y (A1 → B1 and B2 → A2)
NEW_CITY = """\
# A directional Y: expressway A ends where it joins B (two ramps); a class of its own.
name: y_two_ramps
expressways:
  A: [A1, A2]
  B: [B1, B2]
ramps:
  rIn:  {from: A1 straight, to: B1 right @0.60}
  rOut: {from: B2 right @0.40, to: A2 straight}
"""


def _run(cmd: list[str], cwd: Path, log: Path) -> tuple[float, subprocess.CompletedProcess]:
    env = dict(os.environ, PYTHONPATH=str(cwd))
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, env=env, check=False)
    dt = time.perf_counter() - t0
    log.write_text(proc.stdout + proc.stderr, encoding="utf-8")
    return dt, proc


def _jobs(dry_run_output: str) -> list[str]:
    """The 'Job stats' table of a dry run as 'rule count' lines."""
    m = re.search(r"Job stats:\n.*?\n-+\s+-+\n(.*?)\n\n", dry_run_output, re.S)
    return [ln.strip() for ln in m.group(1).splitlines()] if m else ["(nothing to be done)"]


_USAGE = re.compile(r"resource usage: cpu_s=([\d.]+) children_cpu_s=([\d.]+) max_rss_mb=(\d+)")


def _stage_costs(clone: Path) -> dict[str, tuple[float, int, float, int]]:
    """stage → (CPU s of its jobs and their children, interchanges, peak RSS MB, jobs), from
    the resource line every workflow script's log ends with (flyover.workflow_log)."""
    per_class = {}
    for p in (clone / "results" / "features").glob("c*.parquet"):
        per_class[p.stem] = len(set(pq.read_table(p, columns=["sample"]).column("sample").to_pylist()))
    simulated = {}
    for p in (clone / "results" / "throughput").glob("c*.parquet"):
        simulated[p.stem] = len(set(pq.read_table(p, columns=["sample"]).column("sample").to_pylist()))
    out: dict[str, list] = {}
    for log in sorted((clone / "logs").rglob("*.log")):
        m = _USAGE.search(log.read_text(encoding="utf-8", errors="replace"))
        if not m:
            continue
        rel = log.relative_to(clone / "logs")
        stage = rel.parts[0] if len(rel.parts) > 1 else rel.stem
        if stage == "plugins":
            stage = f"plugins/{rel.parts[1]}"
        counts = simulated if stage == "throughput" else per_class
        n = counts.get(log.stem, 0) if len(rel.parts) > 1 and stage not in ("topology",) else 0
        cpu, kids, rss = float(m[1]), float(m[2]), float(m[3])
        acc = out.setdefault(stage, [0.0, 0, 0.0, 0])
        acc[0] += cpu + kids
        acc[1] += n
        acc[2] = max(acc[2], rss)
        acc[3] += 1
    return {k: tuple(v) for k, v in out.items()}


def _cpu_of_children() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--keep", type=Path, help="clone into this folder and keep it")
    ap.add_argument("-j", "--jobs", type=int, default=2)
    args = ap.parse_args(argv)

    clone = args.keep or Path(tempfile.mkdtemp(prefix="flyover-bench-"))
    if clone.exists() and any(clone.iterdir()):
        sys.exit(f"{clone} is not empty")
    subprocess.run(["git", "clone", "-q", str(REPO), str(clone)], check=True)
    head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=clone, capture_output=True,
                          text=True, check=True).stdout.strip()
    for venv in (".venv", ".venv-qc", ".venv-clients"):
        (clone / venv).symlink_to(REPO / venv)
    py, smk = str(REPO / ".venv" / "bin" / "python"), str(REPO / ".venv" / "bin" / "snakemake")
    logs = clone / "bench-logs"
    logs.mkdir()
    print(f"clone of {head} in {clone}")

    dt, _ = _run([py, "-m", "flyover.warmup"], clone, logs / "warmup.log")
    print(f"set-up: numba kernels compiled in {dt:.0f} s")
    cpu0 = _cpu_of_children()
    dt, proc = _run([smk, f"-j{args.jobs}"], clone, logs / "main.log")
    cpu = _cpu_of_children() - cpu0
    print(f"main job (snakemake -j{args.jobs}): {dt:.0f} s wall = {dt / 60:.1f} min, exit {proc.returncode}; "
          f"CPU {cpu:.0f} s (every process; {cpu / dt:.2f} cores busy on average)")
    main_costs = _stage_costs(clone)
    summary = proc.stderr[proc.stderr.rfind("flyover: "):].splitlines()[:7]
    print("\n".join("    " + ln for ln in summary))
    dt, proc = _run([smk, f"-j{args.jobs}"], clone, logs / "noop.log")
    print(f"no-op rerun: {dt:.1f} s wall ({'nothing to be done' if 'Nothing to be done' in proc.stderr + proc.stdout else 'RAN JOBS'})")

    klass = sorted((clone / "results" / "features").glob("c*.parquet"))[0]
    table = pq.read_table(klass)  # one feature set less (touching is no change: Snakemake
    samples = table.column("sample").to_pylist()  # compares the contents of small files)
    pq.write_table(table.take([i for i, s in enumerate(samples) if s != max(samples)]), klass)
    _, proc = _run([smk, "-n"], clone, logs / "touch-dry.log")
    print(f"one class's feature sets changed ({klass.stem}: its last sample removed); jobs:")
    print("\n".join("    " + j for j in _jobs(proc.stdout + proc.stderr)))
    dt, proc = _run([smk, f"-j{args.jobs}"], clone, logs / "touch.log")
    print(f"    run: {dt:.0f} s wall, exit {proc.returncode}")

    city = clone / "config" / "cities" / "newcity"
    city.mkdir()
    (city / "y.yaml").write_text(NEW_CITY, encoding="utf-8")
    _, proc = _run([smk, "-n"], clone, logs / "city-dry.log")
    print("a new city with one interchange (a new class); jobs:")
    print("\n".join("    " + j for j in _jobs(proc.stdout + proc.stderr)))
    dt, proc = _run([smk, f"-j{args.jobs}"], clone, logs / "city.log")
    print(f"    run: {dt:.0f} s wall, exit {proc.returncode}")

    print("\nper stage of the main job (CPU of its jobs and their child processes, from the")
    print("resource line at the end of each job's log; interchanges: built, or simulated for throughput):")
    print(f"    {'stage':<20} {'jobs':>5} {'interchanges':>12} {'CPU s':>8} {'CPU s / interchange':>20} {'peak RSS MB':>12}")
    for stage, (cpu, n, rss, jobs) in main_costs.items():
        per = f"{cpu / n:>20.3f}" if n else f"{'-':>20}"
        print(f"    {stage:<20} {jobs:>5} {n:>12} {cpu:>8.0f} {per} {rss:>12.0f}")
    if not args.keep:
        shutil.rmtree(clone, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
