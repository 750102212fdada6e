"""``flyover throughput NET.xml``: run one interchange as a user would."""

from __future__ import annotations

import argparse
import json
import math
import sys

__all__ = ["register"]


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "throughput", help="simulate one SUMO network: stable throughput and its counts",
        description="Drive every entrance -> exit movement of an interchange (geometry.json and "
                    "interchange.xodr beside NET.xml; else every entry to every exit) at DENSITY "
                    "veh/h each through SUMO (libsumo), and print the stable throughput, when "
                    "entering and leaving balance, and the vehicles not inserted, teleported or "
                    "collided. Exit status 1 when a run fails or is flagged.")
    p.add_argument("net", metavar="NET.xml")
    p.add_argument("--density", type=float, action="append", metavar="VEH_H",
                   help="vehicles per hour per movement (repeat for several; default: config's "
                        "throughput.densities)")
    p.add_argument("--duration", type=float, metavar="S", help="simulated seconds (default 2000)")
    p.add_argument("--seed", type=int, help="master seed (default: config's seed)")
    p.add_argument("--uturns", action="store_true", help="include U-turns onto the same expressway")
    p.add_argument("--configfile", metavar="YAML", help="configuration (default config/config.yaml)")
    p.add_argument("--json", action="store_true", help="print the rows as JSON")
    p.set_defaults(func=_throughput)


def _throughput(args: argparse.Namespace) -> int:
    from dataclasses import replace  # noqa: PLC0415
    from pathlib import Path  # noqa: PLC0415

    from flyover.config import load_config  # noqa: PLC0415
    from flyover.traffic.batch import run_interchange  # noqa: PLC0415
    from flyover.traffic.settings import ThroughputSettings  # noqa: PLC0415

    settings = ThroughputSettings.from_config(load_config(args.configfile))
    kw = {}
    if args.density:
        kw["densities"] = tuple(args.density)
    if args.duration:
        kw["duration_s"] = args.duration
    if args.seed is not None:
        kw["seed"] = args.seed
    if args.uturns:
        kw["uturns"] = True
    settings = replace(settings, **kw)
    net = Path(args.net)
    class_id, sample = net.parent.parent.name or "net", 0
    if net.parent.name.isdigit():
        sample = int(net.parent.name)
    rows, _ = run_interchange(net, settings, class_id=class_id, sample=sample)
    if args.json:
        json.dump([{k: (None if isinstance(v, float) and math.isnan(v) else v)
                    for k, v in r.items()} for r in rows], sys.stdout, indent=2)
        print()
    else:
        for r in rows:
            if not r["ok"]:
                print(f"{r['density_veh_h']:g} veh/h: failed: {r['reason']}")
                continue
            print(f"{r['density_veh_h']:g} veh/h x {r['movements']} movements "
                  f"(demand {r['demand_veh_h']:.0f} veh/h): throughput {r['throughput_veh_h']:.0f} "
                  f"veh/h from {r['stable_from_s']:.0f} s"
                  f"{'' if r['balanced'] else ' (NOT balanced: the network fills up)'}; "
                  f"{r['entered']} entered, {r['left']} left, {r['not_inserted']} not inserted, "
                  f"{r['running_end']} in the network at the end, {r['teleports']} teleports "
                  f"({r['teleports_wrong_lane']} wrong lane, {r['teleports_jam']} jam), "
                  f"{r['collisions']} collisions")
    return 1 if any(not r["ok"] or r["flagged"] for r in rows) else 0
