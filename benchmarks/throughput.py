"""Throughput experiment cost and checks: per-run wall per class and density, libsumo vs sumo.

Usage::

    .venv/bin/python benchmarks/throughput.py --root results --samples 2
    .venv/bin/python benchmarks/throughput.py --root results --samples 1 --compare 3 --step-check 3

For ``--samples`` interchanges of every class under ``ROOT/interchanges`` (the
experiment's own seeded choice; ``ROOT/classes.parquet`` names the classes) and
every density of the config (``--configfile``, default config/config.yaml):

* one line per run (throughput, stable window, counts, CPU and wall seconds);
* per class and density: median and p95 CPU seconds of a run (= wall on an idle
  core; CPU is what a shared machine cannot distort), mean throughput,
  teleports (wrong lane) and collisions;
* ``--compare N``: N runs (interchanges at the highest density, the costliest)
  through libsumo in-process and through the ``sumo`` binary on the same network,
  route file, seed and options: CPU seconds of each and libsumo's overhead, and
  whether they inserted and arrived the same vehicles;
* ``--step-check N``: N runs at half the config's step length: throughput and CPU
  (a setting for speed must not change the throughput);
* the cost of the default experiment (``samples_per_class`` per class) and of the
  paper's (20 per class, config/paper.yaml) on 2 cores, from the mean CPU per
  interchange (all densities) measured here.
"""

from __future__ import annotations

import argparse
import resource
import statistics
import subprocess
import tempfile
import time
from collections import defaultdict
from dataclasses import replace
from pathlib import Path

import numpy as np
import sumolib

from flyover.config import load_config
from flyover.traffic.batch import run_flows, select_samples
from flyover.traffic.demand import interchange_or_network_flows, routes_xml
from flyover.traffic.figures import class_names
from flyover.traffic.measure import stable_window
from flyover.traffic.settings import ThroughputSettings, run_seed
from flyover.traffic.simulate import sumo_args


def p95(x):
    return float(np.percentile(x, 95)) if x else float("nan")


def run_one(net, flows, d, seed, s):
    res = run_flows(net, flows, d, seed, s)
    w = stable_window(res.entered, res.left, res.interval_s, min_stable_s=s.min_stable_s,
                      balance_tolerance=s.balance_tolerance)
    return res, w


def binary_run(net, flows, d, seed, s) -> tuple[float, float, int, int]:
    """Wall and CPU seconds of the sumo binary on the same files and options; inserted, arrived."""
    with tempfile.TemporaryDirectory() as tmp:
        routes = Path(tmp) / "demand.rou.xml"
        routes.write_text(routes_xml(flows, d, s), encoding="utf-8")
        stat = Path(tmp) / "stats.xml"
        cmd = [sumolib.checkBinary("sumo"), *sumo_args(net, routes, seed, s, Path(tmp) / "log"),
               "--statistic-output", str(stat)]
        t0, c0 = time.perf_counter(), resource.getrusage(resource.RUSAGE_CHILDREN)
        subprocess.run(cmd, check=True, capture_output=True)
        wall = time.perf_counter() - t0
        c1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = (c1.ru_utime - c0.ru_utime) + (c1.ru_stime - c0.ru_stime)
        text = stat.read_text()
    import re

    ins = int(re.search(r'<vehicles [^>]*inserted="(\d+)"', text)[1])
    running = int(re.search(r'<vehicles [^>]*running="(\d+)"', text)[1])
    return wall, cpu, ins, ins - running


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--root", default="results")
    ap.add_argument("--configfile", default=None)
    ap.add_argument("--samples", type=int, default=None, help="per class (default: config's)")
    ap.add_argument("--classes", default="", help="comma-separated class ids (default: all)")
    ap.add_argument("--densities", default="", help="comma-separated (default: config's)")
    ap.add_argument("--compare", type=int, default=0)
    ap.add_argument("--repeat", type=int, default=3, help="repeats of each --compare run")
    ap.add_argument("--step-check", type=int, default=0)
    args = ap.parse_args()
    s = ThroughputSettings.from_config(load_config(args.configfile))
    if args.densities:
        s = replace(s, densities=tuple(float(x) for x in args.densities.split(",")))
    k = s.samples_per_class if args.samples is None else args.samples
    root = Path(args.root)
    names = class_names(root / "classes.parquet") if (root / "classes.parquet").exists() else {}
    by_class = defaultdict(list)
    for net in sorted(root.glob("interchanges/*/*/interchange.net.xml")):
        by_class[net.parent.parent.name].append(int(net.parent.name))
    wanted = set(args.classes.split(",")) if args.classes else set(by_class)
    walls = defaultdict(list)
    tps = defaultdict(list)
    per_ic = []
    bad = defaultdict(lambda: [0, 0, 0])
    runs = []
    for c in sorted(by_class, key=lambda c: names.get(c, c)):
        if c not in wanted:
            continue
        for smp in select_samples(by_class[c], k, s.seed, c):
            net = root / "interchanges" / c / str(smp) / "interchange.net.xml"
            try:
                flows, _ = interchange_or_network_flows(net, uturns=s.uturns)
            except Exception as exc:  # noqa: BLE001
                print(f"{names.get(c, c):18s} {smp:3d} no demand: {exc}")
                continue
            t_ic = 0.0
            for d in s.densities:
                seed = run_seed(s.seed, c, smp, d)
                res, w = run_one(net, flows, d, seed, s)
                t_ic += res.cpu_s
                walls[(c, d)].append(res.cpu_s)
                tps[(c, d)].append(w.throughput_veh_h)
                wl = res.teleport_reasons.get("wrong lane", 0)
                b = bad[(c, d)]
                b[0] += res.teleports
                b[1] += wl
                b[2] += res.collisions
                runs.append((c, smp, d, net, flows, seed))
                print(f"{names.get(c, c):18s} {smp:3d} {d:6.0f} veh/h x{len(flows):2d}: "
                      f"{w.throughput_veh_h:7.0f} veh/h (demand {d * len(flows):6.0f}) from "
                      f"{w.stable_from_s:5.0f} s {'balanced' if w.balanced else 'NOT balanced'}; "
                      f"in {int(res.entered.sum())} out {int(res.left.sum())} not inserted "
                      f"{res.not_inserted} teleports {res.teleports} ({res.teleport_reasons}) "
                      f"collisions {res.collisions}; cpu {res.cpu_s:.2f} s wall {res.wall_s:.2f} s",
                      flush=True)
            per_ic.append(t_ic)
    print("\nper class and density: CPU s per run (median / p95), mean throughput veh/h, "
          "teleports (wrong lane), collisions")
    for (c, d), w in sorted(walls.items(), key=lambda t: (names.get(t[0][0], t[0][0]), t[0][1])):
        b = bad[(c, d)]
        print(f"  {names.get(c, c):18s} {d:6.0f}: {statistics.median(w):6.2f} / {p95(w):6.2f} s "
              f"({len(w)} runs)  {np.mean(tps[(c, d)]):7.0f} veh/h  teleports {b[0]} ({b[1]})  "
              f"collisions {b[2]}")
    allw = [x for w in walls.values() for x in w]
    if per_ic:
        mean_ic = float(np.mean(per_ic))
        n_cls = len(by_class)
        print(f"\nall runs (CPU s; wall = CPU on an idle core): median {statistics.median(allw):.2f}"
              f" s, p95 {p95(allw):.2f} s, {len(allw)} runs; mean {mean_ic:.1f} s per interchange "
              "(all densities)")
        for label, kk in (("default", s.samples_per_class), ("paper", 20)):
            n = kk * n_cls  # catalog classes hold 64-108 interchanges each: kk of each
            print(f"  {label:8s} ({kk} per class x {n_cls} classes = {n} interchanges, "
                  f"{n * len(s.densities)} runs): {n * mean_ic / 60:.1f} CPU min, "
                  f"~{n * mean_ic / 120:.1f} min on 2 cores")
    if args.compare:
        print("\nlibsumo (in-process, stepped from Python) vs sumo binary, same files and options:")
        top = max(s.densities)
        cmp_runs = [r for r in runs if r[2] == top][: args.compare]
        over = []
        for c, smp, d, net, flows, seed in cmp_runs:
            bins, libs = [], []
            for _ in range(args.repeat):  # interleaved; the least CPU of each is its cost
                bins.append(binary_run(net, flows, d, seed, s))
                libs.append(run_one(net, flows, d, seed, s)[0])
            tb, cb, ins_b, arr_b = min(bins, key=lambda t: t[1])
            res = min(libs, key=lambda r: r.cpu_s)
            ins_l, arr_l = int(res.entered.sum()), int(res.left.sum())
            over.append(res.cpu_s / cb - 1)
            print(f"  {names.get(c, c):18s} {smp:3d} {d:6.0f}: CPU libsumo {res.cpu_s:6.2f} s, "
                  f"sumo {cb:6.2f} s, overhead {100 * over[-1]:+5.1f} % (least of {args.repeat}; "
                  f"wall {res.wall_s:.2f} vs {tb:.2f} s); inserted {ins_l}/{ins_b}"
                  f" arrived {arr_l}/{arr_b} {'same' if (ins_l, arr_l) == (ins_b, arr_b) else 'DIFFER'}")
        print(f"  median overhead {100 * statistics.median(over):+.1f} %")
    if args.step_check:
        print(f"\nstep length {s.step_length_s / 2:g} s vs the config's {s.step_length_s:g} s:")
        half = replace(s, step_length_s=s.step_length_s / 2)
        top = max(s.densities)
        for c, smp, d, net, flows, seed in [r for r in runs if r[2] in (min(s.densities), top)][
                : args.step_check]:
            r1, w1 = run_one(net, flows, d, seed, s)
            r2, w2 = run_one(net, flows, d, seed, half)
            print(f"  {names.get(c, c):18s} {smp:3d} {d:6.0f}: {w1.throughput_veh_h:7.0f} vs "
                  f"{w2.throughput_veh_h:7.0f} veh/h ({100 * (w2.throughput_veh_h / w1.throughput_veh_h - 1):+.1f} %), "
                  f"CPU {r1.cpu_s:.2f} vs {r2.cpu_s:.2f} s")


if __name__ == "__main__":
    main()
