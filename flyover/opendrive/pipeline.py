"""What the workflow's export rules call: one interchange at a time, then the table.

``results/validation.parquet`` has one row per interchange × check:
``class_id, sample, check, ok, detail``; the checks are :data:`PIPELINE_CHECKS`:
``export`` (writing the ``.xodr`` from ``geometry.json``), then
:data:`flyover.opendrive.validate.CHECKS`, then ``clearance`` (no same-level
conflict anywhere in ``geometry.json``, by :mod:`flyover.geometry.check`).

An interchange that cannot be written is rows, not a missing table: the
validation of one interchange reads only its ``geometry.json`` and writes the
``.xodr`` itself (the same writer and options as rule ``export_xodr``, hence
the same bytes), so a failed ``export_xodr`` or ``export_sumo`` job does not
keep ``results/validation.parquet`` from being built; the failure is its
``export`` (or ``netconvert``) row, with the one-line error naming the file
and element.
"""

from __future__ import annotations

import io
import logging
import os
import tempfile
from pathlib import Path
from typing import Iterable, Mapping

import pyarrow as pa
import pyarrow.parquet as pq

from flyover.errors import FlyoverError
from flyover.geometry.model import read_geometry
from flyover.opendrive.validate import CHECKS, CheckResult, validate_xodr
from flyover.opendrive.writer import ExportOptions, xodr_bytes

__all__ = ["VALIDATION_SCHEMA", "PIPELINE_CHECKS", "export_options", "export_interchange",
           "validate_interchange", "clearance_check", "collect_validation"]

log = logging.getLogger(__name__)

VALIDATION_SCHEMA = pa.schema([("class_id", pa.string()), ("sample", pa.int32()),
                               ("check", pa.string()), ("ok", pa.bool_()), ("detail", pa.string())])
#: the checks of every interchange in ``results/validation.parquet``, in row order
PIPELINE_CHECKS = ("export",) + CHECKS + ("clearance",)


def export_options(section: Mapping) -> ExportOptions:
    """:class:`ExportOptions` from the workflow config's ``export`` section."""
    sec = dict(section)
    kinds = {"opendrive_minor": int}
    return ExportOptions(**{k: kinds.get(k, float)(v) for k, v in sec.items()
                            if k in ExportOptions.__dataclass_fields__})


def _write(geometry: str | os.PathLike, options: ExportOptions | None):
    """``geometry.json`` → (geometry, .xodr bytes); errors name the geometry file."""
    try:
        g = read_geometry(geometry)
        return g, xodr_bytes(g, options)
    except FlyoverError as exc:
        raise exc.located(str(geometry)) from None


def export_interchange(geometry: str | os.PathLike, xodr: str | os.PathLike,
                       plan: str | os.PathLike | None = None,
                       options: ExportOptions | None = None) -> None:
    """``geometry.json`` → ``interchange.xodr`` (and ``plan.png``), all or nothing.

    Both files are made in memory first and each is written atomically; on
    any error neither is left behind.
    """
    from flyover.topology.io import atomic_write  # noqa: PLC0415

    g, data = _write(geometry, options)
    try:
        if plan is not None:
            from flyover.opendrive.plan import draw_plan  # noqa: PLC0415
            from flyover.opendrive.reader import read_xodr  # noqa: PLC0415

            draw_plan(read_xodr(io.BytesIO(data)), plan, title=f"{g.class_id} sample {g.sample}")
        atomic_write(xodr, data)
    except BaseException:
        for p in (plan, xodr):
            if p is not None:
                Path(p).unlink(missing_ok=True)
        raise


def clearance_check(geometry: str | os.PathLike, clearance_m: float = 5.5) -> CheckResult:
    """The ``clearance`` row: every ramp's lane centre, every metre, clear of every road
    and ramp it is not at least ``clearance_m`` above or below."""
    from flyover.geometry.check import same_level_conflicts  # noqa: PLC0415

    try:
        g = read_geometry(geometry)
    except FlyoverError as exc:
        return CheckResult("clearance", False, f"not run: {exc.one_line()}")
    found = same_level_conflicts(g, clearance_m=clearance_m)
    if not found:
        return CheckResult("clearance", True, f"{len(g.ramps)} ramps clear of every road and "
                           f"ramp at their level (lane centres every 1 m, {clearance_m:g} m)")
    parts = [f"{c.ramp} meets {c.other} at s={c.s_m:.0f} m for {c.length_m:.1f} m "
             f"({c.dz_m:.2f} m apart in height)" for c in found[:5]]
    more = f"; and {len(found) - 5} more" if len(found) > 5 else ""
    return CheckResult("clearance", False, f"{geometry}: " + "; ".join(parts) + more)


def validate_interchange(geometry: str | os.PathLike, table: str | os.PathLike, *,
                         class_id: str, sample: int, options: ExportOptions | None = None,
                         run_qc: bool = True, clearance_m: float = 5.5) -> list[dict]:
    """Write one interchange from ``geometry.json`` and validate it: its rows, written to ``table``.

    The ``.xodr`` is written to a temporary folder as ``interchange.xodr``
    (details name it as the file beside ``geometry.json``). When it cannot be
    written the ``export`` row fails with the one-line error and every other
    check fails as not run; the table is written all the same.
    """
    from flyover.topology.tables import write_parquet  # noqa: PLC0415

    folder = Path(geometry).parent
    with tempfile.TemporaryDirectory(prefix="flyover-validate-") as tmp:
        xodr = Path(tmp) / "interchange.xodr"
        try:
            g, data = _write(geometry, options)
            xodr.write_bytes(data)
        except FlyoverError as exc:
            results = _not_written(exc.one_line())
        except Exception as exc:  # noqa: BLE001 - one interchange's failure is its rows, not a lost table
            log.exception("export of %s failed", geometry)
            results = _not_written(f"{geometry}: {type(exc).__name__}: {exc}")
        else:
            checked, _, warnings = validate_xodr(xodr, geometry=g, options=options, run_qc=run_qc)
            for w in warnings:
                log.info("netconvert %s", w)
            minor = (options or ExportOptions()).opendrive_minor
            results = [CheckResult("export", True, f"{folder / xodr.name}: OpenDRIVE 1.{minor}, "
                                   f"{data.count(b'<road ')} roads, {data.count(b'<junction ')} "
                                   f"junctions, {len(data)} bytes")]
            results += [CheckResult(r.check, r.ok, r.detail.replace(f"{tmp}{os.sep}", f"{folder}{os.sep}"))
                        for r in checked]
    results.append(clearance_check(geometry, clearance_m))
    rows = [_row(class_id, sample, r) for r in results]
    for r in results:
        failed = not r.ok and not r.detail.startswith("not run")
        (log.error if failed else log.info)("%s %s: %s", r.check, "ok" if r.ok else "FAILED", r.detail)
    write_parquet(rows, VALIDATION_SCHEMA, table)
    return rows


def _not_written(error: str) -> list[CheckResult]:
    return [CheckResult("export", False, error)] + [
        CheckResult(c, False, "not run: no OpenDRIVE file (export failed)") for c in CHECKS]


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
