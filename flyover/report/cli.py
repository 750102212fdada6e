"""``flyover report``: the dataset browser (static HTML) of a results folder."""

from __future__ import annotations

import argparse

__all__ = ["register"]


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "report", help="static HTML report of a results folder (the dataset browser)",
        description="Write the dataset browser of a results folder: an overview, a page per "
                    "class and per interchange (interactive plan view), and the evaluation. "
                    "Open index.html from disk; no server is needed. Stages not built yet "
                    "are named with the target that builds them.")
    p.add_argument("--results", default="results", metavar="DIR",
                   help="the results folder (default: results)")
    p.add_argument("-o", "--out", metavar="DIR",
                   help="where to write the report (default: DIR/report of --results)")
    p.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    from flyover.report import build_report  # noqa: PLC0415

    index = build_report(args.results, args.out)
    print(index)
    return 0
