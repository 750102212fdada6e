"""``flyover topology check`` and ``flyover classify``."""

from __future__ import annotations

import argparse
import sys

from flyover.cli_output import print_json, report_errors

__all__ = ["register"]


def register(sub: argparse._SubParsersAction) -> None:
    topo = sub.add_parser("topology", help="topology files: check")
    tsub = topo.add_subparsers(dest="topology_command", metavar="ACTION", required=True)
    check = tsub.add_parser("check", help="validate topology files; one summary line per interchange")
    check.add_argument("files", nargs="+", metavar="FILE", help="GraphML, YAML spec, .osm, or a folder")
    check.set_defaults(func=_check)

    cls = sub.add_parser("classify", help="print the isomorphism class of each interchange")
    cls.add_argument("files", nargs="+", metavar="FILE", help="GraphML, YAML spec, .osm, or a folder")
    cls.add_argument("--json", action="store_true", help="machine-readable output")
    cls.set_defaults(func=_classify)


def _load(paths):
    """Read every file; return (topologies, errors) — one bad file never stops the rest."""
    from flyover.errors import FlyoverError
    from flyover.topology.io import iter_files, read_topologies

    topologies, errors = [], []
    for path in iter_files(paths):
        try:
            topologies += read_topologies(path)
        except FlyoverError as exc:
            errors.append(exc.located(str(path)))
    return topologies, errors


def _check(args) -> int:
    topologies, errors = _load(args.files)
    for t in topologies:
        print(f"{t.source}: {t.summary()}")
    return report_errors(errors)


def _classify(args) -> int:
    from flyover.topology.classify import classify

    topologies, errors = _load(args.files)
    classes = classify(topologies)
    rows = [
        {"source_file": m.source, "interchange": m.name, "class_id": c.class_id,
         "class_name": c.class_name, "n_roads": m.n_roads, "n_ramps": m.n_ramps, "shape": m.shape}
        for c in classes for m in c.members
    ]
    rows.sort(key=lambda r: (str(r["source_file"]), r["interchange"]))
    if args.json:
        print_json(rows, errors)
    else:
        for r in rows:
            print(f"{r['source_file']}: {r['interchange']}: {r['class_id']} {r['class_name']} "
                  f"({r['n_roads']} roads, {r['n_ramps']} ramps, {r['shape']})")
        print(f"{len(rows)} interchanges in {len(classes)} classes", file=sys.stderr)
    return report_errors(errors)
