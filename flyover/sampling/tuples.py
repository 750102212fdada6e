"""The t-way tuples of a model: their numbering, which are required, the lower bound, coverage.

Every set of t parameters (a *t-set*) owns a contiguous block of tuple
numbers; inside a block a tuple is numbered in mixed radix, first parameter
most significant. A tuple is *required* (allowed) when some valid row holds
it: coverage counts only those (paper Def. 4, with constraints).

Examples
--------
>>> space = TupleSpace([8, 8, 5], 2)
>>> space.n_tuples, space.lower_bound
(144, 64)
>>> rows = np.array([[0, 0, 0], [1, 1, 1]])
>>> measure_coverage(rows, space).tuples_covered
6
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from functools import cached_property
from typing import Sequence

import numpy as np

from flyover.sampling.constraints import Constraints

__all__ = ["TupleSpace", "Incidence", "Coverage", "measure_coverage"]


@dataclass(frozen=True, eq=False)
class Incidence:
    """For every parameter c, the t-sets holding it, ready for vectorized tuple numbers.

    Every parameter lies in the same number M of t-sets. The number of the
    tuple of the i-th t-set of c in a row is
    ``base[c, i] + row[c] * mul_c[c, i] + (row[others[c, i]] * mul_o[c, i]).sum()``.
    """

    others: np.ndarray  # (k, M, t-1) the other parameters of each t-set
    mul_o: np.ndarray   # (k, M, t-1) their radix weights
    mul_c: np.ndarray   # (k, M) the weight of c
    base: np.ndarray    # (k, M) the block offset of each t-set


class TupleSpace:
    """All t-way tuples over parameters with ``levels``, under ``constraints``.

    ``t`` larger than the number of parameters means all of them (the full
    product).
    """

    def __init__(self, levels: Sequence[int], t: int, constraints: Constraints | None = None):
        if not levels:
            raise ValueError("a model needs at least one parameter")
        if t < 1:
            raise ValueError(f"strength t must be at least 1, got {t}")
        self.levels = np.asarray(levels, dtype=np.int64)
        if (self.levels < 1).any():
            raise ValueError("every parameter needs at least one value")
        self.k = len(self.levels)
        self.t = min(int(t), self.k)
        self.constraints = constraints or Constraints(self.levels)
        self.tsets = np.array(list(itertools.combinations(range(self.k), self.t)),
                              dtype=np.int64).reshape(-1, self.t)
        lv = self.levels[self.tsets]
        self.strides = np.ones_like(lv)
        for j in range(self.t - 2, -1, -1):
            self.strides[:, j] = self.strides[:, j + 1] * lv[:, j + 1]
        sizes = lv.prod(axis=1)
        self.offsets = np.concatenate([[0], np.cumsum(sizes)])
        self.n_tuples = int(self.offsets[-1])

    def index(self, rows: np.ndarray) -> np.ndarray:
        """Tuple numbers held by ``rows`` (N × k): an N × (number of t-sets) array."""
        rows = np.asarray(rows, dtype=np.int64).reshape(-1, self.k)
        return self.offsets[:-1] + (rows[:, self.tsets] * self.strides).sum(axis=2)

    def counts(self, rows: np.ndarray) -> np.ndarray:
        """How many rows hold each tuple (length :attr:`n_tuples`)."""
        return np.bincount(self.index(rows).ravel(), minlength=self.n_tuples)

    def decode(self, u: int) -> tuple[np.ndarray, np.ndarray]:
        """The parameters and values of tuple number ``u``."""
        s = int(np.searchsorted(self.offsets, u, side="right")) - 1
        cols = self.tsets[s]
        return cols, ((u - self.offsets[s]) // self.strides[s]) % self.levels[cols]

    @cached_property
    def allowed(self) -> np.ndarray:
        """Boolean mask of the required tuples: those some valid row can hold."""
        allowed = np.ones(self.n_tuples, dtype=bool)
        cons = self.constraints
        if not cons:
            return allowed
        for s, cols in enumerate(self.tsets):
            groups: dict[int, list[int]] = {}
            for j, c in enumerate(cols):
                if cons.constrained(int(c)):
                    groups.setdefault(cons.component(int(c)), []).append(j)
            if not groups:
                continue
            shape = self.levels[cols]
            block = np.ones(shape, dtype=bool)
            for js in groups.values():
                sub = [int(cols[j]) for j in js]
                ok = np.zeros(shape[js], dtype=bool)
                for combo in itertools.product(*(range(n) for n in shape[js])):
                    ok[combo] = cons.extendable(dict(zip(sub, combo)))
                block &= ok.reshape([shape[j] if j in js else 1 for j in range(self.t)])
            allowed[self.offsets[s]:self.offsets[s + 1]] = block.ravel()
        return allowed

    @cached_property
    def lower_bound(self) -> int:
        """No covering array has fewer rows: the most required tuples of any one t-set."""
        return int(np.add.reduceat(self.allowed, self.offsets[:-1]).max())

    @cached_property
    def incidence(self) -> Incidence:
        """For every parameter, the t-sets holding it."""
        parts = []
        for c in range(self.k):
            rows = np.flatnonzero((self.tsets == c).any(axis=1))
            ts, st = self.tsets[rows], self.strides[rows]
            pos = (ts == c).argmax(axis=1)
            keep = np.arange(self.t)[None, :] != pos[:, None]
            parts.append((ts[keep].reshape(len(rows), self.t - 1), st[keep].reshape(len(rows), self.t - 1),
                          st[np.arange(len(rows)), pos], self.offsets[rows]))
        return Incidence(*(np.stack(arrays) for arrays in zip(*parts)))


@dataclass(frozen=True)
class Coverage:
    """How well an array covers a model: one row of ``coverage.parquet``."""

    t: int
    n_params: int
    rows: int
    tuples_total: int
    tuples_covered: int
    lower_bound: int

    @property
    def complete(self) -> bool:
        return self.tuples_covered == self.tuples_total


def measure_coverage(rows: np.ndarray, space: TupleSpace) -> Coverage:
    """Count the required tuples that ``rows`` cover (rows holding a forbidden
    combination cover nothing)."""
    rows = np.asarray(rows, dtype=np.int64).reshape(-1, space.k)
    valid = np.array([space.constraints.row_ok(r) for r in rows], dtype=bool) \
        if space.constraints else np.ones(len(rows), dtype=bool)
    covered = np.zeros(space.n_tuples, dtype=bool)
    covered[space.index(rows[valid]).ravel()] = True
    return Coverage(t=space.t, n_params=space.k, rows=len(rows),
                    tuples_total=int(space.allowed.sum()),
                    tuples_covered=int((covered & space.allowed).sum()),
                    lower_bound=space.lower_bound)
