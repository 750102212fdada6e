"""The ASAM OpenDRIVE quality checker (PyPI ``asam-qc-opendrive``) as an external tool.

The checker pins ``numpy<2`` while flyover needs ``numpy>=2``, so it lives in
its own virtual environment, by default ``.venv-qc`` in the working directory
(or the repository root), or wherever ``FLYOVER_QC_PYTHON`` points (the
environment's ``python``). :func:`setup_qc_venv` creates it idempotently:

    python -m flyover.opendrive.qc --setup        # creates ./.venv-qc if missing

:func:`run_asam_checker` writes the checker's configuration XML, runs
``python -m qc_opendrive -c config.xml`` and parses its result file (an
``.xqar`` XML: ``CheckerResults/CheckerBundle/Checker[@status]/Issue``).
The checker bundles the ASAM XSDs of every OpenDRIVE version
(:func:`schema_dir`), which :mod:`flyover.opendrive.validate` uses for the
schema check.
"""

from __future__ import annotations

import logging
import os
import subprocess
import sys
import tempfile
import venv
from dataclasses import dataclass
from pathlib import Path
from xml.sax.saxutils import quoteattr

from lxml import etree

from flyover.errors import FlyoverError

__all__ = ["QCError", "CheckerIssue", "CheckerOutcome", "find_qc_python", "setup_qc_venv",
           "schema_dir", "run_asam_checker", "QC_PACKAGE"]

log = logging.getLogger(__name__)

#: the requirement installed into the checker's environment
QC_PACKAGE = "asam-qc-opendrive>=1.0,<2"
_REPO_ROOT = Path(__file__).resolve().parents[2]
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
    """The folder of ASAM OpenDRIVE XSDs bundled with the checker (``1.7.0/...``)."""
    py = python or find_qc_python()
    res = subprocess.run(
        [str(py), "-c", "import os, qc_opendrive.schema as s; print(os.path.dirname(s.__file__))"],
        capture_output=True, text=True)
    if res.returncode != 0:
        raise QCError(f"cannot locate the checker's schemas: {res.stderr.strip()[-300:]}",
                      element=str(py))
    return Path(res.stdout.strip())


def _config_xml(xodr: Path, result: Path) -> str:
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
            where += [f"line {loc.get('row')}" for loc in iss.iter("FileLocation")]
            where += [f"({loc.get('x')}, {loc.get('y')}, {loc.get('z')})"
                      for loc in iss.iter("InertialLocation")]
            issues.append(CheckerIssue(ch.get("checkerId"), _LEVELS.get(iss.get("level"), iss.get("level")),
                                       iss.get("description", ""), " ".join(w for w in where if w)))
        out.append(CheckerOutcome(ch.get("checkerId"), ch.get("status", ""), ch.get("summary", ""),
                                  tuple(issues)))
    return out


def run_asam_checker(xodr: str | os.PathLike, *, python: Path | None = None,
                     timeout_s: float = 600) -> list[CheckerOutcome]:
    """Run the ASAM OpenDRIVE checker bundle on ``xodr``.

    Returns every checker's status (``completed``, ``skipped``, ``error``)
    and issues. Raises :class:`QCError` if the tool cannot run.
    """
    py = python or find_qc_python()
    xodr = Path(xodr).resolve()
    with tempfile.TemporaryDirectory(prefix="flyover-qc-") as tmp:
        cfg, res = Path(tmp) / "config.xml", Path(tmp) / "result.xqar"
        cfg.write_text(_config_xml(xodr, res), encoding="utf-8")
        proc = subprocess.run([str(py), "-m", "qc_opendrive", "-c", str(cfg)], cwd=tmp,
                              capture_output=True, text=True, timeout=timeout_s)
        if proc.returncode != 0 or not res.exists():
            raise QCError(f"ASAM checker failed (exit {proc.returncode}): "
                          f"{proc.stderr.strip()[-400:]}", source=str(xodr))
        return parse_result(res)


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
