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
# numbers' size, and factors of a sum of many terms): only common factors are taken out.
FACTOR_MAX_TERMS = 24
FACTOR_MAX_DIGITS = 40


def sparse(expression: sympy.Expr, *first: sympy.Symbol) -> PolyElement | None:
    """The expression as a polynomial over the rationals in `first`, then its other symbols
    by name; None when it is not one (an algebraic number or a function in it)."""
    others = sorted(expression.free_symbols - set(first), key=lambda x: x.name)
    gens = [*first, *others]
    if not gens:
        return None
    try:
        return ring(gens, sympy.QQ)[0].from_expr(expression)
    except ValueError:
        return None


def in_powers_of_s(expression: sympy.Expr) -> str:
    """A polynomial in s written highest power first, each coefficient factored."""
    terms = []
    for power, coefficient in _coefficients(expression):
        c = factored(coefficient)
        monomial = {0: "", 1: "s"}.get(power, f"s**{power}")
        if not monomial:
            terms.append(str(c))
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
    if digits > FACTOR_MAX_DIGITS or len(p) > FACTOR_MAX_TERMS:
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
    return f"({expression})" if isinstance(expression, sympy.Add) else str(expression)
