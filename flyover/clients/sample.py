"""CommonRoad's map verifier on a seeded sample of the exported interchanges (the main job).

The verifier takes 1-2 min an interchange with every formula, so the workflow runs it on
one interchange of the whole run (:func:`pick_sample`: seeded, from the smallest tenth of
the interchanges the export stage wrote), with the formulas that cost most and check least on one-way
carriageways left out (config ``validation.clients_sample.exclude_formulas``); the slow
test runs it on every catalog design with every formula. ``results/clients_sample.parquet``
has the rows of :data:`flyover.opendrive.pipeline.VALIDATION_SCHEMA` (``class_id, sample,
check, ok, detail``): ``commonroad_conversion`` and ``commonroad_verifier``. Without the
clients' environment (``.venv-clients``) the rows say so (``ok`` null) and the run goes on.
"""

from __future__ import annotations

import logging
import math
import os
import random
from pathlib import Path
from typing import Callable, Iterable, Sequence

import pyarrow.parquet as pq

from flyover.clients.tools import ClientsError, find_clients_python, run_clients

__all__ = ["CONVERSION_TYPES", "pick_sample", "verify_sample"]

log = logging.getLogger(__name__)

#: verifier error types that the conversion makes, not our geometry (README "Compatibility"):
#: it evaluates the reference line at s rounded to 1 mm, and its join/split step re-draws
#: the borders of lanes that open from (close to) zero width; bounds "intersect" where a
#: lane is zero wide by design (the end of a taper)
CONVERSION_TYPES = frozenset({
    "polylines_intersection", "connections_predecessor", "connections_successor",
    "connections_left_forking_adj", "connections_right_forking_adj",
    "connections_left_merging_adj", "connections_right_merging_adj"})


def pick_sample(export_tables: Iterable[str | os.PathLike], seed: int,
                size: Callable[[str, int], float] | None = None) -> tuple[str, int] | None:
    """One ``(class_id, sample)`` among the interchanges whose export succeeded, seeded.

    With ``size`` (``(class_id, sample) -> a measure of the interchange``, e.g. its
    .xodr's bytes), the pick is among the smallest tenth of them (at least one): the
    verifier's time grows with the square of the lanelets, from ~30 s on a T to many
    minutes on a cloverleaf with collector roads, and the main job has a budget. Every
    design is verified in the slow tests.

    The same tables and seed give the same pick, whatever the order of the tables.
    ``None`` when nothing was exported.
    """
    from flyover.opendrive.pipeline import VALIDATION_SCHEMA  # noqa: PLC0415

    done = sorted({(r["class_id"], int(r["sample"]))
                   for t in export_tables
                   for r in pq.read_table(str(t), schema=VALIDATION_SCHEMA).to_pylist()
                   if r["check"] == "export" and r["ok"]})
    if done and size is not None:
        done = sorted(sorted(done, key=lambda cs: (size(*cs), cs))[:max(1, len(done) // 10)])
    return random.Random(seed).choice(done) if done else None


def _rows(class_id: str, sample: int, answer: dict, exclude: Sequence[str]) -> list[dict]:
    conv, ver = answer.get("conversion", {}), answer.get("verifier", {})
    rows = [{"class_id": class_id, "sample": sample, "check": "commonroad_conversion",
             "ok": bool(conv.get("ok")),
             "detail": (f"{conv['lanelets']} lanelets"
                        if conv.get("ok") else f"{conv.get('error')} at {conv.get('where')}")}]
    if not conv.get("ok"):
        rows.append({"class_id": class_id, "sample": sample, "check": "commonroad_verifier",
                     "ok": False, "detail": "not run: the conversion failed"})
        return rows
    if not ver.get("ok"):
        detail, ok = f"{ver.get('error')} at {ver.get('where')}", False
    else:
        errors, crashed = ver["errors"], ver.get("crashed", {})
        other = sorted(set(errors) - CONVERSION_TYPES)
        counts = ", ".join(f"{k}={n}" for k, n in sorted(errors.items())) or "no errors"
        detail = (f"{counts}; {'NOT ' if other else ''}only the conversion's types"
                  + (f" (other: {', '.join(other)})" if other else "")
                  + f"; {ver['formulas']} formulas"
                  + (f", left out: {', '.join(exclude)}" if exclude else ""))
        wrong_sides = ver.get("boundary_sides", {}).get("wrong", [])
        if crashed:  # the verifier's own crash; its known one is answered by our check
            detail += "; crashed: " + ", ".join(f"{k} ({e['error']})" for k, e in crashed.items())
            if "boundary_sides" in ver:
                detail += f"; boundary sides checked instead: {len(wrong_sides)} wrong"
        ok = not other and not wrong_sides and set(crashed) <= {"left_right_boundary_assignment"}
    rows.append({"class_id": class_id, "sample": sample, "check": "commonroad_verifier",
                 "ok": ok, "detail": detail})
    return rows


def verify_sample(export_tables: Iterable[str | os.PathLike], out: str | os.PathLike, *,
                  seed: int, folder: str = "results/interchanges/{class_id}/{sample}",
                  exclude: Sequence[str] = (), python: Path | None = None) -> list[dict]:
    """Pick one exported interchange (:func:`pick_sample`), convert and verify it, write ``out``.

    Parameters
    ----------
    export_tables
        The export stage's per-class tables (``results/export/{class_id}.parquet``).
    out
        ``results/clients_sample.parquet``: two rows (:data:`VALIDATION_SCHEMA`).
    seed
        Picks the interchange.
    folder
        Where an interchange's ``interchange.xodr`` lies.
    exclude
        Formula ids of the verifier left out.
    python
        The clients' environment's python (default: :func:`find_clients_python`).

    Returns
    -------
    list of dict
        The rows written; ``ok`` is None on both when the clients' environment is
        missing (``detail`` says where it was looked for and how to install it).
    """
    from flyover.opendrive.pipeline import VALIDATION_SCHEMA  # noqa: PLC0415
    from flyover.topology.tables import write_parquet  # noqa: PLC0415

    def xodr_bytes(class_id: str, sample: int) -> float:
        path = Path(folder.format(class_id=class_id, sample=sample)) / "interchange.xodr"
        return float(path.stat().st_size) if path.exists() else math.inf

    picked = pick_sample(export_tables, seed, size=xodr_bytes)
    rows: list[dict] = []
    if picked is None:
        log.warning("clients' sample: no interchange was exported; nothing to verify")
    else:
        class_id, sample = picked
        xodr = Path(folder.format(class_id=class_id, sample=sample)) / "interchange.xodr"
        try:
            py = python or find_clients_python()
        except ClientsError as e:
            note = f"skipped: {e.one_line()}"
            log.warning("clients' sample %s/%s %s", class_id, sample, note)
            rows = [{"class_id": class_id, "sample": sample, "check": c, "ok": None, "detail": note}
                    for c in ("commonroad_conversion", "commonroad_verifier")]
        else:
            log.info("clients' sample: %s (seed %d), CommonRoad conversion and map verifier",
                     xodr, seed)
            [answer] = run_clients([{"xodr": xodr, "verify": True,
                                     "verify_exclude": list(exclude)}], python=py)
            rows = _rows(class_id, sample, answer, exclude)  # no seconds: same bytes every run
            log.info("%s: seconds %s", xodr, {k: round(v, 1) for k, v in answer["seconds"].items()})
            for r in rows:
                (log.info if r["ok"] else log.error)("%s %s: %s", xodr, r["check"], r["detail"])
    write_parquet(rows, VALIDATION_SCHEMA, out)
    return rows
