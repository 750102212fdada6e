"""Benchmark: the truck_fuel plugin on every interchange of a results folder, and the queries.

Prints per-ramp CPU time (median, p95; seconds per ramp-km, median and
overall), the distribution of the maximum tracking error (ramps of radius
≥ 30 m), completion, the fuel by direction, and the wall time of every named
query over the rows written. Targets: median ≤ 0.1 s CPU per ramp-km on one
core; max lateral error ≤ 0.3 m on ramps of radius ≥ 30 m; each query ≤ 1 s.

    .venv/bin/python benchmarks/fuel.py [--results results] [--limit N] [--out DIR]

``--out`` receives the hive partitions (default: a temporary folder); the
results folder is only read.
"""

from __future__ import annotations

import argparse
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--results", default="results")
    ap.add_argument("--limit", type=int, default=0, help="at most N interchanges (0: all)")
    ap.add_argument("--out", default="", help="where to write the fuel partitions")
    ap.add_argument("--replicate", type=int, default=40,
                    help="time the queries also on the fuel partitions copied this many times "
                         "(as other samples): catalog scale is ~7,000 ramps in ~820 partitions")
    args = ap.parse_args()

    from flyover.analytics import NAMED_QUERIES, MissingTableError, query
    from flyover.geometry.model import read_geometry
    from flyover.plugins.batch import write_partition
    from flyover_truck_fuel.params import settings
    from flyover_truck_fuel.plugin import evaluate_ramp, fuel_schema

    paths = sorted(Path(args.results).glob("interchanges/*/*/geometry.json"))
    if args.limit:
        paths = paths[: args.limit]
    if not paths:
        raise SystemExit(f"no geometry.json under {args.results}/interchanges")
    out = Path(args.out) if args.out else Path(tempfile.mkdtemp(prefix="fuel-bench-"))
    st = settings({})
    t0 = time.process_time()
    evaluate_ramp(read_geometry(paths[0]), read_geometry(paths[0]).ramps[0], st)
    warm = time.process_time() - t0
    rows, cpu = [], []
    wall0 = time.perf_counter()
    for path in paths:
        g = read_geometry(path)
        part = []
        for ramp in g.ramps:
            t0 = time.process_time()
            part.append(evaluate_ramp(g, ramp, st))
            cpu.append(time.process_time() - t0)
        write_partition(part, fuel_schema(), out, "fuel", g.class_id, g.sample)
        rows += part
    wall = time.perf_counter() - wall0
    cpu = np.array(cpu)
    km = np.array([r["length_m"] / 1000.0 for r in rows])
    per_km = cpu / km
    done = np.array([bool(r.get("completed")) for r in rows])
    radius = np.array([r.get("min_radius_m", np.nan) for r in rows], float)
    err = np.array([r.get("max_lateral_error_m", np.nan) for r in rows], float)
    acc = np.array([r.get("max_lateral_accel_mps2", np.nan) for r in rows], float)
    print(f"interchanges {len(paths)}, ramps {len(rows)}, ramp-km {km.sum():.1f} "
          f"(median ramp {np.median(km) * 1000:.0f} m); model build + first ramp {warm:.2f} s CPU")
    print(f"CPU per ramp: median {np.median(cpu):.3f} s, p95 {np.percentile(cpu, 95):.3f} s, "
          f"total {cpu.sum():.1f} s ({wall:.1f} s wall)")
    print(f"CPU per ramp-km: median {np.median(per_km):.3f} s, p95 {np.percentile(per_km, 95):.3f} s, "
          f"overall {cpu.sum() / km.sum():.3f} s  (target: median <= 0.1)")
    print(f"completed {done.sum()}/{len(rows)}")
    sel = done & (radius >= 30.0)
    if sel.any():
        q = np.percentile(err[sel], [50, 90, 95, 99, 100])
        print(f"max lateral error, {sel.sum()} completed ramps of radius >= 30 m: "
              f"median {q[0]:.3f}, p90 {q[1]:.3f}, p95 {q[2]:.3f}, p99 {q[3]:.3f}, "
              f"max {q[4]:.3f} m  (target: <= 0.3); over 0.3 m: {(err[sel] > 0.3).sum()}")
        print(f"max lateral acceleration: median {np.median(acc[sel]):.2f}, "
              f"max {acc[sel].max():.2f} m/s2")
    for r in rows:
        if not r.get("completed"):
            print(f"  not completed: {r['class_id']}/{r['sample']} {r['ramp']}: {r['reason']}")
    # queries over the rows just written (and the other tables of --results, if present)
    tmp = Path(tempfile.mkdtemp(prefix="fuel-bench-q-"))
    try:
        for item in Path(args.results).iterdir():
            if item.name != "fuel":
                (tmp / item.name).symlink_to(item.resolve())
        (tmp / "fuel").symlink_to((out / "fuel").resolve())
        for q in NAMED_QUERIES.values():
            t0 = time.perf_counter()
            try:
                tbl = query(q.sql, tmp)
                print(f"query {q.name:20s} {time.perf_counter() - t0:6.3f} s, {tbl.num_rows} rows")
            except MissingTableError as exc:
                print(f"query {q.name:20s} skipped: {exc.table} not built")
        res = query(NAMED_QUERIES["fuel-by-direction"].sql, tmp)
        for r in res.to_pylist():
            print("  ", r)
        if args.replicate > 1:
            (tmp / "fuel").unlink()
            parts = sorted((out / "fuel").glob("class_id=*/sample=*/part-0.parquet"))
            for k in range(args.replicate):
                for part in parts:
                    s = int(part.parent.name.split("=")[1]) + 1000 * k
                    dst = tmp / "fuel" / part.parent.parent.name / f"sample={s}" / part.name
                    dst.parent.mkdir(parents=True, exist_ok=True)
                    shutil.copyfile(part, dst)
            n = query("SELECT count(*) AS n FROM fuel", tmp).column("n")[0].as_py()
            print(f"queries over {len(parts) * args.replicate} partitions, {n} rows:")
            for q in NAMED_QUERIES.values():
                t0 = time.perf_counter()
                try:
                    tbl = query(q.sql, tmp)
                    print(f"query {q.name:20s} {time.perf_counter() - t0:6.3f} s, "
                          f"{tbl.num_rows} rows")
                except MissingTableError as exc:
                    print(f"query {q.name:20s} skipped: {exc.table} not built")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
        if not args.out:
            shutil.rmtree(out, ignore_errors=True)


if __name__ == "__main__":
    main()
