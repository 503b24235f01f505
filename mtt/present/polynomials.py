"""Polynomials as people read them: in powers of s, each coefficient factored.

A symbolic result can have thousands of terms (2584 in an 8-section ladder's denominator),
and sympy's general expressions take seconds a coefficient to sort, expand and take
common factors out of (14 s to print that ladder's transfer function, against 0.4 s to
derive it). So the work is done on sympy's sparse polynomials over the rationals, and
only a small coefficient, which reads better fully factored, goes through `sympy.factor`.
"""

from __future__ import annotations

import sympy
from sympy.polys.rings import PolyElement, ring

from mtt.derivation.sparse import as_expr
from mtt.derivation.transfer import LAPLACE

# Beyond these, sympy's multivariate factoring takes too long (it looks for primes of the
# numbers' size, and factors of a sum of many terms or in many symbols: 1.5 s for a
# coefficient of 20 terms in 21 symbols): only common factors are taken out.
FACTOR_MAX_TERMS = 24
FACTOR_MAX_DIGITS = 40
FACTOR_MAX_SYMBOLS = 12


def sparse(expression: sympy.Expr, *first: sympy.Symbol) -> PolyElement | None:
    """The expression as a polynomial over the rationals in `first`, then its other symbols
    by name; None when it is not an expanded one (an algebraic number or a function in it,
    a product of sums). Term by term, in time linear in the terms (sympy's `from_expr`
    adds them one by one, copying the sum each time: 10 minutes for 121393 terms)."""
    others = sorted(expression.free_symbols - set(first), key=lambda x: x.name)
    gens = [*first, *others]
    if not gens:
        return None
    index = {x: i for i, x in enumerate(gens)}
    terms: dict[tuple[int, ...], sympy.Rational] = {}
    for term in sympy.Add.make_args(expression):
        coefficient, factors = term.as_coeff_mul()
        if not isinstance(coefficient, sympy.Rational):
            return None
        monomial = [0] * len(gens)
        for factor in factors:
            base, exponent = factor.as_base_exp()
            if base not in index or not (exponent.is_Integer and exponent.is_positive):
                return None
            monomial[index[base]] += int(exponent)
        key = tuple(monomial)
        terms[key] = terms[key] + coefficient if key in terms else coefficient
    return ring(gens, sympy.QQ)[0].from_dict({m: c for m, c in terms.items() if c != 0})


def in_powers_of_s(expression: sympy.Expr) -> str:
    """A polynomial in s written highest power first, each coefficient factored."""
    terms = []
    for power, coefficient in _coefficients(expression):
        c = factored(coefficient)
        monomial = {0: "", 1: "s"}.get(power, f"s**{power}")
        if not monomial:
            terms.append(text(c))
        elif c == 1:
            terms.append(monomial)
        elif c == -1:
            terms.append(f"-{monomial}")
        else:
            terms.append(f"{grouped(c)}*{monomial}")
    return " + ".join(terms).replace("+ -", "- ") or "0"


def _coefficients(expression: sympy.Expr) -> list[tuple[int, sympy.Expr]]:
    """The (power of s, coefficient) pairs of a polynomial in s, highest power first."""
    p = sparse(expression, LAPLACE)
    if p is None:
        return [(power, c) for (power,), c in sympy.Poly(expression, LAPLACE).terms()]
    by_power: dict[int, dict[tuple[int, ...], object]] = {}
    for monomial, c in p.items():
        by_power.setdefault(monomial[0], {})[monomial[1:]] = c
    rest = ring(p.ring.symbols[1:], sympy.QQ)[0] if p.ring.ngens > 1 else None
    pairs = []
    for power in sorted(by_power, reverse=True):
        terms = by_power[power]
        if rest is None:
            pairs.append((power, sympy.QQ.to_sympy(terms[()])))
        else:
            pairs.append((power, as_expr(rest.from_dict(terms))))
    return pairs


def factored(polynomial: sympy.Expr) -> sympy.Expr:
    """The polynomial factored, when that is cheap: one of many terms or of huge numbers
    only has its common factors taken out."""
    p = sparse(polynomial)
    if p is None:
        numbers = polynomial.atoms(sympy.Rational)
        digits = max((_digits(r) for r in numbers), default=0)
        terms = len(sympy.Add.make_args(sympy.expand(polynomial)))
        if digits > FACTOR_MAX_DIGITS or terms > FACTOR_MAX_TERMS:
            return sympy.factor_terms(polynomial)
        return sympy.factor(polynomial)
    digits = max((_digits(sympy.QQ.to_sympy(c)) for c in p.values()), default=0)
    many = len(p) > FACTOR_MAX_TERMS or p.ring.ngens > FACTOR_MAX_SYMBOLS
    if digits > FACTOR_MAX_DIGITS or many:
        return common_factors_out(p)
    return sympy.factor(polynomial)


def _digits(r: sympy.Rational) -> int:
    return len(str(abs(r.p))) + len(str(r.q))


def common_factors_out(p: PolyElement) -> sympy.Expr:
    """content * common monomial * the rest, the content negative only when every term is:
    what `sympy.factor_terms` makes of an expanded polynomial, without sorting every term
    again at each step."""
    common = tuple(map(min, zip(*p.itermonoms(), strict=True)))
    shifted = {tuple(e - g for e, g in zip(m, common, strict=True)): c for m, c in p.items()}
    rest = p.ring.from_dict(shifted)
    content = rest.content()
    if all(c < 0 for c in rest.itercoeffs()):
        content = -content
    monomial = sympy.Mul(*(x**e for x, e in zip(p.ring.symbols, common, strict=True)))
    body = sympy.Mul(monomial, as_expr(rest.quo_ground(content)))
    c = sympy.QQ.to_sympy(content)
    if c == 1:
        return body
    return sympy.Mul(c, body, evaluate=not isinstance(body, sympy.Add))


def grouped(expression: sympy.Expr) -> str:
    """The expression as text, in parentheses when it is a sum."""
    return f"({text(expression)})" if isinstance(expression, sympy.Add) else text(expression)


def text(expression: sympy.Expr) -> str:
    """`str(expression)`, the same characters, written from the sparse polynomial when the
    expression is a long sum of integer terms, or a product with one: sympy's printer sorts
    the terms through their general form (9 s for the 17711 of a 10-section ladder)."""
    args = sympy.Mul.make_args(expression)
    sums = [a for a in args if isinstance(a, sympy.Add) and len(a.args) > FACTOR_MAX_TERMS]
    if len(sums) != 1:
        return str(expression)
    written = _sum_text(sums[0])
    if written is None:
        return str(expression)
    if len(args) == 1:
        return written
    head = sympy.Mul(*(a for a in args if a is not sums[0]))
    if head.as_coeff_Mul()[0].is_Integer is not True or head.has(sympy.Add):
        return str(expression)
    prefix = {1: "", -1: "-"}.get(head, f"{head}*") if head.is_Number else f"{head}*"
    return f"{prefix}({written})"


def _sum_text(expression: sympy.Add) -> str | None:
    """A sum of integer multiples of monomials as sympy prints it: terms in descending
    lexicographic order of the symbols sorted by name, each product's factors by name."""
    p = sparse(expression)
    if p is None or not all(c.denominator == 1 for c in p.itercoeffs()):
        return None
    names = [str(x) for x in p.ring.symbols]
    terms = []
    for monomial, c in p.terms():
        factors = "*".join(
            n if e == 1 else f"{n}**{e}" for n, e in zip(names, monomial, strict=True) if e
        )
        c = int(c)
        if not factors:
            term = str(c)
        elif abs(c) == 1:
            term = factors if c == 1 else f"-{factors}"
        else:
            term = f"{c}*{factors}"
        terms.append(term)
    return terms[0] + "".join(f" - {t[1:]}" if t[0] == "-" else f" + {t}" for t in terms[1:])
