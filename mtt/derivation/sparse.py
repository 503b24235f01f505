"""Sparse polynomial products and exact quotients, paid for on the derivation's `Meter`.

sympy's `PolyElement.exquo` finds the leading term of the remainder by scanning all of
its terms at every step: time quadratic in the terms (36 of 40 s of a 4 x 4 symbolic mesh
went there, far more than the budget charged). Here the quotient's terms come in
decreasing order from a heap that holds, for each quotient term q_i found so far, its next
product q_i g_j with the divisor's terms (Johnson's heap division, as in Monagan and
Pearce, "Sparse polynomial division using a heap", J. Symb. Comp. 2011): |q| |g| products,
each one step on a heap of at most |q| + 1 entries, some `DIVISION_COST` times the time of a
product in a multiplication. Monomials are packed into one integer each (a byte a variable,
the first variable highest, so that integer order is the ring's lex order): a product of
monomials is one addition.

A product is paid for before it is made, and watched as it grows: one that passes
`PARTIAL` times the budget's terms stops there, before its memory does (a product of two
polynomials within the budget can have their product of terms: 10^7 of them, gigabytes).
"""

from __future__ import annotations

import heapq
from functools import cmp_to_key

import sympy
from sympy.polys.rings import PolyElement

from mtt.derivation.budget import Meter, TooLarge

_FIELD = 8  # bits a variable: exponents below 2^7, the top bit of each byte a guard
# a product q_i g_j in the heap division costs about four products of a multiplication
# (a heap step and a tuple each; measured: 3 us against 0.7 us)
DIVISION_COST = 4
# a product of terms in many variables costs more: one unit of work per this many of them
# (a mesh of 49 nodes has 135: its products took some ten times a ladder's)
VARIABLES_PER_UNIT = 16
# a product stops when it has this many times the budget's terms (the final product is
# held to the budget itself: this bounds the memory of one that cancels to fewer)
PARTIAL = 4


def _packable(*polys: PolyElement) -> bool:
    """Over the integers, with exponents that stay below 2^7 in a product of them."""
    ring = polys[0].ring
    return (
        ring.domain.is_ZZ
        and ring.ngens > 0
        and sum(max(max(m) for m in p) for p in polys) < 1 << (_FIELD - 1)
    )


def term_cost(ring) -> int:
    """The work one product (or quotient) of two terms costs in `ring`, in the `Meter`'s
    units (a product of terms in a few variables)."""
    return 1 + ring.ngens // VARIABLES_PER_UNIT


def _degrees(p: PolyElement) -> list[int]:
    """p's degree in each variable."""
    return [max(exponents) for exponents in zip(*p.keys(), strict=True)]


def _pack(m: tuple[int, ...]) -> int:
    return int.from_bytes(bytes(m), "big")


def product(a: PolyElement, b: PolyElement, meter: Meter) -> PolyElement:
    """a * b, paid for first (|a| |b| products of terms) and held after; `TooLarge` as soon
    as it grows past `PARTIAL` times the budget's terms."""
    meter.spend(len(a) * len(b) * term_cost(a.ring))
    if len(a) < len(b):
        a, b = b, a
    if len(b) <= 1 or not _packable(a, b):
        result = a * b
        meter.hold(len(result))
        return result
    ring, cap = a.ring, PARTIAL * meter.budget.max_terms
    inner = [(_pack(m), c) for m, c in a.items()]
    terms: dict[int, object] = {}
    get = terms.get
    for mb, cb in b.items():
        mb = _pack(mb)
        for ma, ca in inner:
            m = ma + mb
            terms[m] = get(m, 0) + ca * cb
        if len(terms) > cap:
            raise TooLarge(meter.stage, "terms", len(terms), meter.budget.max_terms)
    width = ring.ngens
    result = ring.dtype([(tuple(m.to_bytes(width, "big")), c) for m, c in terms.items() if c])
    meter.hold(len(result))
    return result


def _term_quotient(f: PolyElement, g: PolyElement, meter: Meter) -> PolyElement:
    """f / g for a divisor of one term: each monomial's difference in one subtraction of
    packed integers (a loop over a hundred exponents a term was most of a mesh's time)."""
    ring = f.ring
    meter.spend(len(f) * term_cost(ring))
    ((gm, gc),) = g.items()
    domain = ring.domain
    divide = (lambda c: divmod(c, gc)) if domain.is_ZZ else (lambda c: (domain.exquo(c, gc), 0))
    if not _packable(f, g):
        terms = []
        for m, c in f.items():
            exponents = tuple(a - b for a, b in zip(m, gm, strict=True))
            q, remainder = divide(c)
            if remainder or min(exponents, default=0) < 0:
                raise NotDivisible("the divisor does not divide the polynomial")
            terms.append((exponents, q))
        return ring.dtype(terms)
    width, lead = ring.ngens, _pack(gm)
    guards = int.from_bytes(bytes([1 << (_FIELD - 1)]) * width, "big")
    terms = []
    for m, c in f.items():
        packed = _pack(m)
        q, remainder = divide(c)
        if remainder or ((packed | guards) - lead) & guards != guards:
            raise NotDivisible("the divisor does not divide the polynomial")
        terms.append((tuple((packed - lead).to_bytes(width, "big")), q))
    return ring.dtype(terms)


class NotDivisible(ArithmeticError):
    """The divisor does not divide the dividend (never, where the algebra says it does)."""


def exact_quotient(f: PolyElement, g: PolyElement, meter: Meter) -> PolyElement:
    """f / g, for a divisor g known to divide f exactly, over the integers (over any other
    domain, or with an exponent of 128 or more, by sympy's division, charged at its cost);
    `NotDivisible` if it does not."""
    ring = f.ring
    if not g:
        raise ZeroDivisionError("division by the zero polynomial")
    if not f:
        return ring.zero
    if len(g) == 1:
        return _term_quotient(f, g, meter)
    if not _packable(f):
        # sympy's division: a scan of the remainder for each quotient term
        meter.spend(DIVISION_COST * len(f) * (len(f) + len(g)) * term_cost(ring))
        quotient, remainder = f.div(g)
        if remainder:
            raise NotDivisible("the divisor does not divide the polynomial")
        return quotient
    width = ring.ngens
    # a quotient's exponents are at most f's degrees less g's, variable by variable: held
    # to that, every product q_i g_j stays within f's degrees (below 2^7: no carry)
    room = [a - b for a, b in zip(_degrees(f), _degrees(g), strict=True)]
    if min(room) < 0:
        raise NotDivisible("the divisor does not divide the polynomial")
    bound = _pack(tuple(room))
    # monomials packed, negated: the heap's least entry is the greatest monomial
    fm, fc = zip(*sorted((-_pack(m), c) for m, c in f.items()), strict=True)
    gm, gc = zip(*sorted((-_pack(m), c) for m, c in g.items()), strict=True)
    lead, lead_coefficient, nf, ng = gm[0], gc[0], len(fm), len(gm)
    cost = DIVISION_COST * ng * term_cost(ring)  # a quotient term's products
    guards = int.from_bytes(bytes([1 << (_FIELD - 1)]) * width, "big")
    qm: list[int] = []  # the quotient's terms, as they come (decreasing)
    qc: list = []
    heap = [(fm[0], -1, 0)]  # (monomial, i, j): i = -1 for f's term j, else q_i g_j
    replace, pop, push = heapq.heapreplace, heapq.heappop, heapq.heappush
    while heap:
        monomial = heap[0][0]
        coefficient = 0
        while heap and heap[0][0] == monomial:
            _, i, j = heap[0]
            j += 1
            if i < 0:
                coefficient += fc[j - 1]
                replace(heap, (fm[j], -1, j)) if j < nf else pop(heap)
            else:
                coefficient -= qc[i] * gc[j - 1]
                replace(heap, (qm[i] + gm[j], i, j)) if j < ng else pop(heap)
        if not coefficient:
            continue
        q, remainder = divmod(coefficient, lead_coefficient)
        if remainder or ((-monomial | guards) + lead) & guards != guards:
            raise NotDivisible("the divisor does not divide the polynomial")
        if ((bound | guards) + monomial - lead) & guards != guards:
            raise NotDivisible("the divisor does not divide the polynomial")
        meter.spend(cost)
        qm.append(monomial - lead)
        qc.append(q)
        meter.hold(len(qm))
        push(heap, (qm[-1] + gm[1], len(qm) - 1, 1))
    unpack = lambda m: tuple((-m).to_bytes(width, "big"))  # noqa: E731
    return ring.dtype([(unpack(m), c) for m, c in zip(qm, qc, strict=True)])


_CANONICAL = cmp_to_key(sympy.Basic.compare)  # the order of a product's factors in sympy


def as_expr(poly: PolyElement) -> sympy.Expr:
    """`poly.as_expr()`, the same expression, made faster: each term's product put together
    in sympy's canonical order from one sort of the powers that occur, not by sympy's
    general product (which flattens and sorts each term again: 2.4 ms a term of a symbolic
    ladder's result on a loaded machine). Over other domains than the integers and the
    rationals (a coefficient can be a sum there), sympy's own."""
    ring = poly.ring
    if not (ring.domain.is_ZZ or ring.domain.is_QQ):
        return poly.as_expr()
    powers: dict[tuple[int, int], sympy.Expr] = {}
    terms = []
    for monomial, coefficient in poly.items():
        factors = []
        for i, e in enumerate(monomial):
            if e:
                factor = powers.get((i, e))
                if factor is None:
                    x = ring.symbols[i]
                    factor = powers[i, e] = x if e == 1 else sympy.Pow(x, e)
                factors.append(factor)
        terms.append((ring.domain.to_sympy(coefficient), factors))
    rank = {id(f): r for r, f in enumerate(sorted(powers.values(), key=_CANONICAL))}
    order = lambda factor: rank[id(factor)]  # noqa: E731
    made = []
    for c, factors in terms:
        factors.sort(key=order)
        if not factors:
            made.append(c)
        elif c == 1 and len(factors) == 1:
            made.append(factors[0])
        else:
            made.append(sympy.Mul._from_args(tuple(factors) if c == 1 else (c, *factors), True))
    return sympy.Add(*made)
