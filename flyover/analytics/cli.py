"""``flyover query``: SQL over the results tables (DuckDB)."""

from __future__ import annotations

import argparse
import sys

__all__ = ["register"]


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "query", help="SQL over the results tables (DuckDB views)",
        description="Run SQL over the views classes, rejected, features, coverage, geometry, "
                    "validation, throughput, throughput_stats and fuel (Parquet read where it "
                    "lies, hive partitions as such), or a named query.")
    p.add_argument("sql", nargs="?", help="the SQL to run")
    p.add_argument("--named", metavar="NAME", help="run a named query (see --list)")
    p.add_argument("--list", action="store_true", help="list the named queries and views")
    p.add_argument("--format", choices=("table", "csv", "json"), default="table")
    p.add_argument("--results", default="results", metavar="DIR",
                   help="the results folder (default: results)")
    p.set_defaults(func=_run)


def _table(tbl) -> str:
    cols = tbl.column_names
    rows = [[("" if v is None else (f"{v:.6g}" if isinstance(v, float) else str(v)))
             for v in r.values()] for r in tbl.to_pylist()]
    widths = [max([len(c)] + [len(r[i]) for r in rows]) for i, c in enumerate(cols)]
    line = "  ".join(c.ljust(w) for c, w in zip(cols, widths))
    out = [line, "  ".join("-" * w for w in widths)]
    out += ["  ".join(v.ljust(w) for v, w in zip(r, widths)) for r in rows]
    out.append(f"({len(rows)} row{'s' if len(rows) != 1 else ''})")
    return "\n".join(out)


def _run(args: argparse.Namespace) -> int:
    from flyover.analytics.queries import NAMED_QUERIES  # noqa: PLC0415
    from flyover.analytics.views import VIEWS, AnalyticsError, query  # noqa: PLC0415

    if args.list:
        print("named queries (flyover query --named NAME):")
        for q in NAMED_QUERIES.values():
            print(f"  {q.name:22s} {q.description}")
        print("views:")
        for v in VIEWS:
            print(f"  {v.name:22s} {' | '.join(v.patterns)}  (made by: {v.target})")
        return 0
    if args.named:
        if args.named not in NAMED_QUERIES:
            raise AnalyticsError(f"no named query {args.named!r} (flyover query --list)",
                                 element=args.named)
        sql = NAMED_QUERIES[args.named].sql
    elif args.sql:
        sql = args.sql
    else:
        print("error: give SQL, --named NAME or --list", file=sys.stderr)
        return 2
    tbl = query(sql, args.results)
    if args.format == "csv":
        import pyarrow.csv as pacsv  # noqa: PLC0415

        pacsv.write_csv(tbl, sys.stdout.buffer)
    elif args.format == "json":
        import json  # noqa: PLC0415

        import math  # noqa: PLC0415

        def _json(v):  # valid JSON: NaN → null, ±inf → "inf"/"-inf" (as geometry.json)
            if isinstance(v, float) and not math.isfinite(v):
                return None if math.isnan(v) else ("inf" if v > 0 else "-inf")
            return v

        rows = [{k: _json(v) for k, v in r.items()} for r in tbl.to_pylist()]
        json.dump(rows, sys.stdout, indent=1, default=str)
        print()
    else:
        print(_table(tbl))
    return 0
