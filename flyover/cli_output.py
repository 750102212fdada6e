"""Output helpers shared by the stage commands of the ``flyover`` console script."""

from __future__ import annotations

import json
import sys
from typing import Sequence

from flyover.errors import FlyoverError

__all__ = ["print_json", "report_errors"]


def print_json(rows: Sequence[dict], errors: Sequence[FlyoverError]) -> None:
    """Print ``{"interchanges": rows, "rejected": [...]}`` as indented JSON."""
    json.dump({"interchanges": list(rows),
               "rejected": [{"source_file": e.source, "element": e.element, "reason": e.reason}
                            for e in errors]}, sys.stdout, indent=2)
    print()


def report_errors(errors: Sequence[FlyoverError]) -> int:
    """One ``error: file: element: reason`` line per error on stderr; exit status 1 if any."""
    for exc in errors:
        print(f"error: {exc.one_line()}", file=sys.stderr)
    return 1 if errors else 0
