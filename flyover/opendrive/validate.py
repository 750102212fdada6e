"""Validate any OpenDRIVE file: schema, ASAM checker, 3D continuity, netconvert, routes.

Checks (the ``check`` column of ``results/validation.parquet``):

``xsd``
    The file against the ASAM XSD of the version its header declares (the
    XSDs bundled with the ASAM checker).
``asam_qc``
    The ASAM OpenDRIVE checker bundle (1.0.0), ok only when every one of its
    checkers completed, none ended in error and none reported an issue. One
    of them applies up to OpenDRIVE 1.7 only, another from 1.8 on, so no one
    file completes them all: the bundle also runs on the interchange's
    rendition in the other version (1.7 for a 1.8 file and back), written by
    flyover's writer from the interchange's geometry, and the verdict is over
    the union (:func:`flyover.opendrive.qc.bundle_verdict`; the detail lists
    which checkers ran on which rendition). A rendition is made only when the
    file is exactly what the writer makes of that geometry (then the two
    renditions differ in the declared version alone); relabelling anyone
    else's file would judge it by rules of a version it does not declare
    (1.8 allows one connecting road in several connection elements, 1.7
    forbids it). Without a rendition the checker that does not apply to the
    file's version is reported as not applicable to it, and the check fails.
``continuity``
    Our own check, :mod:`flyover.opendrive.continuity`.
``netconvert``
    SUMO's netconvert runs without error (warnings are counted in the detail).
``routes``
    Every entrance → exit movement of the topology is routable in the SUMO
    network (with the geometry), else every entry edge reaches some exit.
"""

from __future__ import annotations

import logging
import os
import tempfile
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Sequence

from lxml import etree

from flyover.errors import FlyoverError
from flyover.geometry.model import InterchangeGeometry
from flyover.opendrive import qc
from flyover.opendrive.continuity import check_continuity
from flyover.opendrive.reader import XodrNetwork, read_xodr
from flyover.opendrive.writer import ExportOptions, xodr_bytes

__all__ = ["CheckResult", "CHECKS", "OtherVersion", "QCItem", "xsd_errors", "other_rendition",
           "movements", "qc_checks", "continuity_check", "netconvert_check", "routes_check",
           "validate_xodr"]

log = logging.getLogger(__name__)

CHECKS = ("xsd", "asam_qc", "continuity", "netconvert", "routes")
_XSD = {(1, 1): "1.1/OpenDRIVE_1.1.xsd", (1, 2): "1.2/OpenDRIVE_1.2.xsd",
        (1, 3): "1.3/OpenDRIVE_1.3.xsd", (1, 4): "1.4/OpenDRIVE_1.4H.xsd",
        (1, 5): "1.5/OpenDRIVE_1.5M.xsd", (1, 6): "1.6.1/opendrive_16_core.xsd",
        (1, 7): "1.7.0/opendrive_17_core.xsd", (1, 8): "1.8.0/OpenDRIVE_Core.xsd"}
#: the versions whose union completes every checker of the ASAM bundle 1.0.0
_RENDERED = ((1, 7), (1, 8))


@dataclass(frozen=True)
class CheckResult:
    """One row of the validation table."""

    check: str
    ok: bool
    detail: str


def _xsd_path(path: str | os.PathLike, version: tuple[int, int]) -> Path:
    rel = _XSD.get(tuple(version))
    if rel is None:
        raise qc.QCError(f"no ASAM schema for OpenDRIVE {version[0]}.{version[1]}", source=str(path))
    return qc.schema_dir() / rel


def _xsd10_errors(path: str | os.PathLike, xsd: Path) -> list[str]:
    schema = etree.XMLSchema(etree.parse(str(xsd)))
    schema.validate(etree.parse(str(path)))
    return [f"line {e.line}: {e.message}" for e in schema.error_log]


def xsd_errors(path: str | os.PathLike, version: tuple[int, int]) -> list[str]:
    """Schema errors of ``path`` against the ASAM XSD of its ``version`` (1.1–1.8).

    Up to 1.7 the schemas are XSD 1.0 (lxml, here); 1.8 needs XSD 1.1, which
    runs with ``xmlschema`` in the checker's environment.
    """
    xsd = _xsd_path(path, version)
    if tuple(version) < (1, 8):
        return _xsd10_errors(path, xsd)
    run = qc.run_qc_batch(xsd11=[(xsd, path)]).xsd11[0]
    if run.error:
        raise qc.QCError(f"XSD 1.1 validation failed to run: {run.error}", source=str(path))
    return list(run.errors)


@dataclass(frozen=True)
class OtherVersion:
    """A file's rendition in the other of OpenDRIVE 1.7/1.8, or why there is none.

    ``version`` and ``data`` are ``None`` exactly when ``reason`` says why.
    """

    version: tuple[int, int] | None
    data: bytes | None
    reason: str = ""


def other_rendition(data: bytes, version: tuple[int, int], geometry: InterchangeGeometry | None,
                    options: ExportOptions | None = None) -> OtherVersion:
    """The file ``data`` (declaring ``version``) in the other of OpenDRIVE 1.7/1.8, if it can be made.

    Written by flyover's writer from ``geometry`` with ``options``, and only
    when ``data`` is byte for byte what the writer makes of them in
    ``version``: then the rendition is the same interchange, declared in the
    other version.
    """
    version = tuple(version)
    if version not in _RENDERED:
        return OtherVersion(None, None, "no 1.7/1.8 rendition: flyover renders only the files it "
                                        "writes (OpenDRIVE 1.7 and 1.8)")
    other = next(v for v in _RENDERED if v != version)
    name = f"{other[0]}.{other[1]}"
    if geometry is None:
        return OtherVersion(None, None, f"no {name} rendition: only the file's own version can be "
                                        "checked (no geometry.json to write one from)")
    opts = options or ExportOptions()
    try:
        rendition = xodr_bytes(geometry, replace(opts, opendrive_minor=other[1]))
    except FlyoverError as exc:
        return OtherVersion(None, None, f"no {name} rendition: {exc.one_line()}")
    # the writer's two versions differ in the header's revMinor alone (one writer pass, not
    # two; were they to differ anywhere else, no file would match and none would be rendered)
    mark = f'revMinor="{other[1]}"'.encode()
    if mark not in rendition or rendition.replace(mark, f'revMinor="{version[1]}"'.encode(), 1) != data:
        return OtherVersion(None, None, f"no {name} rendition: the file is not what flyover "
                                        "writes from its geometry.json (edited, or other "
                                        "export options)")
    return OtherVersion(other, rendition)


def movements(g: InterchangeGeometry) -> list[tuple[str, str]]:
    """Entrance → exit movements the interchange allows, as (road, road) element ids.

    An entrance is the start of a road that does not begin from a ramp
    (``In-M``), an exit the end of a road that does not end into one
    (``Out-M``). A movement leaves its entrance road, follows ramps only (a
    ramp may be left only downstream of where it was entered) and joins its
    exit road; going straight on along one road is a movement too.
    """
    outs: dict[str, list] = {}
    for r in g.ramps:
        outs.setdefault(r.start.parent, []).append((r.start.s_m, r.id, r.start.label))
    ramp = {r.id: r for r in g.ramps}
    starts_from_ramp = {r.end.parent for r in g.ramps if r.end.label == "In-M"}
    ends_into_ramp = {r.start.parent for r in g.ramps if r.start.label == "Out-M"}
    found: set[tuple[str, str]] = set()
    for u in (r.id for r in g.roads):
        if u in starts_from_ramp:
            continue
        if u not in ends_into_ramp:
            found.add((u, u))
        stack, seen = [(u, 0.0)], set()
        while stack:
            el, s_in = stack.pop()
            if (el, s_in) in seen:
                continue
            seen.add((el, s_in))
            if el in ramp:  # a ramp ends into a road (an exit), another ramp, or forks
                end = ramp[el].end
                if end.parent in ramp:
                    stack.append((end.parent, end.s_m))
                elif end.parent and end.parent not in ends_into_ramp:
                    found.add((u, end.parent))
            for s_out, rid, _ in outs.get(el, []):
                if s_out >= s_in - 1e-6:
                    stack.append((rid, 0.0))
    return sorted(found)


def _movement_roads(net: XodrNetwork, pairs: list[tuple[str, str]]):
    from flyover.sumo.routes import Movement  # noqa: PLC0415

    first = {r.name: r.id for r in net.roads.values() if r.junction == "-1" and r.predecessor is None}
    last = {r.name: r.id for r in net.roads.values() if r.junction == "-1" and r.successor is None}
    return [Movement(f"{u}->{v}", first.get(u, "?"), last.get(v, "?")) for u, v in pairs]


@dataclass(frozen=True)
class QCItem:
    """One OpenDRIVE file for :func:`qc_checks`: its path, bytes, parsed network and, when
    flyover wrote it, the geometry it was written from (for the other version's rendition)."""

    path: Path
    data: bytes
    net: XodrNetwork
    geometry: InterchangeGeometry | None = None


def qc_checks(items: Sequence[QCItem], options: ExportOptions | None = None, run_qc: bool = True,
              times: dict[str, float] | None = None) -> list[list[CheckResult]]:
    """The ``xsd`` and ``asam_qc`` rows of every item, from *one* process of the checker's
    environment (its start-up, ~2 s, is paid once for the whole batch).

    Returns, per item in order, its ``xsd`` row and (with ``run_qc``) its ``asam_qc`` row.
    When the checker's process cannot run at all, every item's checks that needed it fail
    with that reason.
    """
    times = {} if times is None else times
    plans = []  # per item: (xsd path or None, why not, index of the xsd11 job, other rendition, runs)
    files: list[Path] = []
    excluded_by: list[str | None] = []
    xsd11: list[tuple[Path, Path]] = []
    with tempfile.TemporaryDirectory(prefix="flyover-qc-") as tmp:
        for i, it in enumerate(items):
            try:
                xsd, xsd_failed = _xsd_path(it.path, it.net.version), ""
            except FlyoverError as exc:
                xsd, xsd_failed = None, exc.one_line()
            job = None
            if xsd is not None and it.net.version >= (1, 8) and not run_qc:
                job = len(xsd11)  # with the bundle, its own schema checker validates the file
                xsd11.append((xsd, it.path))
            other = (other_rendition(it.data, it.net.version, it.geometry, options) if run_qc
                     else OtherVersion(None, None))
            runs = []
            if run_qc:
                runs.append(len(files))
                files.append(it.path)
                excluded_by.append(None)
                if other.data is not None:
                    runs.append(len(files))
                    files.append(Path(tmp) / f"{i}_rendition_{other.version[0]}_{other.version[1]}.xodr")
                    files[-1].write_bytes(other.data)
                    excluded_by.append(f"{it.net.version[0]}.{it.net.version[1]}.0")
            plans.append((xsd, xsd_failed, job, other, runs))
        batch, error = None, ""
        if files or xsd11:
            try:
                batch = qc.run_qc_batch(files, xsd11=xsd11, excluded_by=excluded_by)
                times["asam_qc"] = times.get("asam_qc", 0.0) + batch.seconds
            except FlyoverError as exc:
                error = exc.one_line()
    return [_qc_rows(it, plan, batch, error, run_qc) for it, plan in zip(items, plans)]


#: the bundle's checker that validates a file against the ASAM XSD of its version
SCHEMA_CHECKER = "check_asam_xodr_xml_valid_schema"


def _bundle_schema_errors(it: QCItem, xsd: Path, run) -> list[str]:
    """The file's XSD errors as the bundle's schema checker found them (the same ASAM XSD,
    the same validator); validated here when that checker did not complete."""
    outcome = next((o for o in run.outcomes if o.checker_id == SCHEMA_CHECKER), None)
    if outcome is not None and outcome.status == "completed":
        return [i.where for i in outcome.issues]
    again = qc.run_qc_batch(xsd11=[(xsd, it.path)]).xsd11[0]
    if again.error:
        raise qc.QCError(f"XSD 1.1 validation failed to run: {again.error}", source=str(it.path))
    return list(again.errors)


def _qc_rows(it: QCItem, plan, batch, error: str, run_qc: bool) -> list[CheckResult]:
    xsd, xsd_failed, job, other, runs = plan
    vname = f"{it.net.version[0]}.{it.net.version[1]}"
    if xsd is None:
        errs = None
    elif job is None and it.net.version >= (1, 8):  # the bundle's own schema check of the file
        if batch is None:
            errs, xsd_failed = None, error
        elif batch.checker[runs[0]].error:
            errs, xsd_failed = None, batch.checker[runs[0]].error
        else:
            try:
                errs = _bundle_schema_errors(it, xsd, batch.checker[runs[0]])
            except FlyoverError as exc:
                errs, xsd_failed = None, exc.one_line()
    elif job is None:
        errs = _xsd10_errors(it.path, xsd)
    elif batch is None:
        errs, xsd_failed = None, error
    elif batch.xsd11[job].error:
        errs, xsd_failed = None, f"{it.path}: XSD 1.1 validation failed to run: {batch.xsd11[job].error}"
    else:
        errs = list(batch.xsd11[job].errors)
    rows = [CheckResult("xsd", False, xsd_failed) if errs is None else CheckResult(
        "xsd", not errs, f"OpenDRIVE {vname}: " + ("valid" if not errs else
                                                   f"{len(errs)} errors; " + "; ".join(errs[:3])))]
    if not run_qc:
        return rows
    checker = [batch.checker[k] for k in runs] if batch is not None else []
    if batch is None:
        rows.append(CheckResult("asam_qc", False, error))
    elif failed := [r.error for r in checker if r.error]:
        rows.append(CheckResult("asam_qc", False, "; ".join(failed)))
    else:
        rends = [qc.Rendition(vname, "the file", checker[0].outcomes)]
        if other.version is not None:
            rends.append(qc.Rendition(f"{other.version[0]}.{other.version[1]}",
                                      f"written from geometry.json, for the checkers {vname} excludes", checker[1].outcomes))
        rows.append(CheckResult("asam_qc", *qc.bundle_verdict(rends, [other.reason] if other.reason else [])))
    return rows


def validate_xodr(path: str | os.PathLike, *, geometry: InterchangeGeometry | None = None,
                  options: ExportOptions | None = None,
                  net_out: str | os.PathLike | None = None, run_qc: bool = True
                  ) -> tuple[list[CheckResult], dict[str, float], tuple[str, ...]]:
    """Run every check on one OpenDRIVE file.

    ``geometry`` (and the export ``options`` the file was written with) give
    the movements to route and the rendition in the other OpenDRIVE version
    for the ASAM checker (see the module's ``asam_qc``). Returns the check
    results (in :data:`CHECKS` order), timings in seconds (``asam_qc``: the
    checker's process, ``netconvert``) and netconvert's warnings. A check
    that cannot run is a failed check with the reason as detail; nothing is
    skipped silently.
    """
    from flyover.sumo.netconvert import run_netconvert  # noqa: PLC0415

    path = Path(path)
    times: dict[str, float] = {}
    try:
        net = read_xodr(path)
        data = path.read_bytes()
    except FlyoverError as exc:
        return [CheckResult(c, False, exc.one_line()) for c in CHECKS], times, ()
    results = qc_checks([QCItem(path, data, net, geometry)], options, run_qc, times)[0]
    results.append(continuity_check(net))
    with tempfile.TemporaryDirectory(prefix="flyover-nc-") as tmp:
        out = Path(net_out) if net_out else Path(tmp) / "net.net.xml"
        nc = run_netconvert(path, out)
        times["netconvert"] = nc.seconds
        results.append(netconvert_check(nc))
        results.append(routes_check(out if nc.ok else None, net, geometry))
    return results, times, nc.warnings


def continuity_check(net: XodrNetwork) -> CheckResult:
    """The ``continuity`` row (:mod:`flyover.opendrive.continuity`)."""
    try:
        ok, detail = check_continuity(net)
        return CheckResult("continuity", ok, detail)
    except (FlyoverError, ValueError, ZeroDivisionError) as exc:
        return CheckResult("continuity", False, f"cannot evaluate: {exc}")


def netconvert_check(nc) -> CheckResult:
    """The ``netconvert`` row of a :class:`~flyover.sumo.netconvert.NetconvertResult`."""
    detail = f"{len(nc.errors)} errors, {len(nc.warnings)} warnings"
    if nc.errors:
        detail += "; " + "; ".join(nc.errors[:3])
    elif nc.warnings:
        detail += "; e.g. " + nc.warnings[0]
    return CheckResult("netconvert", nc.ok, detail)


def routes_check(sumo_net: str | os.PathLike | None, net: XodrNetwork,
                 geometry: InterchangeGeometry | None) -> CheckResult:
    """The ``routes`` row: every movement of ``geometry`` routable in the SUMO network
    ``sumo_net`` (made from ``net``), else every entry reaches some exit."""
    from flyover.sumo.routes import check_routes, generic_routes  # noqa: PLC0415

    if sumo_net is None:
        return CheckResult("routes", False, "no SUMO network")
    if geometry is not None:
        moves = _movement_roads(net, movements(geometry))
        ok, detail, _ = check_routes(sumo_net, moves)
        return CheckResult("routes", ok and bool(moves), detail)
    ok, detail = generic_routes(sumo_net)
    return CheckResult("routes", ok, detail)
