"""Forbidden value combinations and the questions the generator asks of them.

Parameters are numbered ``0 .. k-1`` and their values ``0 .. levels[p]-1``.
A :class:`Forbidden` combination names some parameters and, for each, a set
of values; a row is forbidden when it takes one of the listed values on every
named parameter. :class:`Constraints` answers whether a full row is valid and
whether a partial row can still be completed into a valid one (so implied
constraints are honoured too: a tuple no valid row can hold is not required).

Examples
--------
>>> cons = Constraints([3, 3], [Forbidden.of({0: [2], 1: [0, 1]})])
>>> cons.row_ok([2, 2]), cons.row_ok([2, 0])
(True, False)
>>> cons.extendable({0: 2}), cons.extendable({1: 0})
(True, True)
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from functools import cached_property
from typing import Iterable, Mapping, Sequence

import numpy as np

__all__ = ["Forbidden", "Constraints", "UnsatisfiableError"]


class UnsatisfiableError(ValueError):
    """The forbidden combinations leave no valid row at all."""


@dataclass(frozen=True)
class Forbidden:
    """A forbidden combination: ``cells`` are ``(parameter, values)`` pairs, sorted."""

    cells: tuple[tuple[int, frozenset[int]], ...]

    @classmethod
    def of(cls, mapping: Mapping[int, Iterable[int]]) -> "Forbidden":
        """Build from ``{parameter: values}``."""
        return cls(tuple(sorted((int(p), frozenset(map(int, vs))) for p, vs in mapping.items())))

    @property
    def params(self) -> tuple[int, ...]:
        return tuple(p for p, _ in self.cells)

    def matches(self, row: Mapping[int, int] | Sequence[int]) -> bool:
        """True if ``row`` (full, or a mapping of assigned parameters) holds this combination."""
        if isinstance(row, Mapping):
            return all(p in row and row[p] in vs for p, vs in self.cells)
        return all(row[p] in vs for p, vs in self.cells)


class Constraints:
    """The forbidden combinations of a model over parameters with ``levels``.

    Raises
    ------
    ValueError
        A combination names an unknown parameter or value.
    UnsatisfiableError
        No row satisfies them all.
    """

    def __init__(self, levels: Sequence[int], forbidden: Iterable[Forbidden] = ()):
        self.levels = tuple(int(v) for v in levels)
        self.forbidden = tuple(dict.fromkeys(f for f in forbidden if f.cells))
        for f in self.forbidden:
            for p, vs in f.cells:
                if not 0 <= p < len(self.levels) or not vs or not all(0 <= v < self.levels[p] for v in vs):
                    raise ValueError(f"forbidden combination {f} names an unknown parameter or value")
        self._by_param: dict[int, list[Forbidden]] = {}
        for f in self.forbidden:
            for p in f.params:
                self._by_param.setdefault(p, []).append(f)
        self._component = self._components()
        self._memo: dict[tuple, bool] = {}
        for comp in set(self._component.values()):
            if not self._search(comp, {}):
                raise UnsatisfiableError("the forbidden combinations leave no valid value for "
                                         f"parameters {sorted(p for p, c in self._component.items() if c == comp)}")

    def __bool__(self) -> bool:
        return bool(self.forbidden)

    def _components(self) -> dict[int, int]:
        """Parameter → the smallest parameter linked to it through shared combinations."""
        parent = {p: p for p in self._by_param}

        def find(p: int) -> int:
            while parent[p] != p:
                parent[p] = parent[parent[p]]
                p = parent[p]
            return p

        for f in self.forbidden:
            roots = sorted(find(p) for p in f.params)
            for r in roots[1:]:
                parent[r] = roots[0]
        return {p: find(p) for p in parent}

    def constrained(self, param: int) -> bool:
        """Whether any forbidden combination names ``param``."""
        return param in self._by_param

    def component(self, param: int) -> int | None:
        """An id shared by parameters linked through forbidden combinations (``None`` if free)."""
        return self._component.get(param)

    def row_ok(self, row: Sequence[int]) -> bool:
        """A full row holds no forbidden combination."""
        return not any(f.matches(row) for f in self.forbidden)

    @cached_property
    def arrays(self) -> tuple[np.ndarray, ...]:
        """The combinations as padded arrays, indexed by parameter (for compiled code).

        ``(f_len, f_params, f_masks, p_ptr, p_forb)``: combination i names
        ``f_len[i]`` parameters ``f_params[i, :f_len[i]]``, the j-th holding the
        values where ``f_masks[i, j]`` is true; the combinations naming
        parameter p are ``p_forb[p_ptr[p]:p_ptr[p + 1]]``.
        """
        forb = self.forbidden
        width = max((len(f.cells) for f in forb), default=1)
        f_len = np.array([len(f.cells) for f in forb], dtype=np.int64)
        f_params = np.full((len(forb), width), -1, dtype=np.int64)
        f_masks = np.zeros((len(forb), width, max(self.levels)), dtype=bool)
        for i, f in enumerate(forb):
            for j, (p, vs) in enumerate(f.cells):
                f_params[i, j] = p
                f_masks[i, j, sorted(vs)] = True
        index = {f: i for i, f in enumerate(forb)}
        by_param = [[index[f] for f in self._by_param.get(p, ())] for p in range(len(self.levels))]
        p_ptr = np.concatenate([[0], np.cumsum([len(b) for b in by_param])]).astype(np.int64)
        p_forb = np.array([i for b in by_param for i in b], dtype=np.int64)
        return f_len, f_params, f_masks, p_ptr, p_forb

    def extendable(self, partial: Mapping[int, int]) -> bool:
        """Whether some valid full row agrees with ``partial`` (parameter → value)."""
        by_comp: dict[int, dict[int, int]] = {}
        for p, v in partial.items():
            comp = self._component.get(p)
            if comp is not None:
                by_comp.setdefault(comp, {})[p] = int(v)
        return all(self._search(comp, assigned) for comp, assigned in by_comp.items())

    def _search(self, comp: int, assigned: dict[int, int]) -> bool:
        key = (comp, tuple(sorted(assigned.items())))
        if key not in self._memo:
            self._memo[key] = self._backtrack(comp, dict(assigned))
        return self._memo[key]

    def _backtrack(self, comp: int, row: dict[int, int]) -> bool:
        def violated(p: int) -> bool:
            return any(all(q in row for q in f.params) and f.matches(row) for f in self._by_param[p])

        if any(violated(p) for p in row):
            return False
        free = [p for p, c in sorted(self._component.items()) if c == comp and p not in row]

        def extend(i: int) -> bool:
            if i == len(free):
                return True
            p = free[i]
            for v in range(self.levels[p]):
                row[p] = v
                if not violated(p) and extend(i + 1):
                    return True
            del row[p]
            return False

        return extend(0)

    def valid_rows(self, params: Sequence[int]) -> np.ndarray:
        """Every assignment of ``params`` that :meth:`extendable` accepts, as rows."""
        combos = itertools.product(*(range(self.levels[p]) for p in params))
        keep = [c for c in combos if self.extendable(dict(zip(params, c)))]
        return np.array(keep, dtype=np.int64).reshape(-1, len(params))
