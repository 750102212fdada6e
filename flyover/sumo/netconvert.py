"""Run SUMO's ``netconvert`` (from the ``eclipse-sumo`` wheel) on an OpenDRIVE file.

Example
-------
>>> from flyover.sumo.netconvert import netconvert_command
>>> netconvert_command("in.xodr", "out.net.xml")[1:3]
['--opendrive-files', 'in.xodr']
"""

from __future__ import annotations

import logging
import os
import subprocess
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import sumolib

from flyover.errors import FlyoverError
from flyover.topology.io import file_mode

__all__ = ["NetconvertResult", "NetconvertError", "netconvert_command", "run_netconvert"]

log = logging.getLogger(__name__)


class NetconvertError(FlyoverError):
    """netconvert could not be run."""


@dataclass(frozen=True)
class NetconvertResult:
    """Outcome of one netconvert run: errors and warnings are its own messages."""

    ok: bool
    errors: tuple[str, ...]
    warnings: tuple[str, ...]
    seconds: float


def netconvert_command(xodr: str | os.PathLike, net: str | os.PathLike) -> list[str]:
    """The netconvert command line used for every interchange."""
    return [sumolib.checkBinary("netconvert"), "--opendrive-files", str(xodr),
            "--output-file", str(net), "--opendrive.import-all-lanes", "false",
            "--offset.disable-normalization", "true", "--no-turnarounds", "true",
            "--output.original-names", "true", "--opendrive.position-ids", "false",
            "--xml-validation", "never", "--seed", "0"]


def run_netconvert(xodr: str | os.PathLike, net: str | os.PathLike, timeout_s: float = 600
                   ) -> NetconvertResult:
    """Convert ``xodr`` to a SUMO network at ``net`` (written atomically).

    ``ok`` is False when netconvert exits non-zero or prints an ``Error:``.
    """
    net = Path(net)
    net.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=net.parent, prefix=f".{net.name}.", suffix=".tmp.net.xml")
    os.close(fd)
    t0 = time.perf_counter()
    try:
        proc = subprocess.run(netconvert_command(xodr, tmp), capture_output=True, text=True,
                              timeout=timeout_s)
    except (OSError, subprocess.TimeoutExpired) as exc:
        Path(tmp).unlink(missing_ok=True)
        raise NetconvertError(f"netconvert failed to run: {exc}", source=str(xodr)) from None
    dt = time.perf_counter() - t0
    lines = (proc.stdout + "\n" + proc.stderr).splitlines()
    errors = tuple(ln.strip() for ln in lines if ln.strip().startswith("Error"))
    warnings = tuple(ln.strip() for ln in lines if ln.strip().startswith("Warning"))
    ok = proc.returncode == 0 and not errors and Path(tmp).stat().st_size > 0
    if ok:
        os.chmod(tmp, file_mode())
        os.replace(tmp, net)
    else:
        Path(tmp).unlink(missing_ok=True)
        if proc.returncode != 0 and not errors:
            errors = (f"exit status {proc.returncode}",)
    return NetconvertResult(ok, errors, warnings, dt)
