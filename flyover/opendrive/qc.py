"""The ASAM OpenDRIVE quality checker (PyPI ``asam-qc-opendrive``) as an external tool.

The checker pins ``numpy<2`` while flyover needs ``numpy>=2``, so it lives in
its own virtual environment, by default ``.venv-qc`` in the working directory
(or the repository root), or wherever ``FLYOVER_QC_PYTHON`` points (the
environment's ``python``). :func:`setup_qc_venv` creates it idempotently:

    python -m flyover.opendrive.qc --setup        # creates ./.venv-qc if missing

:func:`run_qc_batch` writes the checker's own configuration XML per file and
runs them all in *one* process of that environment (``_qc_driver.py``, run by
path: it calls the bundle's own ``run_checks`` per file, as ``python -m
qc_opendrive -c config.xml`` does, so startup is paid once), then parses each
result file (an ``.xqar`` XML:
``CheckerResults/CheckerBundle/Checker[@status]/Issue``). The same process
also runs XSD 1.1 validations (OpenDRIVE 1.8) for :mod:`flyover.opendrive.validate`.
The checker bundles the ASAM XSDs of every OpenDRIVE version (:func:`schema_dir`).

No one file gets every checker of the bundle (1.0.0) completed: one applies up
to OpenDRIVE 1.7 only, another from 1.8 on. :func:`bundle_verdict` therefore
judges the union of runs on renditions of one interchange in several versions.
"""

from __future__ import annotations

import functools
import json
import logging
import os
import subprocess
import sys
import tempfile
import time
import venv
from dataclasses import dataclass
from pathlib import Path
from typing import Sequence
from xml.sax.saxutils import quoteattr

from lxml import etree

from flyover.errors import FlyoverError

__all__ = ["QCError", "CheckerIssue", "CheckerOutcome", "CheckerRun", "XsdRun", "QCBatch", "Rendition",
           "find_qc_python", "setup_qc_venv", "schema_dir", "checker_config", "parse_result",
           "run_qc_batch", "run_asam_checker",
           "bundle_verdict", "QC_PACKAGE"]

log = logging.getLogger(__name__)

#: the requirement installed into the checker's environment
QC_PACKAGE = "asam-qc-opendrive>=1.0,<2"
_REPO_ROOT = Path(__file__).resolve().parents[2]
_DRIVER = Path(__file__).with_name("_qc_driver.py")
_LEVELS = {"1": "error", "2": "warning", "3": "information"}


class QCError(FlyoverError):
    """The ASAM checker is missing or failed to run."""


@dataclass(frozen=True)
class CheckerIssue:
    """One issue reported by one checker."""

    checker_id: str
    level: str
    description: str
    where: str


@dataclass(frozen=True)
class CheckerOutcome:
    """The status of one checker of the bundle and its issues."""

    checker_id: str
    status: str
    summary: str
    issues: tuple[CheckerIssue, ...]


def _candidates() -> list[Path]:
    env = os.environ.get("FLYOVER_QC_PYTHON")
    if env:
        return [Path(env)]
    out = []
    for root in (Path.cwd(), _REPO_ROOT):
        out.append(root / ".venv-qc" / "bin" / "python")
    return out


def find_qc_python() -> Path:
    """The python of the checker's environment.

    Raises
    ------
    QCError
        When neither ``FLYOVER_QC_PYTHON`` nor ``./.venv-qc`` holds a python
        that can import ``qc_opendrive``.
    """
    for cand in _candidates():
        if cand.exists():
            return cand
    raise QCError("ASAM checker not found: set FLYOVER_QC_PYTHON or run "
                  "`python -m flyover.opendrive.qc --setup`", element="asam-qc-opendrive")


def setup_qc_venv(path: str | os.PathLike | None = None) -> Path:
    """Create the checker's venv at ``path`` (default ``<repo>/.venv-qc``) if missing.

    Idempotent: an environment that already imports ``qc_opendrive`` is kept.
    Returns the environment's python.
    """
    root = Path(path) if path else _REPO_ROOT / ".venv-qc"
    py = root / "bin" / "python"
    if py.exists() and subprocess.run([str(py), "-c", "import qc_opendrive"],
                                      capture_output=True).returncode == 0:
        return py
    if not py.exists():
        venv.EnvBuilder(with_pip=True, clear=False).create(root)
    subprocess.run([str(py), "-m", "pip", "install", "--quiet", QC_PACKAGE], check=True)
    return py


def schema_dir(python: Path | None = None) -> Path:
    """The folder of ASAM OpenDRIVE XSDs bundled with the checker (``1.7.0/...``).

    Located without importing the checker (whose import takes about a second), once per
    process and checker environment (a validation batch asks for every file).
    """
    return _schema_dir(python or find_qc_python())


@functools.lru_cache(maxsize=None)
def _schema_dir(py: Path) -> Path:
    res = subprocess.run(
        [str(py), "-c", "import importlib.util, os; s = importlib.util.find_spec('qc_opendrive'); "
                        "print(os.path.join(s.submodule_search_locations[0], 'schema'))"],
        capture_output=True, text=True)
    if res.returncode != 0:
        raise QCError(f"cannot locate the checker's schemas: {res.stderr.strip()[-300:]}",
                      element=str(py))
    return Path(res.stdout.strip())


def checker_config(xodr: Path, result: Path) -> str:
    """The checker's own configuration XML: check ``xodr``, write the result file ``result``."""
    return (f'<?xml version="1.0" encoding="UTF-8"?>\n<Config>\n'
            f'  <Param name="InputFile" value={quoteattr(str(xodr))}/>\n'
            f'  <CheckerBundle application="xodrBundle">\n'
            f'    <Param name="resultFile" value={quoteattr(str(result))}/>\n'
            f'  </CheckerBundle>\n</Config>\n')


def parse_result(path: str | os.PathLike) -> list[CheckerOutcome]:
    """Parse the checker's result file into one outcome per checker."""
    root = etree.parse(str(path)).getroot()
    out = []
    for ch in root.iter("Checker"):
        issues = []
        for iss in ch.iter("Issue"):
            where = [loc.get("xpath") for loc in iss.iter("XMLLocation")]
            where += [f"line {loc.get('row')}" + (f": {group.get('description')}"
                                                  if group.get("description") else "")
                      for group in iss.iter("Locations") for loc in group.iter("FileLocation")]
            where += [f"({loc.get('x')}, {loc.get('y')}, {loc.get('z')})"
                      for loc in iss.iter("InertialLocation")]
            issues.append(CheckerIssue(ch.get("checkerId"), _LEVELS.get(iss.get("level"), iss.get("level")),
                                       iss.get("description", ""), " ".join(w for w in where if w)))
        out.append(CheckerOutcome(ch.get("checkerId"), ch.get("status", ""), ch.get("summary", ""),
                                  tuple(issues)))
    return out


@dataclass(frozen=True)
class CheckerRun:
    """The checker bundle's run on one file: its outcomes, or ``error`` when it did not run."""

    xodr: str
    outcomes: tuple[CheckerOutcome, ...]
    error: str
    seconds: float


@dataclass(frozen=True)
class XsdRun:
    """One file validated against an XSD 1.1 schema: ``errors`` (``line N: reason``) or ``error``."""

    xodr: str
    errors: tuple[str, ...]
    error: str
    seconds: float


@dataclass(frozen=True)
class QCBatch:
    """Everything one process of the checker's environment did, in input order."""

    checker: tuple[CheckerRun, ...]
    xsd11: tuple[XsdRun, ...]
    seconds: float
    startup_seconds: float


def run_qc_batch(xodrs: Sequence[str | os.PathLike] = (), *,
                 xsd11: Sequence[tuple[str | os.PathLike, str | os.PathLike]] = (),
                 python: Path | None = None, timeout_s: float = 300,
                 excluded_by: Sequence[str | None] | None = None,
                 share_annotations: bool = True) -> QCBatch:
    """Run the checker bundle on every file of ``xodrs`` and the ``(schema, file)`` XSD 1.1
    validations of ``xsd11``, all in one process of the checker's environment.

    ``excluded_by[i]`` (a version such as ``"1.8.0"``, or ``None``) runs on file ``i``
    only the version-bound checkers that do not apply to that version (and the basic
    ones): for a rendition that differs from a file checked in that version only in the
    declared version.

    ``share_annotations=False`` validates XSD 1.1 identity constraints without the
    driver's shared document annotations (see ``_qc_driver``), as ``xmlschema`` alone does.

    A file the bundle cannot process gets a :class:`CheckerRun` with ``error``
    set; the others still run. ``timeout_s`` is per file. Raises
    :class:`QCError` when the process itself cannot run.
    """
    py = python or find_qc_python()
    paths = [Path(x).resolve() for x in xodrs]
    with tempfile.TemporaryDirectory(prefix="flyover-qc-") as tmp:
        cfgs, results = [], []
        for i, x in enumerate(paths):
            cfg, res = Path(tmp) / f"{i}.config.xml", Path(tmp) / f"{i}.xqar"
            cfg.write_text(checker_config(x, res), encoding="utf-8")
            cfgs.append(str(cfg))
            results.append(res)
        jobs = Path(tmp) / "jobs.json"
        jobs.write_text(json.dumps({"configs": cfgs, "excluded_by": list(excluded_by or [None] * len(cfgs)),
                                    "xsd11": [[str(Path(s).resolve()), str(Path(x).resolve())]
                                              for s, x in xsd11],
                                    "share_annotations": share_annotations}), encoding="utf-8")
        t0 = time.perf_counter()
        try:
            proc = subprocess.run([str(py), str(_DRIVER), str(jobs)], cwd=tmp, capture_output=True,
                                  text=True, timeout=timeout_s * max(1, len(paths) + len(xsd11)))
            report = json.loads(proc.stdout.strip().splitlines()[-1]) if proc.returncode == 0 else None
        except (OSError, subprocess.TimeoutExpired) as exc:
            raise QCError(f"ASAM checker failed to run: {exc}",
                          source=", ".join(map(str, paths)) or None) from None
        except (ValueError, IndexError):
            report = None
        if report is None:
            raise QCError(f"ASAM checker failed (exit {proc.returncode}): {proc.stderr.strip()[-400:]}",
                          source=", ".join(map(str, paths)) or None)
        runs = []
        for x, res, rep in zip(paths, results, report["configs"]):
            error = rep["error"] or ("" if res.exists() else "no result file")
            runs.append(CheckerRun(str(x), tuple(parse_result(res)) if not error else (),
                                   f"ASAM checker failed on {x}: {error}" if error else "",
                                   float(rep["seconds"])))
        xsds = tuple(XsdRun(str(x), tuple(rep["errors"]), rep["error"] or "", float(rep["seconds"]))
                     for (_, x), rep in zip(xsd11, report["xsd11"]))
        return QCBatch(tuple(runs), xsds, time.perf_counter() - t0, float(report["startup_seconds"]))


def run_asam_checker(xodr: str | os.PathLike, *, python: Path | None = None,
                     timeout_s: float = 300) -> list[CheckerOutcome]:
    """Run the ASAM OpenDRIVE checker bundle on ``xodr``.

    Returns every checker's status (``completed``, ``skipped``, ``error``)
    and issues. Raises :class:`QCError` if the tool cannot run.
    """
    run = run_qc_batch([xodr], python=python, timeout_s=timeout_s).checker[0]
    if run.error:
        raise QCError(run.error, source=str(xodr))
    return list(run.outcomes)


# -- one verdict over renditions in several versions ---------------------------------------

@dataclass(frozen=True)
class Rendition:
    """The checker's outcomes on one rendition of an interchange.

    Attributes
    ----------
    version
        The OpenDRIVE version the rendition declares, e.g. ``"1.8"``.
    origin
        Where it came from, e.g. ``"the file"``, ``"written from geometry.json"``.
    outcomes
        The bundle's outcome per checker on it.
    """

    version: str
    origin: str
    outcomes: tuple[CheckerOutcome, ...]


def _by_version(o: CheckerOutcome) -> bool:
    return o.status == "skipped" and o.summary.startswith("Version")


def bundle_verdict(renditions: Sequence[Rendition], missing: Sequence[str] = ()) -> tuple[bool, str]:
    """Judge the checker bundle over renditions of one interchange.

    Passes only when every checker of the bundle completed on at least one
    rendition, no checker ended in error and no run reported an issue. A
    checker that no rendition completed fails the verdict, also when it was
    skipped only because it does not apply to the versions at hand (``missing``
    says why no rendition in another version was checked).

    Returns ``(ok, detail)``; the detail says which checkers ran on which
    rendition.

    Examples
    --------
    >>> a = CheckerOutcome("check_a", "completed", "", ())
    >>> b = CheckerOutcome("check_b", "skipped", "Version 1.8.0 is not valid ...", ())
    >>> ok, detail = bundle_verdict([Rendition("1.8", "the file", (a, b))], ["no 1.7 rendition"])
    >>> ok
    False
    >>> detail.split("; ")[:2]
    ['1/2 checkers completed, 0 issues', 'not completed on any rendition: check_b']
    """
    order: dict[str, None] = {}
    for r in renditions:
        order.update((o.checker_id, None) for o in r.outcomes)
    done = {o.checker_id for r in renditions for o in r.outcomes if o.status == "completed"}
    issues = [(r.version, i) for r in renditions for o in r.outcomes for i in o.issues]
    errored = [(r.version, o) for r in renditions for o in r.outcomes if o.status == "error"]
    never = [c for c in order if c not in done]
    parts = [f"{len(done)}/{len(order)} checkers completed, {len(issues)} issues"]
    if never:
        parts.append("not completed on any rendition: " + ", ".join(never))
    for r in renditions:
        text = f"on {r.version} ({r.origin}): {sum(o.status == 'completed' for o in r.outcomes)} completed"
        excluded = [o.checker_id for o in r.outcomes if _by_version(o)]
        skipped = [o.checker_id for o in r.outcomes if o.status == "skipped" and not _by_version(o)]
        if excluded:
            text += f", not applicable to version {r.version}: " + ", ".join(excluded)
        if skipped:
            text += ", skipped on failed preconditions: " + ", ".join(skipped)
        parts.append(text)
    parts += list(missing)
    parts += [f"error in {o.checker_id} on {v}: {o.summary}" for v, o in errored]
    parts += [f"{i.checker_id} on {v}: {i.description} at {i.where[:160]}" for v, i in issues[:3]]
    ok = bool(order) and not never and not issues and not errored
    return ok, "; ".join(parts)


def main(argv: list[str] | None = None) -> int:
    """``python -m flyover.opendrive.qc --setup [PATH]``: create the checker's venv."""
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0] != "--setup":
        sys.stderr.write("usage: python -m flyover.opendrive.qc --setup [VENV_PATH]\n")
        return 2
    py = setup_qc_venv(argv[1] if len(argv) > 1 else None)
    sys.stdout.write(f"{py}\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
