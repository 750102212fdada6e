"""Logging for workflow scripts: to the rule's log file and to the console."""

from __future__ import annotations

import logging
import sys
from pathlib import Path

__all__ = ["setup_logging"]


def setup_logging(log_path: str, level: int = logging.INFO) -> None:
    """Send INFO+ to ``log_path`` and WARNING+ (e.g. rejected inputs) to stderr."""
    Path(log_path).parent.mkdir(parents=True, exist_ok=True)
    fmt = logging.Formatter("%(asctime)s %(levelname)s %(name)s: %(message)s")
    to_file = logging.FileHandler(log_path, mode="w", encoding="utf-8")
    to_file.setFormatter(fmt)
    to_console = logging.StreamHandler(sys.stderr)
    to_console.setLevel(logging.WARNING)
    to_console.setFormatter(logging.Formatter("flyover %(levelname)s: %(message)s"))
    root = logging.getLogger()
    root.handlers[:] = [to_file, to_console]
    root.setLevel(level)
