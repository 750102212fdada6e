"""The ``flyover`` console script.

Each stage contributes its subcommands from ``flyover/<stage>/cli.py`` through
a ``register(subparsers)`` function; a stage's module is imported only to
register its parser (keep those modules light), and its work only when run.
"""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import logging
import sys

from flyover import __version__
from flyover.errors import FlyoverError

__all__ = ["main", "build_parser"]

#: modules whose ``register(subparsers)`` adds subcommands, in help order
STAGE_CLIS = (
    "flyover.topology.cli",
    "flyover.osm.cli",
    "flyover.sampling.cli",
    "flyover.geometry.cli",
    "flyover.opendrive.cli",
    "flyover.traffic.cli",
    "flyover.plugins.cli",
    "flyover.analytics.cli",
    "flyover.report.cli",
    "flyover.summary",
)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="flyover", description="Diverse, simulation-ready highway interchanges.")
    parser.add_argument("--version", action="version", version=f"flyover {__version__}")
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress to stderr")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in STAGE_CLIS:
        if importlib.util.find_spec(name.rpartition(".")[0]) is None or \
                importlib.util.find_spec(name) is None:
            continue  # stage (or its commands) not built in this checkout
        importlib.import_module(name).register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point; returns the process exit status (1 = some input rejected)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING,
                        format="%(levelname)s %(name)s: %(message)s")
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        return int(args.func(args) or 0)
    except FlyoverError as exc:
        print(f"error: {exc.one_line()}", file=sys.stderr)
        return 1
    except BrokenPipeError:
        return 0


if __name__ == "__main__":
    sys.exit(main())
