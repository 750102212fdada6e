"""What the report shows, read from a results folder.

Every table comes from the DuckDB views of :mod:`flyover.analytics` (the named
queries where one exists, else SQL over the same views), so what the report
shows is what ``flyover query`` prints. A table whose files are not built yet is
an :class:`Absent` naming the workflow target that builds it; the report then
says so instead of failing.
"""

from __future__ import annotations

import json
import logging
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from flyover.analytics import NAMED_QUERIES, AnalyticsError, MissingTableError, query
from flyover.errors import FlyoverError

__all__ = ["Table", "Absent", "ReportError", "Results", "display"]

log = logging.getLogger(__name__)


class ReportError(FlyoverError):
    """The report cannot be built from a results folder (e.g. a file it reads is corrupt)."""


@dataclass(frozen=True)
class Table:
    """Rows of a query, with the command that prints the same rows."""

    columns: tuple[str, ...]
    rows: tuple[tuple, ...]
    command: str

    @property
    def records(self) -> list[dict[str, Any]]:
        """The rows as dictionaries."""
        return [dict(zip(self.columns, r)) for r in self.rows]

    absent = False


@dataclass(frozen=True)
class Absent:
    """A table that is not built yet, and how to build it."""

    table: str
    target: str

    @property
    def command(self) -> str:
        return f"./dev run {self.target}"

    absent = True
    rows: tuple = ()
    records: tuple = ()


def display(value: Any, digits: int = 1) -> str:
    """A cell as text: ``—`` for missing, ``∞`` for infinity, floats rounded.

    >>> display(None), display(float("inf")), display(3.14159, 2), display(7), display(True)
    ('—', '∞', '3.14', '7', 'yes')
    """
    if value is None:
        return "—"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        if math.isnan(value):
            return "—"
        if math.isinf(value):
            return "∞" if value > 0 else "−∞"
        if value == int(value) and abs(value) < 1e15 and digits <= 1:
            return f"{int(value)}"
        return f"{value:.{digits}f}" if abs(value) >= 10 ** -digits or value == 0 else f"{value:.2g}"
    return str(value)


_CLASS_NAMES = ("(SELECT class_id, any_value(class_name) AS class_name FROM classes "
                "GROUP BY class_id)")


@dataclass
class Results:
    """A results folder and the tables read from it (each read once, on first use)."""

    root: Path
    _cache: dict[str, Table | Absent] = field(default_factory=dict)

    def __post_init__(self):
        self.root = Path(self.root)
        if not self.root.is_dir():
            raise ReportError("no such results folder", source=str(self.root))

    # -- tables ------------------------------------------------------------------------
    def sql(self, sql: str, *, named: str | None = None) -> Table | Absent:
        """The rows of ``sql`` (or of the named query ``named``) over the analytics views."""
        key = named or sql
        if key in self._cache:
            return self._cache[key]
        import duckdb  # noqa: PLC0415

        text = NAMED_QUERIES[named].sql if named else sql
        try:
            tbl = query(text, self.root)
        except MissingTableError as exc:
            result: Table | Absent = Absent(exc.table, exc.target)
        except AnalyticsError as exc:
            raise ReportError(f"query failed: {exc.reason}", source=str(self.root),
                              element=named or " ".join(text.split())[:80]) from None
        except duckdb.Error as exc:  # a table that cannot be read (made into a view)
            raise ReportError(f"unreadable table: {str(exc).splitlines()[0]}",
                              source=str(self.root)) from None
        else:
            command = f"flyover query --named {named}" if named else \
                "flyover query " + json.dumps(" ".join(text.split()))
            result = Table(tuple(tbl.column_names),
                           tuple(tuple(r.values()) for r in tbl.to_pylist()), command)
        self._cache[key] = result
        return result

    def named(self, name: str) -> Table | Absent:
        """A named query of ``flyover query --list``."""
        return self.sql("", named=name)

    def by_class(self, table: Table | Absent) -> dict[str, list[dict]]:
        """The records of ``table`` grouped by their ``class_id``."""
        out: dict[str, list[dict]] = {}
        for r in table.records:
            out.setdefault(r["class_id"], []).append(r)
        return out

    # -- files ---------------------------------------------------------------------------
    def exists(self, relpath: str) -> bool:
        """Whether ``relpath`` (under the results folder) is a file."""
        return (self.root / relpath).is_file()

    def read_json(self, relpath: str) -> Any | None:
        """A JSON file under the results folder, ``None`` when absent."""
        path = self.root / relpath
        if not path.is_file():
            return None
        try:
            return json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:
            raise ReportError(f"unreadable JSON: {exc}", source=str(path)) from None

    def cities(self) -> list[dict]:
        """Per city (``results/topology/{city}/index.json``): its interchanges, each with
        its OSM picture when it has one (``{name}.png`` beside its GraphML)."""
        out = []
        folder = self.root / "topology"
        for index in sorted(folder.glob("*/index.json")) if folder.is_dir() else ():
            data = self.read_json(os.path.relpath(index, self.root)) or {}
            city = index.parent.name
            items = []
            for it in data.get("interchanges", []):
                name = str(it.get("interchange", ""))
                picture = f"topology/{city}/{name}.png"
                items.append({"name": name, "source_file": it.get("source_file", ""),
                              "graphml": f"topology/{city}/{name}.graphml",
                              "picture": picture if self.exists(picture) else None,
                              "name_from": it.get("name_from")})
            out.append({"city": city, "interchanges": items,
                        "rejected": data.get("rejected", [])})
        return out

    def manifest(self) -> dict[str, dict]:
        """``results/classes/manifest.json``'s classes (empty when not built)."""
        data = self.read_json("classes/manifest.json") or {}
        return dict(sorted(data.get("classes", {}).items(),
                           key=lambda kv: (kv[1].get("class_name", ""), kv[0])))

    def samples(self, class_id: str) -> list[int]:
        """The samples of a class that have a folder under ``results/interchanges``."""
        folder = self.root / "interchanges" / class_id
        if not folder.is_dir():
            return []
        return sorted(int(p.name) for p in folder.iterdir() if p.is_dir() and p.name.isdigit())
