"""Peak memory and CPU seconds of every Slurm job on this node, for sizing `resources:`.

Usage (beside a run on the one-node Slurm of tests/cluster/slurm.sh)::

    SLURM_CONF=DIR/slurm.conf .venv/bin/python tests/cluster/measure_jobs.py OUT.tsv

Every 0.1 s it reads the process trees under each job's `slurmstepd` (the batch step with
the executor's Snakemake, and the step it starts with `srun`: Snakemake again, the rule's
script and what it runs: netconvert, the ASAM checker's Python) and keeps per job the peak of
their summed resident memory (what a memory limit on the job counts) and the sum of every
process's own CPU seconds at its last sample (a process shorter than 0.1 s, or its last
0.1 s, is missed: a few per cent low). Stops on SIGINT/SIGTERM and writes one row per job: the Slurm
job id, its rule and wildcards (the executor's `--comment`), wall s, CPU s, peak RSS MB.
Slurm's accounting database would give the same figures (sacct MaxRSS, TotalCPU); the test
cluster has none.
"""

from __future__ import annotations

import re
import signal
import subprocess
import sys
import time

import psutil

STEPD = re.compile(r"slurmstepd: \[(\d+)\.")


def _jobs_of_processes() -> dict[int, list[psutil.Process]]:
    """Slurm job id → every process under its slurmstepd processes."""
    out: dict[int, list[psutil.Process]] = {}
    for proc in psutil.process_iter(["cmdline", "name"]):
        m = STEPD.match(" ".join(proc.info["cmdline"] or []) or proc.info["name"] or "")
        if m:
            try:
                out.setdefault(int(m.group(1)), []).extend(proc.children(recursive=True))
            except psutil.Error:
                pass
    return out


def _comments() -> dict[int, str]:
    run = subprocess.run(["squeue", "--states=all", "--noheader", "--format=%i|%k"],
                         capture_output=True, text=True, check=False)
    return {int(i): c for i, c in (ln.split("|", 1) for ln in run.stdout.splitlines())}


def main(out_path: str) -> int:
    peak_rss: dict[int, float] = {}
    cpu: dict[int, dict[int, float]] = {}  # job → pid → own CPU s at the last sample
    first: dict[int, float] = {}
    last: dict[int, float] = {}
    stop = []
    signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
    signal.signal(signal.SIGINT, lambda *_: stop.append(1))
    while not stop:
        now = time.monotonic()
        for job, procs in _jobs_of_processes().items():
            rss = 0
            for p in procs:
                try:
                    rss += p.memory_info().rss
                    t = p.cpu_times()
                    cpu.setdefault(job, {})[p.pid] = t.user + t.system
                except psutil.Error:
                    pass
            peak_rss[job] = max(peak_rss.get(job, 0.0), rss / 2**20)
            first.setdefault(job, now)
            last[job] = now
        time.sleep(0.1)
    comments = _comments()
    with open(out_path, "w", encoding="utf-8") as f:
        f.write("job\trule\twall_s\tcpu_s\tpeak_rss_mb\n")
        for job in sorted(peak_rss):
            f.write(f"{job}\t{comments.get(job, '?')}\t{last[job] - first[job]:.1f}\t"
                    f"{sum(cpu[job].values()):.1f}\t{peak_rss[job]:.0f}\n")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
