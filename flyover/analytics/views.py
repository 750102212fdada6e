"""The views of ``flyover query``: each results table, read where it lies.

Example
-------
>>> import tempfile
>>> with tempfile.TemporaryDirectory() as d:
...     try:
...         query("select count(*) from fuel", d)
...     except MissingTableError as exc:
...         print(exc.table, exc.target)
fuel plugins
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path

from flyover.errors import FlyoverError

__all__ = ["TableSource", "VIEWS", "AnalyticsError", "MissingTableError", "connect", "query"]


class AnalyticsError(FlyoverError):
    """A query cannot run: bad SQL, or a table it reads is not built yet."""


class MissingTableError(AnalyticsError):
    """A view's Parquet files do not exist yet; names the workflow target that makes them."""

    def __init__(self, table: str, pattern: str, target: str, results_dir: str):
        self.table, self.pattern, self.target = table, pattern, target
        super().__init__(
            f"table {table!r} is not built yet (no {pattern} under {results_dir}); "
            f"make it with: ./dev run {target}", element=table)


@dataclass(frozen=True)
class TableSource:
    """Where a view's files lie (globs relative to the results folder, first match wins),
    whether they are hive-partitioned, and the workflow target that writes them."""

    name: str
    patterns: tuple[str, ...]
    target: str
    hive: bool = False


#: the views, in the order of DESIGN.md's tables
VIEWS: tuple[TableSource, ...] = (
    TableSource("classes", ("classes.parquet",), "topology"),
    TableSource("rejected", ("rejected.parquet",), "topology"),
    TableSource("features", ("features/*.parquet",), "sampling"),
    TableSource("coverage", ("coverage.parquet", "coverage/*.parquet"), "sampling"),
    TableSource("geometry", ("geometry.parquet", "geometry/*.parquet"), "geometry"),
    TableSource("geometry_timing", ("geometry_timing.parquet", "geometry_timing/*.parquet"),
                "geometry"),
    TableSource("validation", ("validation.parquet", "validation/*.parquet"), "validation"),
    TableSource("throughput", ("throughput.parquet", "throughput/c*.parquet"), "throughput"),
    TableSource("throughput_stats", ("throughput_stats.parquet",), "throughput"),
    TableSource("fuel", ("fuel/class_id=*/sample=*/*.parquet",), "plugins", hive=True),
)

_BY_NAME = {v.name: v for v in VIEWS}


def _files(results: Path, src: TableSource) -> str | None:
    for pattern in src.patterns:
        if any(results.glob(pattern)):
            return pattern
    return None


def _sql_str(s: str) -> str:
    return "'" + s.replace("'", "''") + "'"


def _referenced(sql: str) -> set[str]:
    """The view names that occur as words in ``sql`` (a superset of those it reads)."""
    words = {w.lower() for w in re.findall(r"[A-Za-z_][A-Za-z0-9_]*", sql)}
    return {v.name for v in VIEWS if v.name in words}


def connect(results_dir: str | os.PathLike = "results", names: set[str] | None = None):
    """An in-memory DuckDB connection with a view per table that exists.

    Only the views in ``names`` are made (default: all). Returns
    ``(connection, missing)`` where ``missing`` maps the name of each wanted view
    whose files are absent to its :class:`TableSource`.
    """
    import duckdb  # noqa: PLC0415

    results = Path(results_dir)
    con = duckdb.connect(":memory:")
    missing = {}
    for src in VIEWS:
        if names is not None and src.name not in names:
            continue
        pattern = _files(results, src)
        if pattern is None:
            missing[src.name] = src
            continue
        glob = _sql_str(str(results / pattern))
        # a plugin's partitions share one schema: no union_by_name (it reads every footer)
        opts = "hive_partitioning = true" if src.hive else \
            "hive_partitioning = false, union_by_name = true"
        con.execute(f"CREATE VIEW {src.name} AS SELECT * FROM read_parquet({glob}, {opts})")
    return con, missing


_MISSING = re.compile(r"Table with name (\w+) does not exist", re.I)


def query(sql: str, results_dir: str | os.PathLike = "results"):
    """Run ``sql`` over the views of ``results_dir``; a :class:`pyarrow.Table`.

    Raises
    ------
    MissingTableError
        When the SQL reads a view whose files are not built yet.
    AnalyticsError
        For any other error DuckDB reports (the message is DuckDB's).
    """
    import duckdb  # noqa: PLC0415

    con, missing = connect(results_dir, _referenced(sql))
    try:
        return con.execute(sql).to_arrow_table()
    except duckdb.CatalogException as exc:
        m = _MISSING.search(str(exc))
        if m and m.group(1).lower() in missing:
            src = missing[m.group(1).lower()]
            raise MissingTableError(src.name, " or ".join(src.patterns), src.target,
                                    str(results_dir)) from None
        raise AnalyticsError(str(exc).splitlines()[0], element="sql") from None
    except duckdb.Error as exc:
        raise AnalyticsError(str(exc).splitlines()[0], element="sql") from None
    finally:
        con.close()
