"""What the workflow has made so far, per stage, and where to look: ``flyover status``.

Read from the tables under ``results/`` (the per-class tables while a run is
going on, so it works in the middle of one and after one that failed). The
workflow prints it when it ends; ``flyover status`` prints it at any time.

Example
-------
>>> print("\\n".join(status_lines("no-such-folder")))
no-such-folder: nothing built yet (run `./dev run`)
"""

from __future__ import annotations

import os
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

__all__ = ["StageStatus", "stage_status", "status_lines", "register"]


@dataclass(frozen=True)
class StageStatus:
    """One stage: how many interchanges of how many are done, and what went wrong."""

    stage: str
    done: int
    total: int
    classes_done: int
    classes_total: int
    problems: tuple[str, ...]
    tables: str


def _read(paths: list[Path], columns: list[str]) -> list[dict]:
    import pyarrow.parquet as pq  # noqa: PLC0415 - keep `flyover --help` light

    rows: list[dict] = []
    for p in paths:
        try:
            rows += pq.read_table(str(p), columns=columns).to_pylist()
        except (OSError, ValueError, KeyError):
            continue  # being written or from an older version: counted as not done
    return rows


def stage_status(results: str | os.PathLike = "results") -> list[StageStatus]:
    """Per stage (sampling, geometry, export, validation, and any later per-class stage), what is done."""
    root = Path(results)
    features = sorted((root / "features").glob("c*.parquet"))
    samples = {(r["class_id"], r["sample"]) for r in _read(features, ["class_id", "sample"])}
    n_classes = len(features)
    out = [StageStatus("sampling", len(samples), len(samples), n_classes, n_classes, (),
                       "results/features/, results/coverage.parquet")]

    geo = sorted((root / "geometry").glob("c*.parquet"))
    rows = _read(geo, ["class_id", "sample", "ok", "infeasible"])
    built = {(r["class_id"], r["sample"]) for r in rows
             if not (r["infeasible"] or "").startswith("not built")}
    problems = []
    if rows:
        ok = sum(r["ok"] for r in rows)
        problems.append(f"{ok}/{len(rows)} ramps within their targets")
        infeasible = sum(bool(r["infeasible"]) and not r["infeasible"].startswith("not built")
                         for r in rows)
        if infeasible:
            problems.append(f"{infeasible} ramps recorded infeasible")
        failed = {(r["class_id"], r["sample"]) for r in rows} - built
        if failed:
            problems.append(f"{len(failed)} interchanges not built")
    out.append(StageStatus("geometry", len(built), len(samples), len(geo), n_classes,
                           tuple(problems), "results/geometry.parquet"))

    for stage, tables in (("export", "results/interchanges/{class_id}/{sample}/, "
                                     "results/validation.parquet (export, netconvert)"),
                          ("validation", "results/validation.parquet")):
        paths = sorted((root / stage).glob("c*.parquet"))
        rows = _read(paths, ["class_id", "sample", "check", "ok"])
        per: dict[tuple, bool] = {}
        for r in rows:
            key = (r["class_id"], r["sample"])
            per[key] = per.get(key, True) and bool(r["ok"])
        bad = Counter(r["check"] for r in rows if not r["ok"])
        problems = [f"{sum(per.values())}/{len(per)} interchanges pass every check"] if per else []
        if bad:
            problems.append("failed: " + ", ".join(f"{c} {n}" for c, n in sorted(bad.items())))
        out.append(StageStatus(stage, len(per), len(samples), len(paths), n_classes,
                               tuple(problems), tables))

    paths = sorted((root / "throughput").glob("c*.parquet"))
    if paths:
        rows = _read(paths, ["class_id", "sample", "ok", "flagged"])
        problems = [f"{len(rows)} runs"]
        if bad := sum(not r["ok"] for r in rows):
            problems.append(f"{bad} failed")
        if flagged := sum(bool(r["ok"] and r["flagged"]) for r in rows):
            problems.append(f"{flagged} flagged (teleports or collisions)")
        done = {(r["class_id"], r["sample"]) for r in rows}
        out.append(StageStatus("throughput", len(done), len(done), len(paths), n_classes,
                               tuple(problems), "results/throughput.parquet, "
                                                "results/throughput_stats.parquet, results/figures/"))
    for plugin in sorted(p for p in (root / "plugins").glob("*") if p.is_dir()):
        paths = sorted(plugin.glob("c*.parquet"))
        rows = _read(paths, ["class_id", "sample", "completed"])
        done = {(r["class_id"], r["sample"]) for r in rows}
        problems = [f"{sum(bool(r['completed']) for r in rows)}/{len(rows)} rows completed"]
        out.append(StageStatus(plugin.name, len(done), len(samples), len(paths), n_classes,
                               tuple(problems), f"results/plugins/{plugin.name}/, `flyover query`"))
    return out


def status_lines(results: str | os.PathLike = "results") -> list[str]:
    """The status as lines of text, one per stage, with the tables to look in."""
    root = Path(results)
    if not (root / "classes.parquet").exists():
        return [f"{results}: nothing built yet (run `./dev run`)"]
    classes = _read([root / "classes.parquet"], ["city", "class_id"])
    rejected = _read([root / "rejected.parquet"], ["source_file"])
    n_cities = len({r["city"] for r in classes})
    lines = [f"{len(classes)} interchanges from {n_cities} {'city' if n_cities == 1 else 'cities'} in "
             f"{len({r['class_id'] for r in classes})} classes; {len(rejected)} inputs rejected "
             "(results/classes.parquet, results/rejected.parquet)"]
    for s in stage_status(root):
        lines.append(f"  {s.stage:<11} {s.done}/{s.total} interchanges "
                     f"({s.classes_done}/{s.classes_total} classes)"
                     + ("; " + "; ".join(s.problems) if s.problems else "") + f"  [{s.tables}]")
    return lines


def register(sub) -> None:
    """``flyover status [--results DIR]``."""
    p = sub.add_parser("status", help="what the workflow has built so far, per stage",
                       description="Per stage, how many interchanges of how many are done, "
                                   "what failed, and the tables to look in.")
    p.add_argument("--results", default="results", help="the results folder (default: results)")
    p.set_defaults(func=_run)


def _run(args) -> int:
    import sys  # noqa: PLC0415

    sys.stdout.write("\n".join(status_lines(args.results)) + "\n")
    return 0
