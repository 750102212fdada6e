"""The compiled inner loops of the covering-array search (numba).

:func:`tabu_search` — one tabu step (after Nurmela, 2004): pick an uncovered tuple; every row that
holds all of it but one cell offers a move (set that cell); take the move
that leaves the fewest tuples uncovered, skipping cells changed in the last
``tenure`` steps unless the move beats the best count so far; forbid the
changed cell for ``tenure`` steps. A step with no move writes the whole tuple
into a random row.

The kernel owns no state: the array, the tuple counts and the list of
uncovered tuples are numpy arrays the caller keeps (see
:class:`flyover.sampling.covering._State`). Tuples that are not required
carry a large count offset (:data:`NOT_REQUIRED`), so "uncovered" is simply
a count of 0 and "held once" a count of 1: one int32 array, read at random
and kept small for the cache. Random numbers come from a
splitmix64 stream seeded by the caller, so runs repeat exactly.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["tabu_search", "rows_alone", "NOT_REQUIRED"]

#: count offset of the tuples no valid row can hold
NOT_REQUIRED = 1 << 24

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_MIX1 = np.uint64(0xBF58476D1CE4E5B9)
_MIX2 = np.uint64(0x94D049BB133111EB)


@njit(cache=True)
def _rand(state, n):
    """A number in ``0 .. n-1`` from the splitmix64 stream ``state`` (1-element uint64 array)."""
    state[0] += _GOLDEN
    z = state[0]
    z = (z ^ (z >> np.uint64(30))) * _MIX1
    z = (z ^ (z >> np.uint64(27))) * _MIX2
    z = z ^ (z >> np.uint64(31))
    return np.int64(z % np.uint64(n))


@njit(cache=True)
def _part(A, r, c, i, others, mul_o, base):
    """The number of the tuple of c's i-th t-set in row r, less c's own term."""
    part = base[c, i]
    for j in range(others.shape[2]):
        part += A[r, others[c, i, j]] * mul_o[c, i, j]
    return part


@njit(cache=True)
def _set(A, r, c, v, counts, unc, pos, n_unc, others, mul_o, mul_c, base):
    """``A[r, c] = v``, updating tuple counts and the uncovered list; returns the new count."""
    old_v = A[r, c]
    if old_v == v:
        return n_unc
    for i in range(others.shape[1]):
        part = _part(A, r, c, i, others, mul_o, base)
        old = part + old_v * mul_c[c, i]
        new = part + v * mul_c[c, i]
        counts[old] -= 1
        if counts[old] == 0:
            pos[old] = n_unc
            unc[n_unc] = old
            n_unc += 1
        counts[new] += 1
        if counts[new] == 1:
            n_unc -= 1
            last = unc[n_unc]
            unc[pos[new]] = last
            pos[last] = pos[new]
            pos[new] = -1
    A[r, c] = v
    return n_unc


@njit(cache=True)
def _delta(A, r, c, v, counts, others, mul_o, mul_c, base):
    """Change in the number of uncovered tuples if ``A[r, c] = v``."""
    d = 0
    old_v = A[r, c]
    for i in range(others.shape[1]):
        part = _part(A, r, c, i, others, mul_o, base)
        old = part + old_v * mul_c[c, i]
        new = part + v * mul_c[c, i]
        if counts[old] == 1:
            d += 1
        if counts[new] == 0:
            d -= 1
    return d


@njit(cache=True)
def _valid(A, r, c, v, f_len, f_params, f_masks, p_ptr, p_forb):
    """Whether row r stays clear of every forbidden combination when ``A[r, c] = v``."""
    for k in range(p_ptr[c], p_ptr[c + 1]):
        f = p_forb[k]
        hit = True
        for i in range(f_len[f]):
            p = f_params[f, i]
            val = v if p == c else A[r, p]
            if not f_masks[f, i, val]:
                hit = False
                break
        if hit:
            return False
    return True


@njit(cache=True)
def tabu_search(A, counts, unc, pos, n_unc, offsets, tsets, strides, levels,
                others, mul_o, mul_c, base, f_len, f_params, f_masks, p_ptr, p_forb,
                work, stall, tenure, seed):
    """Run tabu steps on ``A`` in place; return (work used, uncovered).

    ``work`` bounds the effort, counted in rows scanned plus tuples looked up
    (a measure of time that does not depend on the machine); ``stall`` ends
    the search after that many steps without a new best.

    On return ``A``, ``counts``, ``unc`` and ``pos`` describe the best array
    met (fewest uncovered tuples).
    """
    N, k = A.shape
    t = tsets.shape[1]
    rng = np.zeros(1, dtype=np.uint64)
    rng[0] = np.uint64(seed)
    tabu = np.zeros((N, k), dtype=np.int64)
    best = n_unc
    best_A = A.copy()
    cols = np.empty(t, dtype=np.int64)
    vals = np.empty(t, dtype=np.int64)
    since = 0
    step = 0
    used = 0
    per_delta = others.shape[1] * t
    while used < work and n_unc > 0 and since < stall:
        step += 1
        used += N * t
        u = unc[_rand(rng, n_unc)]
        lo, hi = 0, offsets.shape[0] - 1  # t-set of u: offsets[s] <= u < offsets[s + 1]
        while hi - lo > 1:
            mid = (lo + hi) // 2
            if offsets[mid] <= u:
                lo = mid
            else:
                hi = mid
        for j in range(t):
            cols[j] = tsets[lo, j]
            vals[j] = ((u - offsets[lo]) // strides[lo, j]) % levels[cols[j]]
        best_d, best_r, best_j, ties = 1 << 60, -1, -1, 0
        for r in range(N):
            miss, jm = 0, -1
            for j in range(t):
                if A[r, cols[j]] != vals[j]:
                    miss += 1
                    jm = j
            if miss != 1:
                continue
            c, v = cols[jm], vals[jm]
            if not _valid(A, r, c, v, f_len, f_params, f_masks, p_ptr, p_forb):
                continue
            d = _delta(A, r, c, v, counts, others, mul_o, mul_c, base)
            used += per_delta
            if tabu[r, c] > step and n_unc + d >= best:
                continue
            if d < best_d:
                best_d, best_r, best_j, ties = d, r, jm, 1
            elif d == best_d:
                ties += 1
                if _rand(rng, ties) == 0:
                    best_r, best_j = r, jm
        if best_r < 0:
            # no single change covers u: write it whole into a random row, if that row stays valid
            r = _rand(rng, N)
            saved = A[r].copy()
            ok = True
            for j in range(t):
                if not _valid(A, r, cols[j], vals[j], f_len, f_params, f_masks, p_ptr, p_forb):
                    ok = False
                    break
                A[r, cols[j]] = vals[j]
            A[r, :] = saved
            if ok:
                for j in range(t):
                    n_unc = _set(A, r, cols[j], vals[j], counts, unc, pos, n_unc,
                                 others, mul_o, mul_c, base)
                    tabu[r, cols[j]] = step + tenure
        else:
            c = cols[best_j]
            n_unc = _set(A, best_r, c, vals[best_j], counts, unc, pos, n_unc,
                         others, mul_o, mul_c, base)
            tabu[best_r, c] = step + tenure
        if n_unc < best:
            best = n_unc
            best_A[:, :] = A
            since = 0
        else:
            since += 1
    if n_unc > best:
        for r in range(N):
            for c in range(k):
                if A[r, c] != best_A[r, c]:
                    n_unc = _set(A, r, c, best_A[r, c], counts, unc, pos, n_unc,
                                 others, mul_o, mul_c, base)
    return used, n_unc


@njit(cache=True)
def rows_alone(A, counts, offsets, tsets, strides):
    """For each row, how many tuples it alone holds (count 1)."""
    N = A.shape[0]
    out = np.zeros(N, dtype=np.int64)
    for r in range(N):
        for s in range(tsets.shape[0]):
            u = offsets[s]
            for j in range(tsets.shape[1]):
                u += A[r, tsets[s, j]] * strides[s, j]
            if counts[u] == 1:
                out[r] += 1
    return out
