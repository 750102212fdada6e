"""Run the interchanges of one batch in several processes, in order.

A workflow job handles a whole class; with ``threads: 2`` it uses both cores of a
two-core machine when it is the only job that can run (a new city's one class, the last
class of a run), and Snakemake runs one such job at a time otherwise. Every interchange is
computed from its own inputs and seed, so the results do not depend on the number of
workers.

Example
-------
>>> list(map_ordered(abs, [-2, 1, -3], workers=1))
[2, 1, 3]
"""

from __future__ import annotations

import multiprocessing
from typing import Callable, Iterable, Iterator, TypeVar

__all__ = ["map_ordered"]

T = TypeVar("T")
R = TypeVar("R")


def map_ordered(fn: Callable[[T], R], items: Iterable[T], workers: int = 1) -> Iterator[R]:
    """``fn(item)`` for every item, yielded in input order as each is done.

    With ``workers > 1`` the items run in that many forked processes (``fn`` and the items
    must pickle; a module-level function or a :func:`functools.partial` of one). Exceptions
    are ``fn``'s to handle: one escaping it ends the whole batch.
    """
    items = list(items)
    if workers <= 1 or len(items) <= 1:
        yield from map(fn, items)
        return
    with multiprocessing.get_context("fork").Pool(min(workers, len(items))) as pool:
        yield from pool.imap(fn, items, chunksize=1)
