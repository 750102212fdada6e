"""Small t-way covering arrays with constraints (paper §III-C, Definition 4).

A covering array CA(N; t, v_1 … v_k) has N rows, one value per parameter
each, such that every t parameters show every allowed combination of their
values in some row. The paper makes them with Microsoft PICT (greedy); this
module makes smaller ones, in three steps:

1. **Start** with as many rows as the lower bound (the most required tuples
   of any t parameters):

   * *algebraic*, when that bound is q^t for a prime power q (the t largest
     parameters all have q values): Bush's orthogonal array OA(q^t, q+1, q, t)
     over GF(q) (:mod:`flyover.sampling.galois`) for the q+1 parameters with
     the most values, mapped onto fewer levels where a parameter has fewer;
   * otherwise the full product of the t largest parameters (as IPOG does).

   The other parameters are filled in greedily, row by row (IPOG's horizontal
   growth), and the tabu search (step 2) tries to complete the array without
   adding a row; a completed start is optimal. What it leaves uncovered gets
   greedy extra rows (IPOG's vertical growth).

2. **Tabu search** (after Nurmela, 2004) at a fixed number of rows: pick an
   uncovered tuple, consider every single-cell change that covers it, take
   the one that leaves the fewest tuples uncovered, and forbid changing that
   cell again for a while (:mod:`flyover.sampling._kernels`, compiled).

3. **Shrinking.** Drop a row that covers fewest tuples alone and let the tabu
   search repair the loss; repeat until the lower bound is reached or
   ``retries`` repairs in a row fail.

Forbidden combinations are never written into a row, and only tuples some
valid row can hold are required. Everything random draws from one
:class:`numpy.random.Generator` seeded by the caller, and the effort is
counted in work, never in seconds: the same inputs give the same array.

Examples
--------
>>> ca = covering_array([8, 8, 8, 5, 5, 3], t=2, seed=1)
>>> ca.rows.shape
(64, 6)
>>> ca.coverage.complete
True
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Iterable, Sequence

import numpy as np

from flyover.sampling._kernels import NOT_REQUIRED, rows_alone, tabu_search
from flyover.sampling.constraints import Constraints, Forbidden
from flyover.sampling.galois import orthogonal_array, prime_power
from flyover.sampling.tuples import Coverage, TupleSpace, measure_coverage

__all__ = ["CoveringArray", "covering_array", "SearchBudget"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class SearchBudget:
    """Effort of the tabu search, counted in work, never in seconds, so runs repeat exactly.

    Attributes
    ----------
    work
        Total work across construction and shrinking, in rows scanned plus
        tuples looked up; a current core does about 3·10^8 a second.
    stall
        One attempt gives up after this many steps without reducing the
        number of uncovered tuples.
    tenure
        Steps for which a changed cell may not change again.
    retries
        Shrinking stops after this many failed repairs in a row, each
        dropping another of the rows that cover fewest tuples alone.
    """

    work: int = 1_000_000_000
    stall: int = 20_000
    tenure: int = 6
    retries: int = 8


@dataclass(frozen=True, eq=False)
class CoveringArray:
    """A covering array: ``rows`` (N × k value indices) and its coverage."""

    rows: np.ndarray
    levels: tuple[int, ...]
    t: int
    coverage: Coverage
    construction: str


class _State:
    """An array under search: the rows, how often each tuple is held, the uncovered ones.

    ``counts`` carries :data:`NOT_REQUIRED` on the tuples that are not
    required, so a count of 0 means "required and uncovered".
    """

    def __init__(self, space: TupleSpace, rows: np.ndarray, counts: np.ndarray | None = None):
        self.space = space
        self.A = np.array(rows, dtype=np.int64).reshape(-1, space.k)
        if counts is None:
            counts = (space.counts(self.A) + np.where(space.allowed, 0, NOT_REQUIRED)).astype(np.int32)
        self.counts = counts
        unc = np.flatnonzero(self.counts == 0)
        self.unc = np.zeros(space.n_tuples, dtype=np.int64)
        self.unc[:len(unc)] = unc
        self.pos = np.full(space.n_tuples, -1, dtype=np.int64)
        self.pos[unc] = np.arange(len(unc))
        self.n_unc = len(unc)

    def alone(self) -> np.ndarray:
        """For each row, how many required tuples no other row holds."""
        sp = self.space
        return rows_alone(self.A, self.counts, sp.offsets, sp.tsets, sp.strides)

    def without(self, r: int) -> "_State":
        """A new state: this one less row ``r``."""
        counts = self.counts.copy()
        np.subtract.at(counts, self.space.index(self.A[r])[0], 1)
        return _State(self.space, np.delete(self.A, r, axis=0), counts)

    def tabu(self, work: int, budget: SearchBudget, rng: np.random.Generator) -> int:
        """Tabu search at this number of rows (see :mod:`flyover.sampling._kernels`);
        keeps the best array met. Returns the work used."""
        space, inc = self.space, self.space.incidence
        used, self.n_unc = tabu_search(
            self.A, self.counts, self.unc, self.pos, self.n_unc,
            space.offsets, space.tsets, space.strides, space.levels,
            inc.others, inc.mul_o, inc.mul_c, inc.base, *space.constraints.arrays,
            work, budget.stall, budget.tenure, int(rng.integers(2**63)))
        return int(used)


class _Builder:
    """Fills and grows arrays whose unset cells are ``-1``."""

    def __init__(self, space: TupleSpace, rng: np.random.Generator):
        self.space = space
        self.rng = rng
        order = np.argsort(-space.levels, kind="stable")
        self.order = [int(c) for c in order]  # parameters, most values first

    def _assigned_counts(self, A: np.ndarray) -> np.ndarray:
        space = self.space
        full = (A[:, space.tsets] >= 0).all(axis=2)
        return np.bincount(space.index(np.maximum(A, 0))[full], minlength=space.n_tuples)

    def _choose(self, A: np.ndarray, counts: np.ndarray, r: int, c: int) -> None:
        """Set the unset cell (r, c) to the value that covers most new tuples."""
        space, cons = self.space, self.space.constraints
        inc = space.incidence
        others, row = inc.others[c], A[r]
        known = (row[others] >= 0).all(axis=1)
        part = inc.base[c, known] + (row[others[known]] * inc.mul_o[c, known]).sum(axis=1)
        values = np.arange(space.levels[c])
        idx = part[None, :] + values[:, None] * inc.mul_c[c, known][None, :]
        gain = ((counts[idx] == 0) & space.allowed[idx]).sum(axis=1)
        if cons.constrained(c):
            comp = cons.component(c)
            partial = {p: int(row[p]) for p in range(space.k)
                       if row[p] >= 0 and cons.component(p) == comp}
            ok = np.array([cons.extendable({**partial, c: int(v)}) for v in values])
            gain = np.where(ok, gain, -1)
        v = int(self.rng.choice(np.flatnonzero(gain == gain.max())))
        counts[idx[v]] += 1
        A[r, c] = v

    def fill(self, A: np.ndarray) -> np.ndarray:
        """Horizontal growth: set every unset cell, parameter by parameter."""
        A = A.copy()
        counts = self._assigned_counts(A)
        for c in self.order:
            for r in np.flatnonzero(A[:, c] < 0):
                self._choose(A, counts, int(r), c)
        return A

    def grow(self, A: np.ndarray) -> np.ndarray:
        """Vertical growth: add greedy rows until every required tuple is covered."""
        space = self.space
        counts = space.counts(A)
        rows = [A]
        while True:
            unc = np.flatnonzero((counts == 0) & space.allowed)
            if not len(unc):
                return np.concatenate(rows)
            cols, vals = space.decode(int(unc[self.rng.integers(len(unc))]))
            new = np.full((1, space.k), -1, dtype=np.int64)
            new[0, cols] = vals
            counts[space.index(np.maximum(new, 0))[0][(new[0, space.tsets] >= 0).all(axis=1)]] += 1
            for c in self.order:
                if new[0, c] < 0:
                    self._choose(new, counts, 0, c)
            rows.append(new)

    def repair(self, A: np.ndarray) -> np.ndarray:
        """Unset cells of rows that hold a forbidden combination until each can be completed."""
        cons = self.space.constraints
        if not cons:
            return A
        A = A.copy()
        for r in range(len(A)):
            for c in reversed(self.order):  # fewest values first
                partial = {p: int(v) for p, v in enumerate(A[r]) if v >= 0}
                if cons.extendable(partial):
                    break
                if cons.constrained(c):
                    A[r, c] = -1
        return A


def _algebraic_start(space: TupleSpace, builder: _Builder) -> tuple[str, np.ndarray] | None:
    """Bush's OA for the largest parameters, the rest unset, if it has as many
    rows as the lower bound; else ``None``."""
    q = max(int(space.levels.max()), space.t)
    while prime_power(q) is None:
        q += 1
    if space.t < 2 or q ** space.t != space.lower_bound:
        return None
    oa = orthogonal_array(q, space.t)
    A = np.full((len(oa), space.k), -1, dtype=np.int64)
    for col, c in enumerate(builder.order[:q + 1]):
        A[:, c] = oa[:, col] % space.levels[c]
    return f"orthogonal array OA({q}^{space.t}, {min(q + 1, space.k)}, {q}, {space.t})", builder.repair(A)


def _product_start(space: TupleSpace, builder: _Builder) -> tuple[str, np.ndarray]:
    """The valid rows of the full product of the t largest parameters, the rest unset."""
    first = sorted(builder.order[:space.t])
    product = space.constraints.valid_rows(first)
    A = np.full((len(product), space.k), -1, dtype=np.int64)
    A[:, first] = product
    return "product of the largest parameters", A


def covering_array(
    levels: Sequence[int],
    t: int = 2,
    *,
    forbidden: Iterable[Forbidden] = (),
    seed: int = 0,
    budget: SearchBudget = SearchBudget(),
) -> CoveringArray:
    """A small covering array of strength ``t`` over parameters with ``levels`` values.

    Parameters
    ----------
    levels
        Number of values of each parameter; values are ``0 .. levels[p]-1``.
    t
        Strength: every ``t`` parameters show every allowed value tuple.
    forbidden
        Combinations no row may hold (see :class:`Forbidden`).
    seed
        Seed of every random choice; the same inputs give the same array.
    budget
        Step budgets of the tabu search.

    Returns
    -------
    CoveringArray
        Always complete (every required tuple covered).

    Raises
    ------
    flyover.sampling.constraints.UnsatisfiableError
        The forbidden combinations leave no valid row.
    """
    space = TupleSpace(levels, t, Constraints(levels, forbidden))
    rng = np.random.default_rng(seed)
    builder = _Builder(space, rng)
    work = budget.work

    name, start = _algebraic_start(space, builder) or _product_start(space, builder)
    state = _State(space, builder.fill(start))
    work -= state.tabu(work // 2, budget, rng)
    name += " + tabu"
    rows = builder.grow(state.A)
    if len(rows) > len(state.A):
        name += f" + {len(rows) - len(state.A)} greedy rows"
    log.debug("start: %s, %d rows (lower bound %d)", name, len(rows), space.lower_bound)

    state = _State(space, rows)
    shrunk, failures = 0, 0
    while len(state.A) > space.lower_bound and work > 0 and failures <= budget.retries:
        trial = state.without(int(rng.choice(np.argsort(state.alone(), kind="stable")[:failures + 1])))
        work -= trial.tabu(work, budget, rng)
        if trial.n_unc:
            failures += 1
            continue
        state, shrunk, failures = trial, shrunk + 1, 0
    rows = state.A
    if shrunk:
        name += f" + shrink by {shrunk}"
    return CoveringArray(rows=rows, levels=tuple(int(v) for v in space.levels), t=space.t,
                         coverage=measure_coverage(rows, space), construction=name)
