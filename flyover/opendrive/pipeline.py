"""What the workflow's export rules call: one interchange at a time, then the table.

``results/validation.parquet`` has one row per interchange × check:
``class_id, sample, check, ok, detail`` (checks: :data:`flyover.opendrive.validate.CHECKS`).
"""

from __future__ import annotations

import logging
import os
from typing import Iterable, Mapping

import pyarrow as pa
import pyarrow.parquet as pq

from flyover.geometry.model import read_geometry
from flyover.opendrive.validate import CheckResult, validate_xodr
from flyover.opendrive.writer import ExportOptions, write_xodr

__all__ = ["VALIDATION_SCHEMA", "export_options", "export_interchange", "validate_interchange",
           "collect_validation"]

log = logging.getLogger(__name__)

VALIDATION_SCHEMA = pa.schema([("class_id", pa.string()), ("sample", pa.int32()),
                               ("check", pa.string()), ("ok", pa.bool_()), ("detail", pa.string())])


def export_options(config: Mapping) -> ExportOptions:
    """:class:`ExportOptions` from the workflow config's ``export`` section."""
    sec = dict(config.get("export", {}))
    kinds = {"opendrive_minor": int}
    return ExportOptions(**{k: kinds.get(k, float)(v) for k, v in sec.items()
                            if k in ExportOptions.__dataclass_fields__})


def export_interchange(geometry: str | os.PathLike, xodr: str | os.PathLike,
                       plan: str | os.PathLike | None = None,
                       options: ExportOptions | None = None) -> None:
    """``geometry.json`` → ``interchange.xodr`` (and ``plan.png``)."""
    g = read_geometry(geometry)
    write_xodr(g, xodr, options)
    if plan is not None:
        from flyover.opendrive.plan import draw_plan  # noqa: PLC0415
        from flyover.opendrive.reader import read_xodr  # noqa: PLC0415

        draw_plan(read_xodr(xodr), plan, title=f"{g.class_id} sample {g.sample}")


def validate_interchange(xodr: str | os.PathLike, geometry: str | os.PathLike, table: str | os.PathLike,
                         *, run_qc: bool = True, class_id: str | None = None,
                         sample: int | None = None) -> list[dict]:
    """Validate one interchange into its rows of the validation table (written to ``table``).

    ``class_id``/``sample`` default to the geometry's own (the workflow passes
    its folder names).
    """
    from flyover.topology.tables import write_parquet  # noqa: PLC0415

    g = read_geometry(geometry)
    results, times, warnings = validate_xodr(xodr, geometry=g, run_qc=run_qc)
    for w in warnings:
        log.info("netconvert %s", w)
    cid = g.class_id if class_id is None else class_id
    smp = g.sample if sample is None else int(sample)
    rows = [_row(cid, smp, r) for r in results]
    for r in results:
        (log.info if r.ok else log.error)("%s %s: %s", r.check, "ok" if r.ok else "FAILED", r.detail)
    write_parquet(rows, VALIDATION_SCHEMA, table)
    return rows


def _row(class_id: str, sample: int, r: CheckResult) -> dict:
    return {"class_id": class_id, "sample": int(sample), "check": r.check, "ok": bool(r.ok),
            "detail": r.detail}


def collect_validation(tables: Iterable[str | os.PathLike], out: str | os.PathLike) -> int:
    """Concatenate per-interchange tables into ``results/validation.parquet`` (sorted)."""
    from flyover.topology.tables import write_parquet  # noqa: PLC0415

    rows = []
    for t in tables:
        rows += pq.read_table(str(t), schema=VALIDATION_SCHEMA).to_pylist()
    rows.sort(key=lambda r: (r["class_id"], r["sample"], r["check"]))
    write_parquet(rows, VALIDATION_SCHEMA, out)
    return len(rows)
