"""The AV-research clients on catalog interchanges: result and seconds per client.

Usage::

    .venv/bin/python benchmarks/clients.py                       # every design, feature set 0
    .venv/bin/python benchmarks/clients.py --variants 0 1 --verify
    .venv/bin/python benchmarks/clients.py --designs trumpet j1 --verify
    .venv/bin/python benchmarks/clients.py --xodr old/*.xodr --verify   # files as they are
    .venv/bin/python benchmarks/clients.py --attribution --no-clients   # where verifier errors come from
    .venv/bin/python benchmarks/clients.py --verify --exclude potential_left_opposite_dir_parallel_adj \
        potential_right_opposite_dir_parallel_adj             # the main job's sample formulas

Each catalog design is laid out with fixed features (``flyover.clients.designs``)
and written with the current writer; ``--xodr`` takes existing files instead
(e.g. written by an earlier commit, for before/after figures; no movement check
then). Every client runs in the clients' environment, one process for all
files: CommonRoad Scenario Designer's conversion (and ``--verify``: its map
verifier, verification only), the CommonRoad file written and read back, its
Lanelet2 export loaded by ``lanelet2`` with a routing graph, pyopendrive,
pyxodr. Printed per interchange: seconds per client, verifier errors per
type with the largest boundary gap of the flagged links in the converted map,
our own lanes left unlinked and our largest lane-border gap at road links
(from the .xodr), and whether Lanelet2 routes exactly the topology's
movements. ``--attribution``: the verifier's connection, adjacency and
polyline formulas re-evaluated on the conversion as it is, with its 1 mm
rounding of s neutralised, and with its join/split step neutralised too (the
tests check that the first equals the verifier's counts). Then the totals per
error type and mean/max seconds per client.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
from pathlib import Path

from flyover.clients.designs import catalog_geometry, catalog_names
from flyover.clients.links import dangling_lanes, link_gaps
from flyover.clients.tools import routed_movements, run_clients, two_movement_trips
from flyover.opendrive.reader import read_xodr
from flyover.opendrive.validate import movements
from flyover.opendrive.writer import xodr_bytes


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--designs", nargs="*", default=None)
    ap.add_argument("--variants", nargs="*", type=int, default=[0])
    ap.add_argument("--xodr", nargs="*", default=None, help="run on these files as they are")
    ap.add_argument("--verify", action="store_true", help="also run CommonRoad's map verifier")
    ap.add_argument("--exclude", nargs="*", default=[], help="verifier formulas left out")
    ap.add_argument("--attribution", action="store_true",
                    help="verifier formulas with the converter's own steps neutralised")
    ap.add_argument("--no-clients", action="store_true",
                    help="only the conversion (and what is asked): no Lanelet2, pyopendrive, pyxodr")
    args = ap.parse_args(argv)
    tmp = Path(tempfile.mkdtemp(prefix="flyover-clients-"))
    items = []  # (label, path, geometry or None)
    if args.xodr:
        items = [(Path(p).stem, Path(p), None) for p in args.xodr]
    else:
        for name in args.designs or catalog_names():
            for v in args.variants:
                g = catalog_geometry(name, v)
                path = tmp / f"{name}_{v}.xodr"
                path.write_bytes(xodr_bytes(g))
                items.append((f"{name}_{v}", path, g))
    full = not args.no_clients
    jobs = [{"xodr": p, "commonroad": full and tmp / f"{lab}.cr.xml",
             "lanelet2": full and tmp / f"{lab}.osm", "verify": args.verify,
             "verify_exclude": args.exclude, "attribution": args.attribution, "routing": full,
             "pyopendrive": full, "pyxodr": full} for lab, p, _ in items]
    answers = run_clients(jobs)
    seconds: dict[str, list[float]] = {}
    totals: dict[str, int] = {}
    attributed: dict[str, dict[str, int]] = {}
    rounding_max = 0.0
    converted = routed_ok = 0
    for (label, path, g), a in zip(items, answers):
        net = read_xodr(path)
        gaps = [gap for *_, gap in link_gaps(net)]
        for k, s in a["seconds"].items():
            seconds.setdefault(k, []).append(s)
        conv = a["conversion"]
        converted += conv["ok"]
        line = [f"{label:<22}", f"dangling {len(dangling_lanes(net)):>2}",
                f"our max link gap {max(gaps, default=0.0):.1e} m"]
        if not conv["ok"]:
            line.append(f"CONVERSION FAILED {conv['error']} at {conv['where']}")
        elif full:
            ll2 = a["lanelet2"]
            line.append(f"lanelets {conv['lanelets']:>3}")
            line.append(f"ll2 {'ok' if ll2.get('ok') and not ll2.get('routing_errors') else 'FAIL'}")
            if g is not None and ll2.get("ok"):
                routed, wanted = set(routed_movements(ll2, net)), set(movements(g))
                routed_ok += routed == wanted
                extra = routed - wanted
                trips = two_movement_trips(extra, wanted)
                line.append(f"routes==movements {routed == wanted}")
                if routed != wanted:
                    line.append(f"missing {sorted(wanted - routed)} extra {sorted(extra)} "
                                f"(two movements through {sorted(set(trips.values()))}: "
                                f"{len(trips)}/{len(extra)})")
        if conv["ok"] and args.attribution:
            at = a["attribution"]
            if at["ok"]:
                for variant in ("stock", "exact_s", "exact_s_no_join_split"):
                    tot = attributed.setdefault(variant, {})
                    for k, n in at[variant]["errors"].items():
                        tot[k] = tot.get(k, 0) + n
                rounding_max = max(rounding_max, at["rounding_max_gap_m"])
                line.append("formulas as converted {} / exact s {} / exact s, no join-split {}; "
                            "rounding errors {} (largest gap {:.1e} m)".format(
                                at["stock"]["errors"], at["exact_s"]["errors"],
                                at["exact_s_no_join_split"]["errors"], at["rounding_errors"],
                                at["rounding_max_gap_m"]))
            else:
                line.append(f"attribution FAILED {at['error']}")
        if conv["ok"]:
            if args.verify:
                v = a["verifier"]
                if v["ok"]:
                    for k, n in v["errors"].items():
                        totals[k] = totals.get(k, 0) + n
                    gaps_cr = {k: f"{x:.1e}" for k, x in v["connection_gaps_m"].items()}
                    line.append(f"verifier {v['errors']} gaps in CR map {gaps_cr}")
                    for it in v.get("intersections", []):
                        line.append("intersecting bounds: lanelet {lanelet} width {width_start_m:.3f}"
                                    " .. {width_end_m:.3f} m, least inside {min_inner_width_m}".format(**it))
                else:
                    line.append(f"verifier FAILED {v['error']}")
        if full:
            line.append(f"pyopendrive {'ok' if a['pyopendrive']['ok'] else 'FAIL'}")
            line.append(f"pyxodr {'ok' if a['pyxodr']['ok'] else 'FAIL'}")
        line.append("s: " + " ".join(f"{k} {s:.1f}" for k, s in a["seconds"].items()))
        print("  ".join(line), flush=True)
    n = len(items)
    print(f"\nconverted {converted}/{n}" + (f"; Lanelet2 routes == movements {routed_ok}/{n}"
                                            if full and not args.xodr else ""))
    if args.verify:
        print("verifier errors per type (all files):", dict(sorted(totals.items())))
    for variant, tot in attributed.items():
        print(f"formulas, {variant}: {dict(sorted(tot.items()))}")
    if attributed:
        print(f"largest gap of an error that the 1 mm rounding alone makes: {rounding_max:.2e} m")
    for k, v in seconds.items():
        print(f"{k:<12} mean {statistics.mean(v):6.1f} s  max {max(v):6.1f} s per interchange")
    return 0


if __name__ == "__main__":
    sys.exit(main())
