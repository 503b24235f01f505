"""The transfer function's two determinants by sparse fraction-free elimination over the
polynomials, for matrices in many symbols (where evaluation would need too many points).

G(s) = det(bordered) / det(leading block) (see `transfer`). Eliminating pivot after pivot
in a fill-reducing (Markowitz) order, the entries of the remaining Schur complement are
ratios of minors: with K the pivots taken so far (rows and columns, paired),

    S_ij = det A[K + i, K + j] / det A[K, K].

The pivots taken fall into components, connected through the nonzero entries of A among
them, and det A[K, K] is the product of the components' determinants. A component that
row i does not reach (no nonzero A[i, c] with c one of its columns), or that does not
reach column j, factors out of both determinants; so S_ij = N_ij / D(R_i & Q_j), with
N_ij a minor of A (a polynomial), R_i the components row i reaches, Q_j those that reach
column j and D(X) the product of the determinants of the components X. The elimination
keeps the polynomials N_ij and each component's determinant as a product of polynomial
factors: taking pivot (r, c) joins r, c and the components U = R_r | Q_c into one, of
determinant N_rc D(R_r ^ Q_c), and each N_ij of a row and a column that reach it becomes

    (N_ij N_rc D(R_r ^ Q_c) / D(W)) - (N_ic N_rj D(V) D(U) / (D(R_i & Q_c) D(R_r & Q_j)))

(W = R_i & Q_j & U, V = (R_i & Q_j) - U), written over the common denominator of the
factors, which divides it exactly. Nothing else changes. On a ladder the components never
share a row, nothing is divided, and each step costs the size of the minor it makes: the
continuant recursion of the ABCD product, found from the matrix. Each product is paid for
on the derivation's `Meter` first.

The ratio of the determinants is then N_ll / D(R_l & Q_l) for the last row and column l:
the components the border does not reach cancel (their factors are returned apart, for
callers that check them).
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass

from sympy.polys.rings import PolyElement, PolyRing

from mtt.derivation import sparse
from mtt.derivation.budget import Meter

Entries = dict[tuple[int, int], PolyElement]


@dataclass(frozen=True)
class Ratio:
    """det(whole) / det(leading block) = num / prod(den); det(leading block) is
    +-prod(den) prod(other)."""

    num: PolyElement
    den: tuple[PolyElement, ...]
    other: tuple[PolyElement, ...]


class _Elimination:
    def __init__(self, entries: Entries, size: int, ring: PolyRing, meter: Meter):
        self.ring, self.meter, self.last = ring, meter, size - 1
        self.rows: dict[int, dict[int, PolyElement]] = {i: {} for i in range(size)}
        self.cols: dict[int, set[int]] = {j: set() for j in range(size)}
        self.reaches_col: dict[int, set[int]] = {j: set() for j in range(size)}  # A's pattern
        self.reaches_row: dict[int, set[int]] = {i: set() for i in range(size)}
        for (i, j), p in entries.items():
            if p:
                self.rows[i][j] = p
                self.cols[j].add(i)
                self.reaches_col[j].add(i)
                self.reaches_row[i].add(j)
        self.R: dict[int, frozenset[int]] = {i: frozenset() for i in range(size)}
        self.Q: dict[int, frozenset[int]] = {j: frozenset() for j in range(size)}
        self.rows_of: dict[int, set[int]] = {}  # component -> the rows that reach it
        self.cols_of: dict[int, set[int]] = {}
        self.factors: list[PolyElement] = []
        self.components: dict[int, Counter] = {}  # component -> its factors, with powers
        self.fresh = 0

    def D(self, components) -> Counter:
        total: Counter = Counter()
        for c in components:
            total.update(self.components[c])
        return total

    def expanded(self, powers: dict[int, int]) -> list[PolyElement]:
        """Factors with powers, as a list of factors."""
        return [self.factors[f] for f, e in powers.items() for _ in range(e)]

    def product(self, polys: list[PolyElement]) -> PolyElement:
        result = self.ring.one
        for p in sorted(polys, key=len):
            result = sparse.product(result, p, self.meter) if result != 1 else p
        return result

    def pivot(self) -> tuple[int, int] | None:
        """The nonzero entry of the leading block with the least Markowitz cost (the fewest
        terms among equals)."""
        best = None
        for j, col in self.cols.items():
            if j == self.last:
                continue
            others = len(col) - 1
            for i in col:
                if i != self.last:
                    cost = ((len(self.rows[i]) - 1) * others, len(self.rows[i][j]))
                    if best is None or cost < best[0]:
                        best = (cost, i, j)
        return None if best is None else best[1:]

    def take(self, r: int, c: int) -> None:
        rows, cols, R, Q = self.rows, self.cols, self.R, self.Q
        U = R[r] | Q[c]
        prow = rows.pop(r)
        pcol = {i: rows[i].pop(c) for i in cols.pop(c) if i != r}
        Nrc = prow.pop(c)
        for j in prow:
            cols[j].discard(r)
        self.factors.append(Nrc)
        star = self.fresh
        self.fresh += 1
        new = Counter({len(self.factors) - 1: 1}) + self.D(R[r] ^ Q[c])
        touched_rows, touched_cols = set(self.reaches_col[c]), set(self.reaches_row[r])
        for component in U:
            touched_rows |= self.rows_of.pop(component)
            touched_cols |= self.cols_of.pop(component)
        touched_rows &= rows.keys()
        touched_cols &= cols.keys()
        delta, DU = self.D(R[r] ^ Q[c]), self.D(U)
        updates = {}
        for i in touched_rows:
            row, Nic = rows[i], pcol.get(i)
            columns = (row.keys() & touched_cols) | (prow.keys() if Nic is not None else set())
            for j in columns:
                terms = []
                both = R[i] & Q[j]
                if j in row:
                    exponents = Counter(delta)
                    exponents.subtract(self.D(both & U))
                    terms.append((1, [row[j], Nrc], exponents))
                if Nic is not None and j in prow:
                    exponents = self.D(both - U) + DU
                    exponents.subtract(self.D(R[i] & Q[c]))
                    exponents.subtract(self.D(R[r] & Q[j]))
                    terms.append((-1, [Nic, prow[j]], exponents))
                updates[i, j] = self.combine(terms)
        for component in U:
            del self.components[component]
        self.components[star] = new
        for i in touched_rows:
            R[i] = (R[i] - U) | {star}
        for j in touched_cols:
            Q[j] = (Q[j] - U) | {star}
        self.rows_of[star], self.cols_of[star] = touched_rows, touched_cols
        del R[r], Q[c]
        for (i, j), value in updates.items():
            if value:
                rows[i][j] = value
                cols[j].add(i)
            else:
                rows[i].pop(j, None)
                cols[j].discard(i)

    def combine(self, terms) -> PolyElement:
        """sum(sign * prod(polys) * prod(factor^e)) over terms, with negative powers e
        divided out at the end (exactly: the sum is a minor)."""
        divisor: Counter = Counter()
        for _, _, exponents in terms:
            for f, e in exponents.items():
                divisor[f] = max(divisor[f], -e)
        total = self.ring.zero
        for sign, polys, exponents in terms:
            powers = {f: e + divisor[f] for f, e in exponents.items()}
            powers.update((f, e) for f, e in divisor.items() if f not in exponents)
            scaled = self.product(polys + self.expanded(powers))
            self.meter.spend(len(scaled) * sparse.term_cost(self.ring))
            total = total + scaled if sign > 0 else total - scaled
        for f, e in divisor.items():
            for _ in range(e):
                total = sparse.exact_quotient(total, self.factors[f], self.meter)
        self.meter.hold(len(total))
        return total


def bordered_ratio(entries: Entries, size: int, ring: PolyRing, meter: Meter) -> Ratio | None:
    """det(A) / det(A's leading size - 1 block) for the sparse size x size matrix A over the
    polynomial ring; None when the leading block is singular."""
    work = _Elimination(entries, size, ring, meter)
    for _ in range(size - 1):
        chosen = work.pivot()
        if chosen is None:
            return None
        work.take(*chosen)
    last = work.last
    near = work.R[last] & work.Q[last]
    listed = lambda components: tuple(work.expanded(work.D(components)))  # noqa: E731
    return Ratio(
        work.rows[last].get(last, ring.zero),
        listed(near),
        listed(work.components.keys() - near),
    )
