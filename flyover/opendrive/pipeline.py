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
           "validate_interchange", "clearance_check", "collect_validation", "class_samples",
           "export_class", "validate_class"]

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
    except FileNotFoundError:
        return CheckResult("clearance", False, f"not run: {geometry}: no such file (not built)")
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


# -- one class per job (the workflow's batches) ---------------------------------------------

#: the files of one interchange that the export stage writes beside its geometry.json
EXPORT_FILES = ("interchange.xodr", "plan.png", "interchange.net.xml")
_NO_XODR = "not run: no OpenDRIVE file (export failed)"


def class_samples(geometry_table: str | os.PathLike) -> dict[int, str]:
    """Sample → ``""`` (built) or why it was not built, from a class's ``geometry/{class_id}.parquet``."""
    rows = pq.read_table(str(geometry_table), columns=["sample", "infeasible"]).to_pylist()
    out: dict[int, str] = {}
    for r in rows:
        why = r["infeasible"] or ""
        out.setdefault(int(r["sample"]), why if why.startswith("not built") else "")
    return dict(sorted(out.items()))


def _export_one(folder: Path, options: ExportOptions | None, job: tuple[int, str]
                ) -> list[CheckResult]:
    """One interchange's export files and its ``export`` and ``netconvert`` rows."""
    from flyover.opendrive.plan import draw_plan  # noqa: PLC0415
    from flyover.opendrive.reader import read_xodr  # noqa: PLC0415
    from flyover.opendrive.validate import netconvert_check  # noqa: PLC0415
    from flyover.sumo.netconvert import run_netconvert  # noqa: PLC0415
    from flyover.topology.io import atomic_write, remove_stale_temporaries  # noqa: PLC0415

    sample, not_built = job
    here = folder / str(sample)
    geometry = here / "geometry.json"
    for f in EXPORT_FILES:
        (here / f).unlink(missing_ok=True)
        remove_stale_temporaries(here, f)  # of a killed run
    if not_built:
        return [CheckResult("export", False, f"{geometry}: {not_built}"),
                CheckResult("netconvert", False, _NO_XODR)]
    try:
        g, data = _write(geometry, options)
        draw_plan(read_xodr(io.BytesIO(data)), here / "plan.png", title=f"{g.class_id} sample {g.sample}")
        atomic_write(here / "interchange.xodr", data)
    except Exception as exc:  # noqa: BLE001 - one interchange's failure is its rows
        if isinstance(exc, FlyoverError):
            error = exc.one_line()
        else:
            error = f"{geometry}: {type(exc).__name__}: {exc}"
            log.exception("export of %s failed", geometry)
        for f in EXPORT_FILES:
            (here / f).unlink(missing_ok=True)
        return [CheckResult("export", False, error), CheckResult("netconvert", False, _NO_XODR)]
    minor = (options or ExportOptions()).opendrive_minor
    written = CheckResult("export", True, f"{here / 'interchange.xodr'}: OpenDRIVE 1.{minor}, "
                          f"{data.count(b'<road ')} roads, {data.count(b'<junction ')} junctions, "
                          f"{len(data)} bytes")
    nc = run_netconvert(here / "interchange.xodr", here / "interchange.net.xml")
    for w in nc.warnings:
        log.info("%s: netconvert %s", here, w)
    return [written, netconvert_check(nc)]


def export_class(geometry_table: str | os.PathLike, folder: str | os.PathLike,
                 table: str | os.PathLike, *, class_id: str,
                 options: ExportOptions | None = None, name: str = "", workers: int = 1
                 ) -> list[dict]:
    """Export every interchange of one class in one job: ``.xodr``, ``plan.png``, SUMO network.

    For each sample of the class's geometry table, ``{folder}/{sample}/geometry.json``
    becomes ``interchange.xodr`` (OpenDRIVE), ``plan.png`` and, through netconvert,
    ``interchange.net.xml``, each written atomically. ``table`` gets the class's
    ``export`` and ``netconvert`` rows (:data:`VALIDATION_SCHEMA`; the validation
    stage takes them over): an interchange that cannot be written or converted is
    a failed row with the one-line error, and none of its export files is left.
    ``workers`` processes share the interchanges (the same files for any number).
    """
    from functools import partial  # noqa: PLC0415

    from flyover.parallel import map_ordered  # noqa: PLC0415
    from flyover.progress import Progress  # noqa: PLC0415
    from flyover.topology.io import remove_stale_temporaries  # noqa: PLC0415
    from flyover.topology.tables import write_parquet  # noqa: PLC0415

    folder = Path(folder)
    remove_stale_temporaries(Path(table).parent, Path(table).name)
    samples = class_samples(geometry_table)
    progress = Progress("export", f"{class_id} {name}".strip(), len(samples))
    rows: list[dict] = []
    jobs = list(samples.items())
    for (sample, _), results in zip(jobs, map_ordered(partial(_export_one, folder, options), jobs,
                                                      workers)):
        for r in results:
            if not r.ok:
                log.error("%s %s FAILED: %s", folder / str(sample), r.check, r.detail)
        rows += [_row(class_id, sample, r) for r in results]
        progress.done(ok=all(r.ok for r in results))
    write_parquet(rows, VALIDATION_SCHEMA, table)
    return rows


def validate_class(export_table: str | os.PathLike, folder: str | os.PathLike,
                   table: str | os.PathLike, *, class_id: str,
                   options: ExportOptions | None = None, run_qc: bool = True,
                   clearance_m: float = 5.5, name: str = "", chunk: int = 32,
                   workers: int = 1) -> list[dict]:
    """Validate every interchange of one class: its rows of ``validation.parquet`` → ``table``.

    Reads the files the export stage wrote (:func:`export_class`) and takes over its
    ``export`` and ``netconvert`` rows; the XSD and ASAM checks (both renditions of every
    interchange) run in one process of the checker's environment per ``chunk``
    interchanges (its start-up, ~1 s, is paid once per chunk; progress is reported after
    each); continuity, routes (on the SUMO network the export stage made) and clearance
    per interchange. Checks that need a file the export could not make fail as ``not
    run``. ``workers`` processes share the chunks (the same rows for any number).
    """
    from functools import partial  # noqa: PLC0415

    from flyover.parallel import map_ordered  # noqa: PLC0415
    from flyover.progress import Progress  # noqa: PLC0415
    from flyover.topology.io import remove_stale_temporaries  # noqa: PLC0415
    from flyover.topology.tables import write_parquet  # noqa: PLC0415

    folder = Path(folder)
    remove_stale_temporaries(Path(table).parent, Path(table).name)
    exported: dict[int, dict[str, CheckResult]] = {}
    for r in pq.read_table(str(export_table), schema=VALIDATION_SCHEMA).to_pylist():
        exported.setdefault(r["sample"], {})[r["check"]] = CheckResult(r["check"], r["ok"], r["detail"])
    samples = sorted(exported)
    if workers > 1 and samples:  # a multiple of `workers` chunks of at most `chunk`, all equal
        n_chunks = workers * -(-len(samples) // (workers * chunk))
        chunk = -(-len(samples) // n_chunks)
    chunks = [{s: exported[s] for s in samples[k:k + chunk]} for k in range(0, len(samples), chunk)]
    progress = Progress("validation", f"{class_id} {name}".strip(), len(exported))
    check = partial(_validate_chunk, folder, options, run_qc, clearance_m)
    rows: list[dict] = []
    for done in map_ordered(check, chunks, workers):
        for sample, results in done:
            for r in results:
                failed = not r.ok and not r.detail.startswith("not run")
                (log.error if failed else log.info)("%s %s %s: %s", folder / str(sample), r.check,
                                                    "ok" if r.ok else "FAILED", r.detail)
            rows += [_row(class_id, sample, r) for r in results]
            progress.done(ok=all(r.ok for r in results))
    write_parquet(rows, VALIDATION_SCHEMA, table)
    return rows


def _validate_chunk(folder: Path, options: ExportOptions | None, run_qc: bool, clearance_m: float,
                    exported: dict[int, dict[str, CheckResult]]
                    ) -> list[tuple[int, list[CheckResult]]]:
    """The checks of some interchanges of one class, their XSD and ASAM checks in one process."""
    from flyover.opendrive.reader import read_xodr  # noqa: PLC0415
    from flyover.opendrive.validate import QCItem, continuity_check, qc_checks, routes_check  # noqa: PLC0415

    items, item_samples, parsed = [], [], {}
    for sample, done in exported.items():
        here = folder / str(sample)
        if not done["export"].ok:
            continue
        try:
            g = read_geometry(here / "geometry.json")
            xodr = here / "interchange.xodr"
            parsed[sample] = (g, read_xodr(xodr))
            items.append(QCItem(xodr, xodr.read_bytes(), parsed[sample][1], g))
            item_samples.append(sample)
        except FlyoverError as exc:
            parsed[sample] = exc.one_line()
    times: dict[str, float] = {}
    checked = dict(zip(item_samples, qc_checks(items, options, run_qc, times)))
    log.info("ASAM checker and XSD for %d interchanges: %.1f s", len(items), times.get("asam_qc", 0.0))
    out = []
    for sample, done in exported.items():
        here = folder / str(sample)
        if sample in checked:
            g, net = parsed[sample]
            results = [done["export"], *checked[sample], continuity_check(net), done["netconvert"],
                       routes_check(here / "interchange.net.xml" if done["netconvert"].ok else None,
                                    net, g)]
        else:
            why = parsed.get(sample, _NO_XODR)
            results = [done["export"]] + [
                CheckResult(c, False, why if c != "netconvert" else done["netconvert"].detail)
                for c in CHECKS]
        results = [r for r in results if r.check != "asam_qc" or run_qc]
        results.append(clearance_check(here / "geometry.json", clearance_m))
        out.append((sample, results))
    return out
