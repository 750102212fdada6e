"""``flyover osm FILE.osm[.pbf|.gz|.bz2]``: the interchanges an OpenStreetMap extract holds."""

from __future__ import annotations

import argparse
import sys

from flyover.cli_output import print_json, report_errors

__all__ = ["register"]


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("osm", help="list the motorway interchanges of OpenStreetMap extracts")
    p.add_argument("files", nargs="+", metavar="FILE.osm", help="OSM extract(s): .osm, .osm.pbf, .osm.gz, "
                   ".osm.bz2")
    p.add_argument("--config", metavar="YAML", help="config file whose osm: section to use "
                   "(default: config/config.yaml if present)")
    p.add_argument("--plot", metavar="DIR", help="also draw each interchange's OSM geometry to "
                   "DIR/{interchange}.png")
    p.add_argument("--notes", action="store_true", help="print the data quirks met (snaps, "
                   "reclassified ways, ignored links)")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=_osm)


def _osm(args) -> int:
    from pathlib import Path

    from flyover.config import load_config
    from flyover.errors import FlyoverError
    from flyover.osm import OsmOptions, default_options, read_osm_topologies
    from flyover.osm.plot import plot_osm_topology
    from flyover.topology.canonical import class_id
    from flyover.topology.catalog import catalog_class_names
    from flyover.topology.names import child_path

    options = OsmOptions.from_config(load_config(args.config)) if args.config else default_options()
    names = catalog_class_names()
    rows, errors = [], []
    for path in args.files:
        try:
            topologies = read_osm_topologies(path, options)
        except FlyoverError as exc:
            errors.append(exc.located(str(path)))
            continue
        if not topologies:
            print(f"{path}: no motorway-to-motorway interchange found", file=sys.stderr)
        for t in topologies:
            cid = class_id(t)
            row = {"source_file": str(path), "interchange": t.name, "n_roads": t.n_roads,
                   "n_ramps": t.n_ramps, "shape": t.shape, "class_id": cid,
                   "catalog_design": names.get(cid), "roads": list(t.roads),
                   "expressways": {k: list(v) for k, v in t.expressways.items()},
                   "notes": t.attrs["osm"]["quirks"], "self_check": t.attrs["osm"].get("self_check", [])}
            if args.plot:
                try:
                    png = child_path(Path(args.plot), t.name, ".png", source=str(path))
                except FlyoverError as exc:
                    errors.append(exc)
                    continue
                png.parent.mkdir(parents=True, exist_ok=True)
                plot_osm_topology(t, png)
                row["picture"] = str(png)
            rows.append(row)
    if args.json:
        print_json(rows, errors)
    else:
        for r in rows:
            design = r["catalog_design"] or "no catalog design"
            exps = ", ".join(f"{k} ({'/'.join(v)})" for k, v in r["expressways"].items())
            print(f"{r['source_file']}: {r['interchange']}: {r['n_roads']} roads, {r['n_ramps']} ramps, "
                  f"{r['shape']}, {r['class_id']} = {design}; expressways {exps}"
                  + (f"; picture {r['picture']}" if "picture" in r else ""))
            for row in r["self_check"]:
                print(f"    self-check {row['check']}: {row['detail']}")
            if args.notes:
                for note in r["notes"]:
                    print(f"    note: {note}")
    return report_errors(errors)
