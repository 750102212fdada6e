"""Logging for workflow scripts: to the rule's log file and to the console."""

from __future__ import annotations

import logging
import sys
from pathlib import Path

from flyover.progress import PROGRESS_LOGGER

__all__ = ["setup_logging"]


class _ConsoleFormatter(logging.Formatter):
    """``flyover WARNING: ...`` for warnings and errors, ``flyover ...`` for progress."""

    def format(self, record: logging.LogRecord) -> str:
        if record.levelno >= logging.WARNING:
            return f"flyover {record.levelname}: {record.getMessage()}"
        return f"flyover {record.getMessage()}"


def _for_console(record: logging.LogRecord) -> bool:
    return record.levelno >= logging.WARNING or record.name == PROGRESS_LOGGER


def setup_logging(log_path: str, level: int = logging.INFO) -> None:
    """Send INFO+ to ``log_path``; WARNING+ (e.g. rejected inputs) and batch progress to stderr."""
    Path(log_path).parent.mkdir(parents=True, exist_ok=True)
    fmt = logging.Formatter("%(asctime)s %(levelname)s %(name)s: %(message)s")
    to_file = logging.FileHandler(log_path, mode="w", encoding="utf-8")
    to_file.setFormatter(fmt)
    to_console = logging.StreamHandler(sys.stderr)
    to_console.addFilter(_for_console)
    to_console.setFormatter(_ConsoleFormatter())
    root = logging.getLogger()
    root.handlers[:] = [to_file, to_console]
    root.setLevel(level)
