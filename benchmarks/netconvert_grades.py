"""netconvert's grade warnings on exported interchanges: where SUMO's network gets steep.

netconvert flattens each junction it builds from an OpenDRIVE junction (a diverge or a
merge) and cuts the roads at the junction's shape; where a ramp's height there is not its
parent's (it climbs from its split point while it still runs beside its parent), the first
(last) stretch of its lane shapes rises by the difference over a few metres and netconvert
warns ``Edge '…' has a grade of N%``. This script counts those warnings, independently of
the geometry stage's own measures: the real ``netconvert`` (the ``eclipse-sumo`` wheel,
``sumolib.checkBinary``) run on each interchange's ``.xodr`` as the export stage runs it.

Input: directories of ``{class_id}/{sample}/geometry.json`` (``benchmarks/geometry.py
--keep DIR`` writes them; ``results/interchanges`` is the workflow's). For each of the
first ``--samples`` samples of each class (by sample number), ``interchange.xodr`` is
written next to ``geometry.json`` with the export stage's code and options
(:func:`flyover.opendrive.pipeline.export_interchange`, config ``export``; an existing
``interchange.xodr`` is used as it is with ``--reuse``), then
:func:`flyover.sumo.netconvert.run_netconvert` (the export stage's command line) writes
``interchange.net.xml`` beside it.

Prints, per design: interchanges, those with a grade warning, the warnings, distinct
edges and distinct topology elements (ramps and roads, by the OpenDRIVE road's ``name``)
they fall on, the median and largest grade warned of, and every other netconvert warning
counted; then the elements with a warning, by design. ``--list N``: the first N warnings
verbatim with their interchange.

Run (from the repository root): ``PYTHONPATH=. .venv/bin/python
benchmarks/netconvert_grades.py /tmp/x --samples 16 --jobs 2``
"""

from __future__ import annotations

import argparse
import multiprocessing
import re
import statistics
from collections import Counter, defaultdict
from pathlib import Path

from lxml import etree

from flyover.config import load_config
from flyover.errors import FlyoverError
from flyover.opendrive.pipeline import export_interchange, export_options
from flyover.sumo.netconvert import run_netconvert
from flyover.topology.canonical import class_id as class_id_of
from flyover.topology.catalog import catalog_topologies

#: netconvert's grade warnings (``geometry.max-grade``, 10 % by default): of an edge's
#: shape, or of a connection's inside a junction
GRADE = re.compile(r"(Edge|Connection) '([^']+)' has a grade of ([0-9.eE+-]+)%")
#: netconvert's edge id of OpenDRIVE road N: ``N``, ``-N``, with ``#k`` when it is split
EDGE = re.compile(r"^-?(.+?)(?:#\d+)?$")


def road_names(xodr: Path) -> dict[str, str]:
    """OpenDRIVE road id → its ``name`` (the topology element it belongs to)."""
    root = etree.parse(str(xodr)).getroot()
    return {r.get("id"): r.get("name") or "" for r in root.iter("road")}


def element_of(edge: str, names: dict[str, str]) -> str:
    """The topology element of netconvert edge ``edge`` (``?`` if it names no road)."""
    m = EDGE.match(edge)
    return names.get(m.group(1), "?") if m else "?"


def measure(job: tuple[str, str, bool]) -> dict:
    """Export one ``geometry.json`` and run netconvert on it; its warnings, sorted."""
    geometry, options_key, reuse = job
    here = Path(geometry).parent
    xodr, net = here / "interchange.xodr", here / "interchange.net.xml"
    out = {"dir": str(here), "grades": [], "other": 0, "error": ""}
    try:
        if not (reuse and xodr.exists()):
            export_interchange(geometry, xodr, options=_OPTIONS[options_key])
        nc = run_netconvert(xodr, net)
    except FlyoverError as exc:
        out["error"] = exc.one_line()
        return out
    if not nc.ok:
        out["error"] = "; ".join(nc.errors)[:200]
    names = road_names(xodr)
    for w in nc.warnings:
        m = GRADE.search(w)
        if m:
            kind, ident = m.group(1), m.group(2)
            # a connection is named from its incoming edge's lane ("E_0->F_1")
            first = ident.split("->")[0].rsplit("_", 1)[0] if kind == "Connection" else ident
            element = element_of(first, names) + (" (connection)" if kind == "Connection" else "")
            out["grades"].append((ident, element, float(m.group(3)), w))
        else:
            out["other"] += 1
    return out


_OPTIONS: dict[str, object] = {}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dirs", nargs="+", type=Path, metavar="DIR",
                    help="folders of {class_id}/{sample}/geometry.json")
    ap.add_argument("--samples", type=int, default=0,
                    help="the first N samples of each class (by number; 0: all)")
    ap.add_argument("--jobs", type=int, default=1, help="worker processes")
    ap.add_argument("--reuse", action="store_true",
                    help="use an existing interchange.xodr instead of exporting again")
    ap.add_argument("--list", type=int, default=0, help="print the first N warnings verbatim")
    args = ap.parse_args()
    cfg = load_config("config/config.yaml")
    _OPTIONS["export"] = export_options(cfg.get("export", {}))
    design = {class_id_of(t): name for name, t in catalog_topologies().items()}
    jobs, where = [], {}
    for d in args.dirs:
        for cdir in sorted(p for p in d.iterdir() if p.is_dir()):
            samples = sorted((p for p in cdir.iterdir() if (p / "geometry.json").exists()),
                             key=lambda p: int(p.name) if p.name.isdigit() else p.name)
            for p in samples[: args.samples or None]:
                jobs.append((str(p / "geometry.json"), "export", args.reuse))
                where[str(p)] = (design.get(cdir.name, cdir.name), p.name)
    if args.jobs > 1:
        with multiprocessing.get_context("fork").Pool(args.jobs) as pool:
            results = list(pool.imap(measure, jobs))
    else:
        results = [measure(j) for j in jobs]
    per: dict[str, dict] = defaultdict(lambda: {"n": 0, "warned": 0, "warnings": 0,
                                                "edges": set(), "elements": Counter(),
                                                "grades": [], "other": 0, "failed": 0})
    listed = 0
    for r in results:
        name, sample = where[r["dir"]]
        row = per[name]
        row["n"] += 1
        row["other"] += r["other"]
        row["failed"] += bool(r["error"])
        if r["error"]:
            print(f"{name} sample {sample}: {r['error']}")
        if r["grades"]:
            row["warned"] += 1
        for edge, element, grade, text in r["grades"]:
            row["warnings"] += 1
            row["edges"].add((sample, edge))
            row["elements"][(sample, element)] += 1
            row["grades"].append(grade)
            if listed < args.list:
                print(f"  {name} sample {sample}: {text}")
                listed += 1
    print(f"{'design':18s} {'ics':>4s} {'warned':>6s} {'grade warnings':>14s} {'edges':>6s} "
          f"{'elements':>8s} {'median %':>9s} {'max %':>8s} {'other warnings':>14s} {'failed':>6s}")
    total = Counter()
    for name in sorted(per):
        row = per[name]
        g = row["grades"]
        print(f"{name:18s} {row['n']:4d} {row['warned']:6d} {row['warnings']:14d} "
              f"{len(row['edges']):6d} {len(row['elements']):8d} "
              f"{statistics.median(g) if g else 0:9.1f} {max(g) if g else 0:8.1f} "
              f"{row['other']:14d} {row['failed']:6d}")
        for k in ("n", "warned", "warnings", "other", "failed"):
            total[k] += row[k]
        total["edges"] += len(row["edges"])
        total["elements"] += len(row["elements"])
    print(f"{'all':18s} {total['n']:4d} {total['warned']:6d} {total['warnings']:14d} "
          f"{total['edges']:6d} {total['elements']:8d} {'':9s} {'':8s} {total['other']:14d} "
          f"{total['failed']:6d}")
    for name in sorted(per):
        els = per[name]["elements"]
        if els:
            kinds = Counter(e for _, e in els)
            print(f"{name}: " + ", ".join(f"sample {s} {e} ({n})" for (s, e), n in sorted(
                els.items(), key=lambda kv: (int(kv[0][0]) if kv[0][0].isdigit() else 0,
                                             kv[0][1])))
                  + " | by element: " + ", ".join(f"{e} {n}" for e, n in kinds.most_common()))


if __name__ == "__main__":
    main()
