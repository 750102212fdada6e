"""Which first-try misses are search failures and which may be combinations the room cannot hold.

Builds every feature set of the catalog designs (``results/features/{class_id}.parquet``,
the workflow's; as ``benchmarks/geometry.py --from-results`` builds them: the config's seed
and resampler) and lists each ramp that misses its targets at the first try or is recorded
infeasible. Then builds each such feature set again, unchanged, with ``--seeds`` other seeds
and no resampler: a ramp that meets the same targets at the first try with some seed is a
combination that can be built (a search failure: leave the domain alone); one that no seed
builds is a candidate for a per-ramp domain (:mod:`flyover.geometry.feasibility`), to be
explained from the geometry before anything is forbidden.

Run (from the repository root):
``PYTHONPATH=. .venv/bin/python benchmarks/misses.py --designs j1 --seeds 1 2 3 4 5 6``.
"""

from __future__ import annotations

import argparse
import os

os.environ.setdefault("OMP_NUM_THREADS", "1")

from flyover.config import load_config  # noqa: E402
from flyover.geometry.layout import LayoutSettings  # noqa: E402
from flyover.geometry.tables import (  # noqa: E402
    build_sample, domain_resampler, read_feature_sets, sample_seed,
)
from flyover.topology.canonical import class_id as class_id_of  # noqa: E402
from flyover.topology.catalog import catalog_topologies  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--designs", nargs="*", default=None)
    ap.add_argument("--seeds", nargs="*", type=int, default=[1, 2, 3],
                    help="the other seeds each missing feature set is built with")
    ap.add_argument("--features", default="results/features",
                    help="folder of the feature sets ({class_id}.parquet)")
    args = ap.parse_args()
    cfg = load_config("config/config.yaml")
    settings = LayoutSettings.from_config(cfg["geometry"])
    seed = int(cfg["seed"])
    built_some, never = 0, 0
    for name, topo in catalog_topologies().items():
        if args.designs and name not in args.designs:
            continue
        cid = class_id_of(topo)
        sets = read_feature_sets(f"{args.features}/{cid}.parquet")
        misses = []
        for sample in sorted(sets):
            ic = build_sample(topo, sets[sample], class_id=cid, sample=sample, seed=seed,
                              settings=settings, resampler=domain_resampler(
                                  sets, sample_seed(seed, cid, sample), topo, settings, sample))
            misses += [(sample, o) for o in ic.outcomes if not o.first_try_ok or o.infeasible]
        print(f"{name} ({cid}): {len(misses)} ramps missing at the first try or recorded "
              f"infeasible", flush=True)
        for sample, o in misses:
            t = o.first_targets
            ok = []
            for other in args.seeds:
                again = build_sample(topo, sets[sample], class_id=cid, sample=sample,
                                     seed=other, settings=settings, resampler=None)
                ok += [s.first_try_ok for s in again.outcomes if s.ramp == o.ramp]
            built_some += any(ok)
            never += not any(ok)
            print(f"  sample {sample} {o.ramp} ({t.radius_m:g} m, {t.slope_pct:g} %)"
                  f"{' recorded infeasible: ' + o.infeasible if o.infeasible else ''}: "
                  f"built at the first try with {sum(ok)} of {len(ok)} other seeds", flush=True)
    print(f"built with some other seed (search failures): {built_some}; with none: {never}")


if __name__ == "__main__":
    main()
