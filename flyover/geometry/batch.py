"""The geometry stage of one class in one process: every feature set → its ``geometry.json``.

The workflow runs one job per class (process start-up and imports are paid
once per class, not per interchange). The job's declared output is the class's
rows of ``geometry.parquet`` (``results/geometry/{class_id}.parquet``); beside
it the job writes ``results/interchanges/{class_id}/{sample}/geometry.json``
for every sample, each atomically, and removes the folders of samples the
class no longer has, so that ``results/`` holds exactly what the feature sets
say. An interchange that cannot be built is rows (every ramp ``ok = False``,
``infeasible`` the one-line reason) and no ``geometry.json``; the others are
still built.
"""

from __future__ import annotations

import logging
import math
import os
import re
import shutil
import time
from functools import partial
from pathlib import Path

from flyover.errors import FlyoverError
from flyover.geometry.layout import LayoutSettings
from flyover.geometry.tables import (
    GEOMETRY_SCHEMA, GEOMETRY_TIMING_SCHEMA, build_sample, domain_resampler, geometry_rows, read_feature_sets,
    sample_seed,
)
from flyover.geometry.model import write_geometry
from flyover.parallel import map_ordered
from flyover.progress import Progress
from flyover.topology.io import read_graphml, remove_stale_temporaries
from flyover.topology.tables import write_parquet

__all__ = ["build_class", "failed_rows", "remove_stale_samples"]

log = logging.getLogger(__name__)

_SAMPLE_DIR = re.compile(r"^[0-9]+$")


def failed_rows(class_id: str, sample: int, ramps, reason: str) -> list[dict]:
    """Rows of an interchange that could not be built: every ramp failed with ``reason``.

    ``ramps`` maps ramp id → its :class:`~flyover.geometry.layout.RampFeatures` targets.
    """
    nan = math.nan
    return [{"class_id": class_id, "sample": int(sample), "ramp": r,
             "target_radius_m": f.radius_m, "target_slope_pct": f.slope_pct,
             "min_radius_m": nan, "max_slope_pct": nan, "length_m": nan, "ok": False,
             "evaluations": 0, "seconds": 0.0, "first_try_ok": False, "resamples": 0,
             "infeasible": reason, "conflicts": 0, "first_target_radius_m": f.radius_m,
             "first_target_slope_pct": f.slope_pct}
            for r, f in sorted(ramps.items())]


def remove_stale_samples(folder: str | os.PathLike, samples) -> list[str]:
    """Remove the sample folders of ``folder`` (numeric names only) not in ``samples``."""
    folder, keep, removed = Path(folder), {str(int(s)) for s in samples}, []
    if folder.is_dir():
        for d in sorted(folder.iterdir()):
            if d.is_dir() and _SAMPLE_DIR.match(d.name) and d.name not in keep:
                shutil.rmtree(d)
                removed.append(d.name)
    return removed


def _build_one(topo, feature_sets, folder: Path, class_id: str, seed: int,
               settings: LayoutSettings, sample: int) -> tuple[list[dict], bool]:
    """One sample: its geometry.json written, its rows (with timings) and whether it was built."""
    fs = feature_sets[sample]
    t0 = time.process_time()
    path = folder / str(sample) / "geometry.json"
    try:
        ic = build_sample(topo, fs, class_id=class_id, sample=sample, seed=seed,
                          settings=settings,
                          resampler=domain_resampler(feature_sets, sample_seed(seed, class_id, sample),
                                                     topo, settings, sample))
        write_geometry(ic.geometry, path)
    except Exception as exc:  # noqa: BLE001 - one interchange's failure is its rows
        if isinstance(exc, FlyoverError):
            reason = exc.one_line()
            log.error("%s: not built: %s", path, reason)
        else:
            reason = f"{type(exc).__name__}: {exc}"
            log.exception("%s: not built", path)
        Path(path).unlink(missing_ok=True)
        return failed_rows(class_id, sample, fs[1], f"not built: {reason}"), False
    for o in ic.outcomes:
        if o.infeasible:
            log.warning("%s sample %d ramp %s: %s", class_id, sample, o.ramp, o.infeasible)
    log.info("%s: %d ramps, %.2f s CPU", path, len(ic.outcomes), time.process_time() - t0)
    return geometry_rows(ic), True


def build_class(topology: str | os.PathLike, features: str | os.PathLike,
                table: str | os.PathLike, folder: str | os.PathLike, *, class_id: str,
                seed: int, settings: LayoutSettings, timing: str | os.PathLike | None = None,
                name: str = "", workers: int = 1) -> list[dict]:
    """Build every feature set of one class; write each ``geometry.json`` and the class table.

    Parameters
    ----------
    topology, features
        The class's topology GraphML and its feature sets (``features/{class_id}.parquet``).
    table
        Where the class's rows of ``geometry.parquet`` go (written last).
    folder
        ``results/interchanges/{class_id}``: ``{sample}/geometry.json`` is written in it.
    timing
        Where each ramp's fitting seconds go (:data:`GEOMETRY_TIMING_SCHEMA`), kept out of
        ``table`` so that it is the same bytes in every run.
    workers
        Processes to build in (:func:`flyover.parallel.map_ordered`); the same bytes for any.

    Returns the rows written to ``table``.
    """
    topo = read_graphml(topology)
    feature_sets = read_feature_sets(features)
    folder = Path(folder)
    for stale in remove_stale_samples(folder, feature_sets):
        log.info("removed %s/%s: the class has no such sample any more", folder, stale)
    # a killed run of this class (the first stage of its chain: no other job writes here now)
    left = remove_stale_temporaries(folder)
    for out in (table, timing) if timing is not None else (table,):
        left += remove_stale_temporaries(Path(out).parent, Path(out).name)
    for path in left:
        log.info("removed %s: left by a killed run", path)
    progress = Progress("geometry", f"{class_id} {name}".strip(), len(feature_sets))
    rows: list[dict] = []
    build = partial(_build_one, topo, feature_sets, folder, class_id, seed, settings)
    for one, ok in map_ordered(build, sorted(feature_sets), workers):
        rows += one
        progress.done(ok=ok)
    if timing is not None:
        write_parquet(rows, GEOMETRY_TIMING_SCHEMA, timing)
    write_parquet(rows, GEOMETRY_SCHEMA, table)
    return rows
