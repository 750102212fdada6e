"""Covering-array size and time on the paper's feature model, beside the lower bound and PICT.

Model: lanes {3,4,5} per road; radius (8 values) and slope (5 values) per ramp.
Prints one line per case: rows, lower bound, PICT's rows, rows / PICT, CPU and
wall seconds (one core, numba kernels already compiled), and whether coverage
is complete.

PICT's rows are the ones quoted in the issue (Microsoft PICT, default
options), or measured when ``--pict PATH`` names a PICT binary (e.g. the one
shipped inside the ``pypict`` sdist).

    .venv/bin/python benchmarks/sampling.py [--pict PATH] [--seed N]
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from flyover.sampling import covering_array

#: (roads, ramps, t) → PICT's rows as quoted in the issue; 3 × 3 and 4 × 8 at t=3 measured
#: with the PICT binary shipped in the pypict 0.1.0 sdist (2018), default options
CASES = {
    (3, 3, 2): 74, (4, 4, 2): 85, (4, 6, 2): 98, (4, 8, 2): 110, (4, 12, 2): 126, (4, 4, 3): 691,
    (4, 8, 3): 1140,
}


def levels(roads: int, ramps: int) -> list[int]:
    return [3] * roads + [8, 5] * ramps


def pict_rows(pict: str, roads: int, ramps: int, t: int) -> int:
    """Rows of PICT's array for the same model."""
    lines = [f"L{i}: 3, 4, 5" for i in range(roads)]
    for j in range(ramps):
        lines += [f"R{j}: inf, 280, 210, 150, 100, 60, 40, 30", f"S{j}: 1, 2, 3, 4, 5"]
    with tempfile.TemporaryDirectory() as tmp:
        model = Path(tmp) / "model.txt"
        model.write_text("\n".join(lines) + "\n")
        out = subprocess.run([pict, str(model), f"/o:{t}"], capture_output=True, text=True, check=True)
    return len(out.stdout.strip().splitlines()) - 1  # less the header


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pict", help="a PICT binary, to measure its rows instead of quoting them")
    parser.add_argument("--seed", type=int, default=20231024)
    args = parser.parse_args()
    covering_array([2, 2], 2)  # compile or load the numba kernels once
    print(f"{'roads':>5} {'ramps':>5} {'t':>2} {'rows':>5} {'bound':>5} {'PICT':>5} "
          f"{'/PICT':>6} {'cpu_s':>6} {'wall_s':>6}  complete")
    for (roads, ramps, t), quoted in CASES.items():
        pict = pict_rows(args.pict, roads, ramps, t) if args.pict else quoted
        cpu, wall = time.process_time(), time.perf_counter()
        ca = covering_array(levels(roads, ramps), t, seed=args.seed)
        cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
        ratio = f"{len(ca.rows) / pict:.2f}" if pict else "-"
        print(f"{roads:>5} {ramps:>5} {t:>2} {len(ca.rows):>5} {ca.coverage.lower_bound:>5} "
              f"{pict or '-':>5} {ratio:>6} {cpu:>6.2f} {wall:>6.2f}  {ca.coverage.complete}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
