"""Logging for workflow scripts: to the rule's log file and to the console."""

from __future__ import annotations

import atexit
import logging
import resource
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
    atexit.register(_log_usage)


#: the line every workflow script's log ends with (read by benchmarks/workflow.py)
USAGE_LINE = "resource usage: cpu_s={cpu:.3f} children_cpu_s={children:.3f} max_rss_mb={rss:.0f}"


def _log_usage() -> None:
    """The job's CPU seconds, its child processes' (netconvert, the ASAM checker) and its peak
    memory: Snakemake's own benchmark samples the process tree and misses short children."""
    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    logging.getLogger("flyover.usage").info(USAGE_LINE.format(
        cpu=me.ru_utime + me.ru_stime, children=kids.ru_utime + kids.ru_stime,
        rss=max(me.ru_maxrss, kids.ru_maxrss) / 1024))
