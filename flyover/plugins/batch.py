"""Evaluate many interchanges with the installed plugins in one process.

One process per class (not per interchange) keeps interpreter and plugin
start-up (imports, model building) off the per-interchange cost. Each
interchange's rows go to a hive partition, written atomically (temporary file
in the same folder, then :func:`os.replace`)::

    {results}/{table}/class_id={class_id}/sample={sample}/part-0.parquet

The partition files hold every column except ``class_id`` and ``sample``
(hive readers such as DuckDB restore them from the path). An interchange a
plugin cannot evaluate is logged and counted (and recorded as rows when the
plugin provides ``failure_rows``); it never stops the others.
"""

from __future__ import annotations

import logging
import os
import re
import shutil
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence

import pyarrow as pa
import pyarrow.parquet as pq

from flyover.errors import FlyoverError
from flyover.geometry.model import read_geometry
from flyover.parallel import map_ordered
from flyover.plugins.api import PluginError, plugin_config
from flyover.plugins.registry import installed_plugins, load_plugin
from flyover.topology.io import file_mode

__all__ = ["PARTITION_KEYS", "PluginRun", "ClassRun", "run_plugins_on_class", "write_partition",
           "partition_path"]


log = logging.getLogger(__name__)

#: the hive partition columns, in path order
PARTITION_KEYS = ("class_id", "sample")
_SAFE = re.compile(r"^[A-Za-z0-9_.-]+$")


@dataclass(frozen=True)
class PluginRun:
    """What one plugin did on one batch: rows written, failures, CPU seconds."""

    plugin: str
    version: str
    table: str
    rows: int
    interchanges: int
    failures: tuple[tuple[str, str], ...] = ()
    cpu_s: float = 0.0


@dataclass(frozen=True)
class ClassRun:
    """The outcome of :func:`run_plugins_on_class`, one :class:`PluginRun` per plugin."""

    runs: tuple[PluginRun, ...] = field(default_factory=tuple)

    @property
    def failures(self) -> int:
        """Number of (plugin, interchange) evaluations that failed."""
        return sum(len(r.failures) for r in self.runs)


def partition_path(results_dir: str | os.PathLike, table: str, class_id: str,
                   sample: int) -> Path:
    """Where the rows of one interchange go."""
    return (Path(results_dir) / table / f"class_id={class_id}" / f"sample={int(sample)}"
            / "part-0.parquet")


def _write_atomic(table: pa.Table, path: Path) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    os.close(fd)
    try:
        pq.write_table(table, tmp, compression="zstd")
        os.chmod(tmp, file_mode())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_partition(rows: Sequence[Mapping[str, Any]], schema: pa.Schema,
                    results_dir: str | os.PathLike, table: str, class_id: str,
                    sample: int) -> Path:
    """Write one interchange's rows (``schema`` includes the partition columns).

    Returns the path written. Rows missing a column get nulls; extra keys are
    ignored.
    """
    if not _SAFE.match(str(class_id)):
        raise PluginError(f"class id {class_id!r} cannot name a partition", element=table)
    data = pa.Table.from_pylist([dict(r) for r in rows], schema=schema)
    keep = [n for n in schema.names if n not in PARTITION_KEYS]
    path = partition_path(results_dir, table, class_id, sample)
    _write_atomic(data.select(keep), path)
    return path


def _ids_from_path(path: Path) -> tuple[str, int]:
    """``(class_id, sample)`` from ``…/{class_id}/{sample}/geometry.json``."""
    try:
        return path.parent.parent.name, int(path.parent.name)
    except ValueError:
        return path.parent.parent.name, -1


def _prune(results_dir: Path, table: str, class_id: str, keep: set[int]) -> None:
    root = results_dir / table / f"class_id={class_id}"
    if not root.is_dir():
        return
    for part in root.glob("sample=*"):
        try:
            stale = int(part.name.split("=", 1)[1]) not in keep
        except ValueError:
            stale = True
        if stale:
            log.info("removing stale partition %s", part)
            shutil.rmtree(part, ignore_errors=True)


#: (plugins, their configs, their schemas, results folder) of the batch being run
_BATCH: tuple | None = None


def _evaluate_one(path: str) -> tuple[str, int, dict[str, tuple[list[dict], tuple | None, float]]]:
    """Every plugin of the running batch on one ``geometry.json``; its partitions written."""
    loaded, cfgs, schemas, results_dir = _BATCH
    path = Path(path)
    class_id, sample = _ids_from_path(path)
    try:
        geometry = read_geometry(path)
        class_id, sample = geometry.class_id, geometry.sample
        load_error = None
    except FlyoverError as exc:
        geometry, load_error = None, exc.one_line()
    except OSError as exc:
        geometry, load_error = None, f"cannot read geometry.json: {exc.strerror or exc}"
    out = {}
    for p in loaded:
        t0 = time.process_time()
        if geometry is not None:
            try:
                rows = list(p.evaluate(geometry, cfgs[p.name]))
                reason = None
            except Exception as exc:  # noqa: BLE001 - one interchange never stops the batch
                log.exception("plugin %s failed on %s", p.name, path)
                rows, reason = [], f"{type(exc).__name__}: {exc}"
        else:
            rows, reason = [], load_error
        if reason is not None:
            log.error("plugin %s: %s: %s", p.name, path, reason)
            if hasattr(p, "failure_rows"):
                rows = list(p.failure_rows(class_id, sample, reason))
        for r in rows:
            r.setdefault("class_id", class_id)
            r.setdefault("sample", sample)
        seconds = time.process_time() - t0
        write_partition(rows, schemas[p.name], results_dir, p.table, class_id, sample)
        out[p.name] = (rows, None if reason is None else (str(path), reason), seconds)
    return class_id, sample, out


def run_plugins_on_class(geometry_paths: Iterable[str | os.PathLike],
                         results_dir: str | os.PathLike, *,
                         config: Mapping[str, Mapping[str, Any]] | None = None,
                         plugins: Sequence[Any] | None = None,
                         class_tables: Mapping[str, str | os.PathLike] | None = None,
                         prune: bool = True, config_source: str | None = None,
                         workers: int = 1) -> ClassRun:
    """Evaluate every interchange in ``geometry_paths`` with every plugin.

    Parameters
    ----------
    geometry_paths
        ``geometry.json`` files (normally one class's, ``…/{class_id}/{sample}/``).
    results_dir
        Root of the hive tables (``results``).
    config
        The ``plugins:`` section of the workflow config: plugin name → its
        section (validated against the plugin's schema, defaults filled).
    plugins
        Plugin objects or names; default every installed plugin (broken ones
        skipped with a warning).
    class_tables
        Plugin name → a Parquet file that receives all of this batch's rows of
        that plugin, with every column (the workflow's per-class output).
    prune
        Remove partitions of the classes seen here whose sample is not in the
        batch (left by an earlier run with more samples).
    workers
        Forked processes sharing the interchanges (the same rows for any number).

    Returns
    -------
    ClassRun
        Rows and failures per plugin.

    Raises
    ------
    PluginError, ConfigError
        Only for a plugin named in ``plugins`` that cannot be loaded or a bad
        config section; a failing interchange is logged, never raised.
    """
    results_dir = Path(results_dir)
    config = config or {}
    if plugins is None:
        loaded = list(installed_plugins().values())
    else:
        loaded = [load_plugin(p) if isinstance(p, str) else p for p in plugins]
    cfgs = {p.name: plugin_config(p.config_schema(), config.get(p.name), plugin=p.name,
                                  source=config_source) for p in loaded}
    schemas = {p.name: p.schema() for p in loaded}
    all_rows: dict[str, list[dict[str, Any]]] = {p.name: [] for p in loaded}
    failures: dict[str, list[tuple[str, str]]] = {p.name: [] for p in loaded}
    cpu = {p.name: 0.0 for p in loaded}
    seen: dict[str, set[int]] = {}
    n = 0
    global _BATCH  # what forked workers evaluate with (plugin objects need not pickle)
    _BATCH = (loaded, cfgs, schemas, results_dir)
    try:
        for class_id, sample, outcomes in map_ordered(_evaluate_one, list(map(str, geometry_paths)),
                                                      workers):
            n += 1
            seen.setdefault(class_id, set()).add(sample)
            for name, (rows, failure, seconds) in outcomes.items():
                if failure is not None:
                    failures[name].append(failure)
                cpu[name] += seconds
                all_rows[name].extend(rows)
    finally:
        _BATCH = None
    if prune:
        for p in loaded:
            for class_id, samples in seen.items():
                _prune(results_dir, p.table, class_id, samples)
    for name, path in (class_tables or {}).items():
        if name not in all_rows:
            raise PluginError("no such plugin in this batch", element=name)
        _write_atomic(pa.Table.from_pylist(all_rows[name], schema=schemas[name]), Path(path))
    runs = tuple(PluginRun(p.name, p.version, p.table, len(all_rows[p.name]), n,
                           tuple(failures[p.name]), cpu[p.name]) for p in loaded)
    for r in runs:
        log.info("plugin %s %s: %d interchanges, %d rows, %d failed, %.2f s CPU", r.plugin,
                 r.version, r.interchanges, r.rows, len(r.failures), r.cpu_s)
    return ClassRun(runs)
