"""One SUMO run through ``libsumo``, in-process: the entering/leaving series and the counts.

``libsumo`` runs one simulation per process at a time: :func:`simulate`
starts it, steps it and always closes it, so runs follow each other in one
process. SUMO's warnings go to a log file that is read back for the reasons
of teleports (``wrong lane``, ``jam``, ``yield``, ``collision``).
"""

from __future__ import annotations

import logging
import os
import re
import tempfile
import time
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from flyover.errors import FlyoverError
from flyover.traffic.settings import ThroughputSettings

__all__ = ["SimulationError", "RunResult", "sumo_args", "simulate"]

log = logging.getLogger(__name__)

_TELEPORT = re.compile(r"Teleporting vehicle '[^']*'; (?:waited too long \((?P<why>[^)]*)\)|"
                       r"(?P<coll>collision))")


class SimulationError(FlyoverError):
    """SUMO could not load the network or routes, or aborted the run."""


@dataclass(frozen=True)
class RunResult:
    """What one run measured.

    Attributes
    ----------
    interval_s
        Length of the series' intervals.
    entered, left
        Vehicles inserted into / arrived out of the network in each interval.
    loaded
        Vehicles the flows generated (inserted or waiting to be).
    not_inserted
        Generated vehicles never inserted (waiting at the end, or dropped after
        ``max_depart_delay_s``).
    running
        Vehicles in the network at the end.
    teleports
        Teleports SUMO started (every reason, collisions included).
    teleport_reasons
        ``reason -> count``: ``wrong lane``, ``jam``, ``yield``, ``collision``.
    collisions
        Collisions SUMO detected.
    wall_s, cpu_s
        Wall and CPU (this process) seconds of the run, from start to close.
    """

    interval_s: float
    entered: np.ndarray
    left: np.ndarray
    loaded: int
    not_inserted: int
    running: int
    teleports: int
    teleport_reasons: dict[str, int] = field(default_factory=dict)
    collisions: int = 0
    wall_s: float = 0.0
    cpu_s: float = 0.0


def sumo_args(net: str | os.PathLike, routes: str | os.PathLike, seed: int,
              settings: ThroughputSettings, error_log: str | os.PathLike) -> list[str]:
    """SUMO's options for one run (the same for libsumo and the ``sumo`` binary)."""
    return ["-n", str(net), "-r", str(routes), "--seed", str(int(seed)),
            "--begin", "0", "--end", repr(float(settings.duration_s)),
            "--step-length", repr(float(settings.step_length_s)),
            "--time-to-teleport", repr(float(settings.time_to_teleport_s)),
            "--max-depart-delay", repr(float(settings.max_depart_delay_s)),
            "--collision.action", "teleport",
            "--no-step-log", "true", "--duration-log.disable", "true",
            "--error-log", str(error_log)]


def _reasons(log_path: Path) -> dict[str, int]:
    try:
        text = log_path.read_text(encoding="utf-8", errors="replace")
    except OSError:
        return {}
    found = Counter(m["why"] or "collision" for m in _TELEPORT.finditer(text))
    return dict(sorted(found.items()))


def simulate(net: str | os.PathLike, routes: str | os.PathLike, seed: int,
             settings: ThroughputSettings) -> RunResult:
    """Run SUMO on ``net`` with the route file ``routes`` for ``settings.duration_s``.

    Raises :class:`SimulationError` (with SUMO's message) when SUMO cannot load
    the files or aborts; libsumo is closed in every case.
    """
    import libsumo  # noqa: PLC0415

    steps_per = int(round(settings.interval_s / settings.step_length_s))
    n_steps = int(round(settings.duration_s / settings.step_length_s))
    n_int = -(-n_steps // steps_per)
    entered = np.zeros(n_int, dtype=np.int64)
    left = np.zeros(n_int, dtype=np.int64)
    loaded = teleports = collisions = 0
    t0, c0 = time.perf_counter(), time.process_time()
    with tempfile.TemporaryDirectory(prefix="flyover-sumo-") as tmp:
        elog = Path(tmp) / "sumo.log"
        try:
            libsumo.start(["sumo", *sumo_args(net, routes, seed, settings, elog)])
        except Exception as exc:  # libsumo raises TraCIException / FatalTraCIError
            _close(libsumo)
            msg = _first_error(elog) or str(exc) or type(exc).__name__
            raise SimulationError(f"SUMO cannot start: {msg}", source=str(net)) from None
        try:
            sim = libsumo.simulation
            for k in range(n_steps):
                libsumo.simulationStep()
                i = k // steps_per
                entered[i] += sim.getDepartedNumber()
                left[i] += sim.getArrivedNumber()
                loaded += sim.getLoadedNumber()
                teleports += sim.getStartingTeleportNumber()
                collisions += len(sim.getCollisions())
            departed = int(entered.sum())
            running = libsumo.vehicle.getIDCount()
        except Exception as exc:
            msg = _first_error(elog) or str(exc) or type(exc).__name__
            raise SimulationError(f"SUMO aborted the run: {msg}", source=str(net)) from None
        finally:
            _close(libsumo)
        reasons = _reasons(elog)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    return RunResult(float(settings.interval_s), entered, left, int(loaded), int(loaded - departed),
                     int(running), int(teleports), reasons, int(collisions), wall, cpu)


def _close(libsumo) -> None:
    try:
        libsumo.close()
    except Exception:  # not started, or already closed
        pass


def _first_error(log_path: Path) -> str:
    try:
        for line in log_path.read_text(encoding="utf-8", errors="replace").splitlines():
            if line.startswith("Error"):
                return line.strip()
    except OSError:
        pass
    return ""
