"""CPU time of sampling one class as the workflow does (rule sample_class): the fixed
features, the forbidden rules (of which the shift rooms, :func:`flyover.geometry.
feasibility.shift_rooms`) and the covering array, each the median of ``--repeat`` runs in
one process (numba kernels compiled or loaded first, so a cold cache is not counted).

    PYTHONPATH=. OMP_NUM_THREADS=1 .venv/bin/python benchmarks/sampling_class.py \
        ../shared/osm/26_us_dc_i66_us50_e_st_expwy.osm cloverleaf [--repeat 3]

Arguments are catalog design names, topology files (GraphML, YAML) or .osm extracts (every
interchange found in it). Prints, per topology: parameters, rules, rows, the rows' sha256
(first 12 hex digits, to compare two checkouts) and the CPU seconds of each part.
"""

from __future__ import annotations

import argparse
import hashlib
import statistics
import sys
import time

from flyover.config import load_config
from flyover.geometry.feasibility import fixed_features, forbidden_features, shift_rooms
from flyover.geometry.settings import LayoutSettings
from flyover.sampling import covering_array
from flyover.sampling.cli import _topologies
from flyover.sampling.sample import sample_topology
from flyover.sampling.settings import settings_from_config


def cpu(fn, repeat: int):
    """``fn()``'s result and the median CPU seconds of ``repeat`` calls."""
    times, out = [], None
    for _ in range(repeat):
        t = time.process_time()
        out = fn()
        times.append(time.process_time() - t)
    return out, statistics.median(times)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("topology", nargs="+")
    ap.add_argument("--config", default="config/config.yaml")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    config = load_config(args.config)
    layout = LayoutSettings.from_config(config.get("geometry", {}))
    settings = settings_from_config(config)
    covering_array([2, 2], 2)  # compile or load the numba kernels once
    print(f"{'topology':<40} {'params':>6} {'rules':>5} {'rows':>4} {'rows_sha':>12} "
          f"{'fixed_s':>7} {'rules_s':>7} {'shift_s':>7} {'array_s':>7}")
    for arg in args.topology:
        for topo in _topologies(arg):
            fixed, t_fixed = cpu(lambda: fixed_features(topo), args.repeat)
            rules, t_rules = cpu(lambda: forbidden_features(topo, settings.profile, layout),
                                 args.repeat)
            _, t_shift = cpu(lambda: shift_rooms(topo, settings.profile, layout), args.repeat)
            s, t_array = cpu(lambda: sample_topology(
                topo, settings.profile, t=settings.t, seed=config["seed"], fixed=fixed,
                extra=rules, budget=settings.budget), args.repeat)
            sha = hashlib.sha256(repr(s.feature_rows()).encode()).hexdigest()[:12]
            print(f"{topo.name[:40]:<40} {s.coverage.n_params:>6} {len(rules):>5} "
                  f"{s.coverage.rows:>4} {sha:>12} {t_fixed:>7.2f} {t_rules:>7.2f} "
                  f"{t_shift:>7.2f} {t_array:>7.2f}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
