"""Benchmark: classify 10,000 topologies (relabelings and label flips of the catalog).

Prints wall time, time per topology, classes found and peak memory of the
classification step. Target: ≤ 30 s on one core.

    .venv/bin/python benchmarks/classify.py [--n 10000] [--seed 1]
"""

from __future__ import annotations

import argparse
import random
import resource
import time
import tracemalloc

from flyover.topology import Connection, Label, Ramp, Road, Topology, classify
from flyover.topology.catalog import catalog_topologies

FLIP = {"R": "L", "L": "R", "M": "M"}


def variant(t: Topology, rng: random.Random, k: int) -> Topology:
    """``t`` with nodes renamed at random and ``k`` random sides flipped (R <-> L)."""
    names = list(t.graph)
    new = [f"n{i}" for i in rng.sample(range(10 * len(names)), len(names))]
    rename = dict(zip(names, new))
    g = t.graph
    roads = [Road(rename[r], g.nodes[r]["expressway"]) for r in t.roads]
    ramps = [Ramp(rename[r]) for r in t.ramps]
    conns = [Connection(rename[c.source], rename[c.target], c.label) for c in t.connections()]
    for i in rng.sample(range(len(conns)), k):
        c = conns[i]
        conns[i] = Connection(c.source, c.target, Label(c.label.value[:-1] + FLIP[c.label.value[-1]]))
    rng.shuffle(conns)
    return Topology.build(f"{t.name}-{k}", roads, ramps, conns)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=10_000)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    rng = random.Random(args.seed)
    designs = list(catalog_topologies().values())
    pool = [variant(t, rng, rng.choice([0, 0, 1, 2])) for t in rng.choices(designs, k=args.n)]
    ramps = [t.n_ramps for t in pool]
    t0 = time.process_time()
    w0 = time.perf_counter()
    classes = classify(pool)
    cpu, wall = time.process_time() - t0, time.perf_counter() - w0
    tracemalloc.start()  # a second, traced run: tracing slows Python down, so it is not timed
    classify(pool)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    assert sum(len(c.members) for c in classes) == len(pool)
    print(f"topologies          {len(pool)} ({min(ramps)}-{max(ramps)} ramps)")
    print(f"classes             {len(classes)}")
    print(f"wall time           {wall:.2f} s  ({1e3 * wall / len(pool):.3f} ms per topology)")
    print(f"cpu time (1 core)   {cpu:.2f} s")
    print(f"peak traced memory  {peak / 2**20:.1f} MiB during classify")
    print(f"max RSS             {resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MiB (process)")


if __name__ == "__main__":
    main()
