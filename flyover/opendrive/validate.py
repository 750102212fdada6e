"""Validate any OpenDRIVE file: schema, ASAM checker, 3D continuity, netconvert, routes.

Checks (the ``check`` column of ``results/validation.parquet``):

``xsd``
    The file against the ASAM XSD of the version its header declares (the
    XSDs bundled with the ASAM checker).
``asam_qc``
    The ASAM OpenDRIVE checker bundle: ok when it reports zero issues and no
    checker ended in error. Checkers the bundle itself skips because they do
    not apply to the declared version are listed in the detail.
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
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path

from lxml import etree

from flyover.errors import FlyoverError
from flyover.geometry.model import InterchangeGeometry
from flyover.opendrive import qc
from flyover.opendrive.continuity import check_continuity
from flyover.opendrive.reader import XodrNetwork, read_xodr

__all__ = ["CheckResult", "CHECKS", "xsd_errors", "movements", "validate_xodr"]

log = logging.getLogger(__name__)

CHECKS = ("xsd", "asam_qc", "continuity", "netconvert", "routes")
_XSD = {(1, 1): "1.1/OpenDRIVE_1.1.xsd", (1, 2): "1.2/OpenDRIVE_1.2.xsd",
        (1, 3): "1.3/OpenDRIVE_1.3.xsd", (1, 4): "1.4/OpenDRIVE_1.4H.xsd",
        (1, 5): "1.5/OpenDRIVE_1.5M.xsd", (1, 6): "1.6.1/opendrive_16_core.xsd",
        (1, 7): "1.7.0/opendrive_17_core.xsd", (1, 8): "1.8.0/OpenDRIVE_Core.xsd"}
_XSD11 = """import sys, xmlschema
schema = xmlschema.XMLSchema11(sys.argv[1])
for e in schema.iter_errors(sys.argv[2]):
    print(f"line {e.sourceline}: {e.reason}")
"""


@dataclass(frozen=True)
class CheckResult:
    """One row of the validation table."""

    check: str
    ok: bool
    detail: str


def xsd_errors(path: str | os.PathLike, version: tuple[int, int]) -> list[str]:
    """Schema errors of ``path`` against the ASAM XSD of its ``version`` (1.1–1.8).

    Up to 1.7 the schemas are XSD 1.0 (lxml, here); 1.8 needs XSD 1.1, which
    runs with ``xmlschema`` in the checker's environment.
    """
    rel = _XSD.get(tuple(version))
    if rel is None:
        raise qc.QCError(f"no ASAM schema for OpenDRIVE {version[0]}.{version[1]}", source=str(path))
    xsd = qc.schema_dir() / rel
    if tuple(version) >= (1, 8):
        res = subprocess.run([str(qc.find_qc_python()), "-c", _XSD11, str(xsd), str(path)],
                             capture_output=True, text=True)
        if res.returncode != 0:
            raise qc.QCError(f"XSD 1.1 validation failed to run: {res.stderr.strip()[-300:]}",
                             source=str(path))
        return [ln for ln in res.stdout.splitlines() if ln.strip()]
    schema = etree.XMLSchema(etree.parse(str(xsd)))
    schema.validate(etree.parse(str(path)))
    return [f"line {e.line}: {e.message}" for e in schema.error_log]


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


def validate_xodr(path: str | os.PathLike, *, geometry: InterchangeGeometry | None = None,
                  net_out: str | os.PathLike | None = None, run_qc: bool = True
                  ) -> tuple[list[CheckResult], dict[str, float], tuple[str, ...]]:
    """Run every check on one OpenDRIVE file.

    Returns the check results (in :data:`CHECKS` order), timings in seconds
    (``netconvert``) and netconvert's warnings. A check that cannot run is a
    failed check with the reason as detail; nothing is skipped silently.
    """
    from flyover.sumo.netconvert import run_netconvert  # noqa: PLC0415
    from flyover.sumo.routes import check_routes, generic_routes  # noqa: PLC0415

    path = Path(path)
    results: list[CheckResult] = []
    times: dict[str, float] = {}
    try:
        net = read_xodr(path)
    except FlyoverError as exc:
        return [CheckResult(c, False, exc.one_line()) for c in CHECKS], times, ()
    try:
        errs = xsd_errors(path, net.version)
        results.append(CheckResult("xsd", not errs, f"OpenDRIVE {net.version[0]}.{net.version[1]}: "
                                   + ("valid" if not errs else f"{len(errs)} errors; " + "; ".join(errs[:3]))))
    except FlyoverError as exc:
        results.append(CheckResult("xsd", False, exc.one_line()))
    if run_qc:
        try:
            outcomes = qc.run_asam_checker(path)
            issues = [i for o in outcomes for i in o.issues]
            errored = [o.checker_id for o in outcomes if o.status == "error"]
            by_version = [o.checker_id for o in outcomes
                          if o.status == "skipped" and o.summary.startswith("Version")]
            skipped = [o.checker_id for o in outcomes
                       if o.status == "skipped" and o.checker_id not in by_version]
            done = sum(o.status == "completed" for o in outcomes)
            detail = f"{done}/{len(outcomes)} checkers completed, {len(issues)} issues"
            if by_version:
                detail += "; not applicable to this version: " + ", ".join(by_version)
            if skipped:
                detail += f"; {len(skipped)} skipped on failed preconditions"
            if errored:
                detail += "; errors in: " + ", ".join(errored)
            for i in issues[:3]:
                detail += f"; {i.checker_id}: {i.description} at {i.where[:160]}"
            results.append(CheckResult("asam_qc", not (issues or errored or skipped), detail))
        except (FlyoverError, OSError) as exc:
            results.append(CheckResult("asam_qc", False, str(exc)))
    try:
        ok, detail = check_continuity(net)
        results.append(CheckResult("continuity", ok, detail))
    except (FlyoverError, ValueError, ZeroDivisionError) as exc:
        results.append(CheckResult("continuity", False, f"cannot evaluate: {exc}"))
    with tempfile.TemporaryDirectory(prefix="flyover-nc-") as tmp:
        out = Path(net_out) if net_out else Path(tmp) / "net.net.xml"
        nc = run_netconvert(path, out)
        times["netconvert"] = nc.seconds
        detail = f"{len(nc.errors)} errors, {len(nc.warnings)} warnings"
        if nc.errors:
            detail += "; " + "; ".join(nc.errors[:3])
        elif nc.warnings:
            detail += "; e.g. " + nc.warnings[0]
        results.append(CheckResult("netconvert", nc.ok, detail))
        if not nc.ok:
            results.append(CheckResult("routes", False, "no SUMO network"))
        elif geometry is not None:
            moves = _movement_roads(net, movements(geometry))
            ok, detail, _ = check_routes(out, moves)
            results.append(CheckResult("routes", ok and bool(moves), detail))
        else:
            ok, detail = generic_routes(out)
            results.append(CheckResult("routes", ok, detail))
    return results, times, nc.warnings
