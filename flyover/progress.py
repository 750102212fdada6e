"""Progress of a batch job that a user can read on the console.

A workflow job handles a whole class of interchanges; :class:`Progress` tells
how many of them are done, at most every ``every_s`` seconds and at the end:

    geometry c6e7ded01c5 (stack4): 40/106 interchanges (12 s)

Example
-------
>>> p = Progress("geometry", "c0", total=2, every_s=0.0)
>>> p.done(); p.done()
>>> p.count
2
"""

from __future__ import annotations

import logging
import time

__all__ = ["Progress", "PROGRESS_LOGGER"]

#: the logger progress goes to; :func:`flyover.workflow_log.setup_logging` shows it on the console
PROGRESS_LOGGER = "flyover.progress"

log = logging.getLogger(PROGRESS_LOGGER)


class Progress:
    """Counts the interchanges of one batch as they are done and reports now and then.

    Parameters
    ----------
    stage
        The stage's name (``geometry``, ``export``, ``validation``, ...).
    batch
        What the batch is, usually a class id and name.
    total
        How many interchanges the batch has.
    every_s
        Least time between two reports (the last one is always made).
    """

    def __init__(self, stage: str, batch: str, total: int, every_s: float = 10.0):
        self.stage, self.batch, self.total, self.every_s = stage, batch, int(total), every_s
        self.count = 0
        self.failed = 0
        self._t0 = self._last = time.monotonic()
        log.info("%s %s: 0/%d interchanges", stage, batch, self.total)

    def done(self, ok: bool = True) -> None:
        """One more interchange is done (``ok=False``: it failed)."""
        self.count += 1
        self.failed += not ok
        now = time.monotonic()
        if self.count >= self.total or now - self._last >= self.every_s:
            self._last = now
            failed = f", {self.failed} failed" if self.failed else ""
            log.info("%s %s: %d/%d interchanges%s (%.0f s)", self.stage, self.batch, self.count,
                     self.total, failed, now - self._t0)
