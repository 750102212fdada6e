"""``flyover validate FILE.xodr`` and ``flyover export GEOMETRY.json``."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

__all__ = ["register"]


def register(sub: argparse._SubParsersAction) -> None:
    val = sub.add_parser(
        "validate", help="check an OpenDRIVE file: XSD, ASAM checker, 3D continuity, netconvert, routes",
        description="Run every check on OpenDRIVE files (ours or anyone's); exit 1 if any fails.")
    val.add_argument("files", nargs="+", metavar="FILE.xodr")
    val.add_argument("--geometry", metavar="GEOMETRY.json",
                     help="flyover geometry the file was written from: the movements to route, and "
                          "the file's 1.7/1.8 rendition that the ASAM checker needs to complete "
                          "every checker (default: geometry.json beside the file, if any)")
    val.add_argument("--net", metavar="NET.xml", help="keep the SUMO network here (one file only)")
    val.add_argument("--no-qc", action="store_true", help="leave out the ASAM checker")
    val.set_defaults(func=_validate)
    exp = sub.add_parser("export", help="write interchange.xodr (and plan.png) from a geometry.json",
                         description="Write an interchange as OpenDRIVE, or as a CommonRoad or Lanelet2 "
                                     "map (converted by commonroad-scenario-designer in the clients' "
                                     "environment, then loaded by its own library as a check).")
    exp.add_argument("geometry", metavar="GEOMETRY.json")
    exp.add_argument("-o", "--output", metavar="FILE",
                     help="default beside it: interchange.xodr, interchange.cr.xml (commonroad) "
                          "or interchange.osm (lanelet2)")
    exp.add_argument("--format", choices=("opendrive", "commonroad", "lanelet2"), default="opendrive",
                     help="commonroad and lanelet2 need the clients' environment "
                          "(python -m flyover.clients.setup)")
    exp.add_argument("--plan", metavar="FILE.png", help="also draw the plan view here")
    exp.set_defaults(func=_export)


def _validate(args: argparse.Namespace) -> int:
    from flyover.geometry.model import read_geometry  # noqa: PLC0415
    from flyover.opendrive.validate import validate_xodr  # noqa: PLC0415

    failed = 0
    for f in args.files:
        gpath = Path(args.geometry) if args.geometry else Path(f).with_name("geometry.json")
        geometry = read_geometry(gpath) if gpath.exists() else None
        results, times, warnings = validate_xodr(f, geometry=geometry, net_out=args.net,
                                                 run_qc=not args.no_qc)
        bad = [r for r in results if not r.ok]
        failed += bool(bad)
        print(f"{f}: {'OK' if not bad else 'FAILED'} ({len(results) - len(bad)}/{len(results)} checks)")
        for r in results:
            print(f"  {'ok  ' if r.ok else 'FAIL'} {r.check:<10} {r.detail}")
        for w in warnings[:5]:
            print(f"  netconvert {w}")
        if len(warnings) > 5:
            print(f"  ... {len(warnings) - 5} more netconvert warnings")
    sys.stdout.flush()
    return 1 if failed else 0


def _export(args: argparse.Namespace) -> int:
    from flyover.geometry.model import read_geometry  # noqa: PLC0415
    from flyover.opendrive.writer import write_xodr  # noqa: PLC0415

    g = read_geometry(args.geometry)
    if args.format != "opendrive":
        return _export_client(args, g)
    out = Path(args.output) if args.output else Path(args.geometry).with_name("interchange.xodr")
    write_xodr(g, out)
    if args.plan:
        from flyover.opendrive.plan import draw_plan  # noqa: PLC0415
        from flyover.opendrive.reader import read_xodr  # noqa: PLC0415

        draw_plan(read_xodr(out), args.plan)
    print(out)
    return 0


def _export_client(args: argparse.Namespace, g) -> int:
    """``--format commonroad|lanelet2``: our .xodr through the clients, checked on load."""
    import tempfile  # noqa: PLC0415

    from flyover.clients.tools import run_clients  # noqa: PLC0415
    from flyover.opendrive.writer import write_xodr  # noqa: PLC0415
    from flyover.topology.io import atomic_write  # noqa: PLC0415

    suffix = {"commonroad": "interchange.cr.xml", "lanelet2": "interchange.osm"}[args.format]
    out = Path(args.output) if args.output else Path(args.geometry).with_name(suffix)
    with tempfile.TemporaryDirectory() as tmp:
        xodr, made = Path(tmp) / "interchange.xodr", Path(tmp) / suffix
        write_xodr(g, xodr)
        [answer] = run_clients([{"xodr": xodr, args.format: made}])
        step = answer.get(args.format) or answer["conversion"]
        if not answer["conversion"]["ok"] or not step.get("ok"):
            print(f"{args.geometry}: {args.format} export failed: "
                  f"{step.get('error') or step.get('load_errors')} ({step.get('where', '')})",
                  file=sys.stderr)
            return 1
        atomic_write(out, made.read_bytes())
    print(out)
    return 0
