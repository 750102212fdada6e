"""Finite fields GF(q) and Bush's orthogonal arrays OA(q^t, q+1, q, t).

An orthogonal array of strength t and index 1 has q^t rows, and every t
columns hold every one of the q^t value tuples exactly once: it is a
covering array of the smallest possible size for q-level factors. Bush's
construction over GF(q) gives q + 1 columns for any prime power q >= t: the
rows are the polynomials of degree < t over GF(q), the columns their values
at each field element plus their leading coefficient (the "point at
infinity").

Examples
--------
>>> oa = orthogonal_array(8, 2)
>>> oa.shape
(64, 9)
>>> len({(a, b) for a, b in oa[:, [0, 5]]})
64
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

__all__ = ["GaloisField", "galois_field", "prime_power", "orthogonal_array"]


@dataclass(frozen=True, eq=False)
class GaloisField:
    """GF(q) with elements ``0 .. q-1``; ``add`` and ``mul`` are q × q tables."""

    q: int
    add: np.ndarray
    mul: np.ndarray


def prime_power(q: int) -> tuple[int, int] | None:
    """``(p, m)`` with ``q == p**m`` for a prime p, or ``None``.

    >>> prime_power(8), prime_power(9), prime_power(12)
    ((2, 3), (3, 2), None)
    """
    if q < 2:
        return None
    p = next(d for d in range(2, q + 1) if q % d == 0)
    m, rest = 0, q
    while rest % p == 0:
        rest //= p
        m += 1
    return (p, m) if rest == 1 else None


def _poly_mulmod(a: tuple[int, ...], b: tuple[int, ...], modulus: tuple[int, ...], p: int) -> tuple[int, ...]:
    """Product of two polynomials (low-order digit first) modulo a monic ``modulus``."""
    m = len(modulus) - 1
    prod = [0] * (2 * m - 1)
    for i, x in enumerate(a):
        for j, y in enumerate(b):
            prod[i + j] = (prod[i + j] + x * y) % p
    for d in range(len(prod) - 1, m - 1, -1):
        coef = prod[d]
        if coef:
            for i in range(m + 1):
                prod[d - m + i] = (prod[d - m + i] - coef * modulus[i]) % p
    return tuple(prod[:m])


@lru_cache(maxsize=None)
def galois_field(q: int) -> GaloisField:
    """The field of order ``q`` (a prime power), built from the first monic
    irreducible polynomial found (deterministic).

    Raises
    ------
    ValueError
        ``q`` is not a prime power.
    """
    pm = prime_power(q)
    if pm is None:
        raise ValueError(f"no field of order {q}: not a prime power")
    p, m = pm
    digits = [tuple((x // p**i) % p for i in range(m)) for x in range(q)]
    add = np.array([[sum(((a + b) % p) * p**i for i, (a, b) in enumerate(zip(da, db)))
                     for db in digits] for da in digits], dtype=np.int64)
    for low in itertools.product(range(p), repeat=m):
        modulus = (*low, 1)
        mul = np.array([[sum(c * p**i for i, c in enumerate(_poly_mulmod(da, db, modulus, p)))
                         for db in digits] for da in digits], dtype=np.int64)
        # a field iff every nonzero row of the table is a permutation (no zero divisors)
        if all(len(set(mul[a, 1:])) == q - 1 and 0 not in mul[a, 1:] for a in range(1, q)):
            return GaloisField(q, add, mul)
    raise ValueError(f"no irreducible polynomial of degree {m} over GF({p})")  # unreachable


@lru_cache(maxsize=None)
def _orthogonal_array(q: int, t: int) -> np.ndarray:
    gf = galois_field(q)
    coefs = np.array(list(itertools.product(range(q), repeat=t)), dtype=np.int64)  # a_{t-1} .. a_0
    cols = []
    for x in range(q):
        value = np.zeros(len(coefs), dtype=np.int64)
        for i in range(t):  # Horner: value = value * x + a_i
            value = gf.add[gf.mul[value, x], coefs[:, i]]
        cols.append(value)
    cols.append(coefs[:, 0])  # the leading coefficient: the point at infinity
    out = np.stack(cols, axis=1)
    out.flags.writeable = False
    return out


def orthogonal_array(q: int, t: int) -> np.ndarray:
    """Bush's OA(q^t, q+1, q, t) as a ``(q**t, q + 1)`` integer array.

    Parameters
    ----------
    q
        A prime power, the number of levels.
    t
        The strength, ``1 <= t <= q``.
    """
    if not 1 <= t <= q:
        raise ValueError(f"Bush's construction needs 1 <= t <= q, got t={t}, q={q}")
    return _orthogonal_array(q, t).copy()
