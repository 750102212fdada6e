"""The AV-research clients of our OpenDRIVE as external tools, in their own environment.

CommonRoad Scenario Designer (OpenDRIVE → CommonRoad lanelets, its map
verifier, its Lanelet2 export), Lanelet2 (load, routing graph), pyopendrive
and pyxodr pin other versions of numpy, shapely and friends than flyover, and
pyopendrive needs Python ≥ 3.12: they live in ``.venv-clients`` (or wherever
``FLYOVER_CLIENTS_PYTHON`` points). :func:`setup_clients_venv` creates it
idempotently (a stamp file names the installed requirements);
:func:`run_clients` runs ``_driver.py`` there once for a batch of files and
returns its JSON answers; :func:`routed_movements` turns the Lanelet2 routing
answer into (entrance road, exit road) movements of the interchange, found by
where the lanelets begin and end in our own ``.xodr``.
"""

from __future__ import annotations

import json
import logging
import math
import os
import shutil
import subprocess
import venv
from pathlib import Path
from typing import Iterable, Mapping

from flyover.errors import FlyoverError
from flyover.opendrive.reader import XodrNetwork

__all__ = ["ClientsError", "CLIENT_PACKAGES", "find_clients_python", "setup_clients_venv",
           "run_clients", "routed_movements", "road_ends", "two_movement_trips"]

log = logging.getLogger(__name__)

#: what the clients' environment holds (the stamp records this list)
CLIENT_PACKAGES = ("commonroad-scenario-designer==0.8.5", "lanelet2==1.2.3", "pyopendrive==0.2.0",
                   "pyxodr==0.1.3")
#: the interpreter the environment is made with: pyopendrive needs >= 3.12,
#: commonroad-scenario-designer 0.8.5 and lanelet2 1.2.3 have wheels for 3.12
PYTHON_VERSION = "3.12"
_REPO_ROOT = Path(__file__).resolve().parents[2]
_DRIVER = Path(__file__).with_name("_driver.py")
_STAMP = ".flyover-clients"


class ClientsError(FlyoverError):
    """The clients' environment is missing or a client run failed."""


def _root(path: str | os.PathLike | None) -> Path:
    return Path(path) if path else _REPO_ROOT / ".venv-clients"


def find_clients_python(path: str | os.PathLike | None = None) -> Path:
    """The python of the clients' environment (``FLYOVER_CLIENTS_PYTHON`` or ``.venv-clients``).

    Raises
    ------
    ClientsError
        When the environment is not installed (its stamp is missing or stale).
    """
    env = os.environ.get("FLYOVER_CLIENTS_PYTHON")
    if env and not path:
        if Path(env).exists():
            return Path(env)
        raise ClientsError(f"FLYOVER_CLIENTS_PYTHON={env} does not exist", element="clients")
    root = _root(path)
    py = root / "bin" / "python"
    stamp = root / _STAMP
    if py.exists() and stamp.exists() and stamp.read_text().split() == list(CLIENT_PACKAGES):
        return py
    raise ClientsError(f"clients' environment not installed at {root}: run "
                       "`python -m flyover.clients.setup`", element="clients")


def _interpreter() -> str:
    """A python of :data:`PYTHON_VERSION` (``FLYOVER_CLIENTS_INTERPRETER`` overrides)."""
    env = os.environ.get("FLYOVER_CLIENTS_INTERPRETER")
    if env:
        return env
    found = shutil.which(f"python{PYTHON_VERSION}")
    if found and subprocess.run([found, "-c", "pass"], capture_output=True).returncode == 0:
        return found
    pyenv = shutil.which("pyenv")
    if pyenv:
        res = subprocess.run([pyenv, "root"], capture_output=True, text=True)
        for cand in sorted(Path(res.stdout.strip(), "versions").glob(f"{PYTHON_VERSION}.*"),
                           reverse=True):
            if (cand / "bin" / "python3").exists():
                return str(cand / "bin" / "python3")
    raise ClientsError(f"no Python {PYTHON_VERSION} found for the clients' environment "
                       "(set FLYOVER_CLIENTS_INTERPRETER)", element="clients")


def setup_clients_venv(path: str | os.PathLike | None = None) -> Path:
    """Create the clients' environment at ``path`` (default ``<repo>/.venv-clients``) if needed.

    Idempotent and fast when installed: a stamp file listing
    :data:`CLIENT_PACKAGES` says so without starting any python. Returns the
    environment's python.
    """
    root = _root(path)
    try:
        return find_clients_python(root)
    except ClientsError:
        pass
    py = root / "bin" / "python"
    if not py.exists():
        subprocess.run([_interpreter(), "-m", "venv", str(root)], check=True)
    if not py.exists():  # pragma: no cover - venv module without ensurepip
        venv.EnvBuilder(with_pip=True).create(root)
    log.info("installing %s into %s", " ".join(CLIENT_PACKAGES), root)
    subprocess.run([str(py), "-m", "pip", "install", "--quiet", *CLIENT_PACKAGES], check=True)
    (root / _STAMP).write_text("\n".join(CLIENT_PACKAGES) + "\n")
    return py


def run_clients(jobs: Iterable[Mapping], python: Path | None = None,
                timeout_s: float | None = None) -> list[dict]:
    """Run the clients on each job in one process of their environment.

    A job is ``{"xodr": path, "commonroad": path|None, "lanelet2": path|None,
    "lanelet2_shared_nodes": path|None, "verify": bool, "routing": bool,
    "pyopendrive": bool, "pyxodr": bool}``; ``lanelet2_shared_nodes`` writes the Lanelet2
    map again with the converter's nodes shared by position (a point where two
    lanelets from different predecessors meet is one node: the driver's
    ``_nodes_shared_by_position``). The answer per job holds one entry per client run
    (``ok``, its figures or ``error``/``where``) and ``seconds`` per client.
    """
    jobs = [{k: (str(v) if isinstance(v, os.PathLike) else v) for k, v in j.items()} for j in jobs]
    py = python or find_clients_python()
    res = subprocess.run([str(py), str(_DRIVER)], input=json.dumps({"jobs": jobs}),
                         capture_output=True, text=True, timeout=timeout_s)
    lines = [ln for ln in res.stdout.splitlines() if ln.startswith("{")]
    if res.returncode != 0 or len(lines) != len(jobs):
        raise ClientsError(f"clients' driver failed ({res.returncode}): "
                           f"{res.stderr.strip()[-600:]}", element=str(py))
    return [json.loads(ln) for ln in lines]


def road_ends(net: XodrNetwork) -> tuple[list[tuple[str, tuple[float, float]]],
                                         list[tuple[str, tuple[float, float]]]]:
    """Lane-centre points where the interchange begins (entrances) and ends (exits).

    ``([(road name, (x, y)), ...], [...])``: every lane at the start of a road
    without predecessor, and at the end of a road without successor.
    """
    starts, ends = [], []
    for road in net.roads.values():
        for at_end, link, out in ((False, road.predecessor, starts), (True, road.successor, ends)):
            if link is not None:
                continue
            s = road.length if at_end else 0.0
            for lid in road.section_at(s, at_end).lanes:
                p = road.lane_point(lid, s, at_end)
                if p is not None:
                    out.append((road.name, (p[0], p[1])))
    return starts, ends


def _nearest(points: list[tuple[str, tuple[float, float]]], xy, tol_m: float) -> str | None:
    best = min(points, key=lambda p: math.dist(p[1], xy), default=None)
    return best[0] if best is not None and math.dist(best[1], xy) <= tol_m else None


def routed_movements(answer: Mapping, net: XodrNetwork, tol_m: float = 0.5
                     ) -> dict[tuple[str, str], int]:
    """Movements the Lanelet2 routing graph routes: ``{(entrance, exit): lane routes}``.

    A route counts when its first lanelet begins on a lane of an entrance road
    and its last ends on a lane of an exit road (within ``tol_m``); lanelets
    that begin or end inside the interchange (auxiliary lanes opening from or
    closing to zero width) are not entrances or exits.
    """
    starts, ends = road_ends(net)
    src = {int(k): _nearest(starts, v, tol_m) for k, v in answer["sources"].items()}
    dst = {int(k): _nearest(ends, v, tol_m) for k, v in answer["sinks"].items()}
    out: dict[tuple[str, str], int] = {}
    for a, b in answer["routes"]:
        u, v = src.get(int(a)), dst.get(int(b))
        if u is not None and v is not None:
            out[(u, v)] = out.get((u, v), 0) + 1
    return out


def two_movement_trips(extra: Iterable[tuple[str, str]], movements: Iterable[tuple[str, str]]
                       ) -> dict[tuple[str, str], str]:
    """Which of ``extra`` are two movements in a row through one road: ``{(u, w): v}``.

    A router that may change lanes finds U-turns the topology's movements leave
    out (they follow ramps only): into road ``v`` by one ramp and out of it by
    the next, through the auxiliary lane of a weaving section.
    """
    mv = set(movements)
    out = {}
    for u, w in extra:
        via = sorted(v for (a, v) in mv if a == u and (v, w) in mv and v not in (u, w))
        if via:
            out[(u, w)] = via[0]
    return out
