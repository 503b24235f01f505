"""Exact determinants of a sparse polynomial matrix, by evaluation and interpolation.

The transfer function is a ratio of two determinants (see `transfer`): that of the
bordered pencil [[sE - A, B], [-C, D]] and that of its leading block sE - A, both with
integer polynomial entries (in s and the symbols) of low degree in each variable. Their
fraction-free elimination over the polynomials grows as n^3 to n^4 on a ladder of n
stages; here instead:

* a degree bound per variable (row and column sums of the entries' degrees) and
  Hadamard's bound on the coefficients (a coefficient is at most the determinant's
  largest value on the unit torus, where an entry is at most its coefficients' 1-norm)
  say how many points and how many primes suffice;
* at every point of the grid and modulo every prime p < 2^31 (products stay below 2^62
  in int64), both determinants are computed at once by division-free sparse elimination
  in a fill-reducing order (Markowitz, on the pattern) fixed in advance: numpy arrays of
  points x primes. A point where a planned pivot vanishes is done alone;
* each determinant's coefficients are interpolated modulo each prime and combined by
  Chinese remainders (symmetric range).

Everything is exact: the bounds are rigorous, so the polynomials are the determinants.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache
from itertools import product

import numpy as np
from sympy import prevprime
from sympy.polys.rings import PolyElement

from mtt.derivation import deadline

MAX_POINTS = 1 << 14  # grid points: beyond, the caller eliminates over the polynomials
PRIME_LIMIT = 1 << 31
MAX_BITS = 60_000  # Hadamard's bound on the coefficients: beyond, `TooLarge`


class TooLarge(Exception):
    """The determinants' coefficients could have more than `MAX_BITS` bits."""


Entries = dict[tuple[int, int], PolyElement]


@cache
def _prime(index: int) -> int:
    """The index-th prime below 2^31, descending."""
    return prevprime(PRIME_LIMIT if index == 0 else _prime(index - 1))


@dataclass(frozen=True)
class _Plan:
    """What every point and every prime share: the grid, the pivots and their fill."""

    size: int  # the bordered matrix is size x size; its leading block size - 1
    degrees: tuple[int, ...]  # per variable: the grid has degrees[g] + 1 points 1, 2, ...
    steps: tuple[tuple[int, int, tuple[int, ...]], ...]  # (pivot row, column, rows updated)
    sign: int  # of the permutation the pivots make
    primes: int  # how many primes the coefficient bound needs


def _degree_bound(entries: Entries, size: int, variable: int) -> int:
    rows, cols = [0] * size, [0] * size
    for (i, j), poly in entries.items():
        degree = max(m[variable] for m in poly.itermonoms())
        rows[i], cols[j] = max(rows[i], degree), max(cols[j], degree)
    return min(sum(rows), sum(cols))


def _log2_hadamard(entries: Entries, size: int) -> float:
    """log2 of the product of the rows' (or the columns') Euclidean norms of the entries'
    coefficient 1-norms: a bound on every coefficient of the determinant."""
    rows, cols = [0] * size, [0] * size
    for (i, j), poly in entries.items():
        norm = sum(abs(int(c)) for c in poly.itercoeffs())
        rows[i] += norm * norm
        cols[j] += norm * norm
    by = [sum(math.log2(x) / 2 for x in sums if x) for sums in (rows, cols)]
    return min(by)


def _markowitz(entries: Entries, size: int) -> tuple[list, int] | None:
    """A fill-reducing pivot order for the leading block (the last row and column come
    last), and its permutation's sign; None if the leading block is structurally
    singular (its determinant is zero for every value)."""
    rows = {i: set() for i in range(size)}
    cols = {j: set() for j in range(size)}
    for i, j in entries:
        rows[i].add(j)
        cols[j].add(i)
    last = size - 1
    steps, pairs = [], []
    for _ in range(last):
        costs = (
            ((len(rows[i]) - 1) * (len(cols[j]) - 1), i, j)
            for j in cols
            if j != last
            for i in cols[j]
            if i != last
        )
        best = min(costs, default=None)
        if best is None:
            return None
        _, r, c = best
        targets = tuple(sorted(cols[c] - {r}))
        for i in targets:
            rows[i] |= rows[r]
            rows[i].discard(c)
            for j in rows[r]:
                cols[j].add(i)
        for j in rows.pop(r):
            cols[j].discard(r)
        del cols[c]
        steps.append((r, c, targets))
        pairs.append((r, c))
    return steps, _permutation_sign([*pairs, (last, last)])


def _permutation_sign(pairs: list[tuple[int, int]]) -> int:
    mapping = dict(pairs)
    sign, seen = 1, set()
    for start in mapping:
        length, i = 0, start
        while i not in seen:
            seen.add(i)
            i = mapping[i]
            length += 1
        if length and length % 2 == 0:
            sign = -sign
    return sign


def _plan(entries: Entries, size: int, nvars: int) -> _Plan | None:
    ordered = _markowitz(entries, size)
    if ordered is None:
        return None
    steps, sign = ordered
    leading = {ij: p for ij, p in entries.items() if max(ij) < size - 1}
    degrees = tuple(
        max(_degree_bound(entries, size, g), _degree_bound(leading, size, g)) for g in range(nvars)
    )
    bits = max(_log2_hadamard(entries, size), _log2_hadamard(leading, size))
    if bits > MAX_BITS:
        raise TooLarge(bits)
    primes = math.ceil((bits + 2) / math.log2(_prime(0)))  # +2: the sign, and a margin
    return _Plan(size, degrees, tuple(steps), sign, max(primes, 1))


def _inverse(x: np.ndarray, mods: np.ndarray) -> np.ndarray:
    """x^(p-2) mod p, elementwise, p along the last axis: the inverses of nonzero residues."""
    result, base, exponent = np.ones_like(x), x % mods, mods - 2
    for bit in range(int(exponent.max()).bit_length()):
        result = np.where((exponent >> bit) & 1, result * base % mods, result)
        base = base * base % mods
    return result


def _values(poly: PolyElement, grid: list[np.ndarray], mods: np.ndarray) -> np.ndarray:
    """The polynomial at every grid point, modulo every prime: (points, primes)."""
    total = np.zeros((grid[0].size, mods.size), dtype=np.int64)
    for monom, coeff in poly.iterterms():
        residues = [int(coeff) % p for p in mods.tolist()]  # coefficients may be huge
        term = np.broadcast_to(np.array(residues, dtype=np.int64), total.shape)
        for values, exponent in zip(grid, monom, strict=True):
            for _ in range(exponent):
                term = term * values[:, None] % mods
        total = (total + term) % mods
    return total


def _eliminate(plan: _Plan, values: dict, shape: tuple[int, int], mods: np.ndarray):
    """Both determinants at every point modulo every prime, and where a pivot vanished."""
    last = plan.size - 1
    rows: dict[int, dict[int, np.ndarray]] = {}
    for (i, j), v in values.items():
        rows.setdefault(i, {})[j] = v
    pivots = np.ones(shape, dtype=np.int64)
    # division-free: an updated row is multiplied by the pivot; these are the factors of
    # the leading block's rows (True) and of the last row (False)
    scales = {True: np.ones(shape, dtype=np.int64), False: np.ones(shape, dtype=np.int64)}
    bad = np.zeros(shape, dtype=bool)
    for r, c, targets in plan.steps:
        deadline.check()
        pivot_row = rows.pop(r)
        pivot = pivot_row.pop(c)
        bad |= pivot == 0
        pivots = pivots * pivot % mods
        for i in targets:
            row = rows[i]
            factor = row.pop(c)
            for j in row:  # row_i = pivot row_i - factor row_r
                row[j] = row[j] * pivot % mods
            for j, v in pivot_row.items():
                row[j] = (row.get(j, 0) - factor * v) % mods
            scales[i != last] = scales[i != last] * pivot % mods
    leading = plan.sign * pivots % mods * _inverse(scales[True], mods) % mods
    final = rows.get(last, {}).get(last, np.zeros(shape, dtype=np.int64))
    return leading, leading * final % mods * _inverse(scales[False], mods) % mods, bad


def _det_mod(rows: dict[int, dict[int, int]], size: int, p: int) -> int:
    """A determinant mod p, with the pivots the values allow."""
    rows = {i: dict(row) for i, row in rows.items() if i < size}
    product_, pairs = 1, []
    for c in range(size):
        deadline.check()
        candidates = [i for i, row in rows.items() if row.get(c, 0) % p]
        if not candidates:
            return 0
        r = min(candidates)
        pivot_row = rows.pop(r)
        pivot = pivot_row.pop(c)
        product_ = product_ * pivot % p
        pairs.append((r, c))
        inverse = pow(pivot, -1, p)
        for row in rows.values():
            factor = row.pop(c, 0) * inverse % p
            if factor:
                for j, v in pivot_row.items():
                    row[j] = (row.get(j, 0) - factor * v) % p
    return _permutation_sign(pairs) * product_ % p


def _at_point(entries: Entries, size: int, point: tuple[int, ...], p: int) -> tuple[int, int]:
    """Both determinants mod p at one point (where a planned pivot vanishes)."""
    rows: dict[int, dict[int, int]] = {}
    for (i, j), poly in entries.items():
        value = sum(int(c) * math.prod(x**e for x, e in zip(point, m, strict=True))
                    for m, c in poly.iterterms())  # fmt: skip
        rows.setdefault(i, {})[j] = value % p
    leading = {i: {j: v for j, v in row.items() if j < size - 1} for i, row in rows.items()}
    return _det_mod(leading, size - 1, p), _det_mod(rows, size, p)


@cache
def _interpolation_matrices(count: int, primes: tuple[int, ...]) -> np.ndarray:
    """The inverse Vandermonde matrix at 1..count modulo each prime, (count, count,
    primes): coefficients = V^-1 values. Row k of V^-1 holds the Lagrange basis
    polynomial of the point k + 1: prod_(i != k) (x - x_i) / prod_(i != k) (x_k - x_i)."""
    mods = np.array(primes, dtype=np.int64)
    master = np.zeros((count + 1, mods.size), dtype=np.int64)  # prod (x - x_i), low first
    master[0] = 1
    for x in range(1, count + 1):
        master = (np.roll(master, 1, axis=0) - x * master) % mods
    points = np.arange(1, count + 1, dtype=np.int64)[:, None]
    quotients = np.zeros((count, count, mods.size), dtype=np.int64)  # [degree, k, prime]
    carry = np.broadcast_to(master[count], (count, mods.size))
    quotients[count - 1] = carry
    for degree in range(count - 1, 0, -1):  # synthetic division by (x - x_k), every k
        carry = (master[degree] + points * carry) % mods
        quotients[degree - 1] = carry
    factorial = np.ones((count, mods.size), dtype=np.int64)
    for j in range(1, count):
        factorial[j] = factorial[j - 1] * j % mods
    k = np.arange(count)
    signs = np.where((count - 1 - k) % 2, -1, 1)[:, None]
    weights = signs * factorial[k] % mods * factorial[count - 1 - k] % mods
    return quotients * _inverse(weights, mods)[None] % mods


def _interpolate(values: np.ndarray, degrees: tuple[int, ...], mods: np.ndarray) -> np.ndarray:
    """Coefficients (indexed by exponents, then prime) from values on the grid 1..d+1."""
    array = values.reshape([*(d + 1 for d in degrees), mods.size])
    for axis, d in enumerate(degrees):
        matrix = _interpolation_matrices(d + 1, tuple(int(p) for p in mods))
        moved = np.moveaxis(array, axis, 0)
        result = np.zeros_like(moved)
        extra = (1,) * (moved.ndim - 2)
        for k in range(d + 1):
            result = (result + matrix[:, k].reshape(d + 1, *extra, mods.size) * moved[k]) % mods
        array = np.moveaxis(result, 0, axis)
    return array


def _combine(residues: np.ndarray, primes: list[int]) -> dict[tuple[int, ...], int]:
    """Chinese remainders over the last axis, in the symmetric range: the coefficients."""
    modulus, combined = 1, None
    for lane, p in enumerate(primes):
        values = residues[..., lane].astype(object)
        if combined is None:
            combined = values
        else:  # x = combined + modulus t, t = (r - combined) / modulus mod p
            combined = combined + modulus * ((values - combined) % p * pow(modulus, -1, p) % p)
        modulus *= p
    half = modulus // 2
    coefficients = {}
    for index, value in np.ndenumerate(combined):
        value = int(value) - modulus if value > half else int(value)
        if value:
            coefficients[index] = value
    return coefficients


def bordered_determinants(entries: Entries, size: int, ring):
    """det of the leading (size - 1) block and of the whole matrix, exact elements of the
    polynomial ring `ring`; None when the grid would be too large, or when the leading
    block is structurally singular (its determinant is zero for every value): the caller
    then eliminates over the polynomials. `TooLarge` when the coefficients could have
    more than `MAX_BITS` bits."""
    plan = _plan(entries, size, ring.ngens)
    if plan is None:
        return None
    count = math.prod(d + 1 for d in plan.degrees)
    if count > MAX_POINTS:
        return None
    axes = [np.arange(1, d + 2, dtype=np.int64) for d in plan.degrees]
    grid = [a.ravel() for a in np.meshgrid(*axes, indexing="ij")]
    primes = [_prime(i) for i in range(plan.primes)]
    mods = np.array(primes, dtype=np.int64)
    values = {ij: _values(poly, grid, mods) for ij, poly in entries.items()}
    leading, full, bad = _eliminate(plan, values, (count, mods.size), mods)
    if bad.any():
        points = list(product(*(range(1, d + 2) for d in plan.degrees)))
        for index, lane in zip(*np.nonzero(bad), strict=True):
            at = _at_point(entries, size, points[index], primes[lane])
            leading[index, lane], full[index, lane] = at
    return tuple(
        ring.from_dict(_combine(_interpolate(determinant, plan.degrees, mods), primes))
        for determinant in (leading, full)
    )
