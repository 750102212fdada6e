"""``flyover sample``: the covering array of one topology, without the workflow."""

from __future__ import annotations

import argparse
import json
import re
import sys
import time
from pathlib import Path

__all__ = ["register"]

_CLASS_ID = re.compile(r"^c[0-9a-f]{10}$")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "sample", help="covering array of one topology: rows and coverage",
        description="Build the t-way covering array of a topology's features and print its "
                    "size and coverage. Features the geometry stage fixes up front (slope 0 on "
                    "level ramps, see flyover.geometry.feasibility) are written, not sampled. "
                    "TOPOLOGY is a topology file (GraphML, YAML spec, .osm), a class id (read from "
                    "results/classes/) or a catalog design name.")
    p.add_argument("topology", metavar="CLASS_OR_TOPOLOGY_FILE")
    p.add_argument("--t", type=int, default=None, help="strength (default: config sampling.t)")
    p.add_argument("--profile", default=None, help="regulation profile (default: config sampling.profile)")
    p.add_argument("--config", default=None, help="config file (default: config/config.yaml if present)")
    p.add_argument("--seed", type=int, default=None, help="master seed (default: config seed)")
    p.add_argument("--features", metavar="OUT.parquet", default=None,
                   help="also write the feature sets (one topology only)")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=_sample)


def _topologies(arg: str):
    """The topologies ``arg`` names, each with its source."""
    from flyover.errors import InputFormatError
    from flyover.topology.catalog import catalog_topologies
    from flyover.topology.io import read_graphml, read_topologies

    path = Path(arg)
    if path.exists():
        return read_topologies(path)
    if _CLASS_ID.match(arg):
        stored = Path("results/classes") / arg / "topology.graphml"
        if stored.exists():
            return [read_graphml(stored, name=arg)]
        from flyover.topology.canonical import class_id
        found = [t for t in catalog_topologies().values() if class_id(t) == arg]
        if found:
            return found
    if arg in catalog_topologies():
        return [catalog_topologies()[arg]]
    raise InputFormatError("neither a topology file, a class id in results/classes/, "
                           "nor a catalog design", source=arg)


def _sample(args) -> int:
    from flyover.config import load_config
    from flyover.errors import InputFormatError
    from flyover.geometry.feasibility import fixed_features, forbidden_features
    from flyover.geometry.settings import LayoutSettings
    from flyover.sampling.sample import FEATURES_SCHEMA, sample_topology
    from flyover.sampling.settings import settings_from_config
    from flyover.topology.tables import write_parquet

    config = load_config(args.config)
    layout = LayoutSettings.from_config(config.get("geometry", {}))
    settings = settings_from_config(config, profile=args.profile, t=args.t,
                                    source=args.config or "config/config.yaml")
    seed = config["seed"] if args.seed is None else args.seed
    topologies = _topologies(args.topology)
    if args.features and len(topologies) != 1:
        raise InputFormatError(f"--features needs one topology, found {len(topologies)}",
                               source=args.topology)
    out = []
    for topology in topologies:
        start = time.perf_counter()
        s = sample_topology(topology, settings.profile, t=settings.t, seed=seed,
                            fixed=fixed_features(topology),
                            extra=forbidden_features(topology, settings.profile, layout),
                            budget=settings.budget)
        seconds = time.perf_counter() - start
        if args.features:
            write_parquet(s.feature_rows(), FEATURES_SCHEMA, args.features)
        c = s.coverage
        out.append({"interchange": topology.name, **s.coverage_row(), "profile": settings.profile.name,
                    "n_roads": topology.n_roads, "n_ramps": topology.n_ramps,
                    "fixed": {f"{e}.{f.value}": v for e, f, v in s.model.fixed},
                    "construction": s.array.construction, "seconds": round(seconds, 3)})
        if not args.json:
            share = 100.0 * c.tuples_covered / c.tuples_total if c.tuples_total else 100.0
            print(f"{topology.name} ({s.class_id}): {topology.n_roads} roads, {topology.n_ramps} ramps, "
                  f"{c.n_params} parameters, t={c.t}, profile {settings.profile.name}")
            if s.model.fixed:
                print("  fixed (not sampled): " + ", ".join(
                    f"{e} {f.value}={v:g}" for e, f, v in s.model.fixed))
            print(f"  {c.rows} rows (lower bound {c.lower_bound}), {c.tuples_covered}/{c.tuples_total} "
                  f"tuples covered ({share:.1f} %), {seconds:.2f} s")
    if args.json:
        json.dump(out if len(out) > 1 else out[0], sys.stdout, indent=2)
        print()
    return 0
