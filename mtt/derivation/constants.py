"""The constants a model's values may hold, and the exact field the equations live in.

Parameter values are exact. Besides rational numbers they may hold

* real algebraic numbers: roots of rational numbers, nested or not (`sqrt(7)`, `2^0.5`,
  `2^(1/3)`, `sqrt(1 + sqrt(2))`, `cos(pi/4)`); they are computed with in sympy's algebraic
  number field Q(alpha) for a primitive element alpha of them all, where every relation
  between them holds (sqrt(2)^2 = 2, sqrt(2) sqrt(3) = sqrt(6)), so that results are exact
  and canonical;
* pi, e (`exp(n)` for an integer n) and logarithms of rational numbers (written with the
  logarithms of primes, log(12) = 2 log(2) + log(3)): they are taken as further variables
  of the field, algebraically independent of each other (no algebraic relation between
  them is known; none can be used).

Every other constant (`sin(1)`, `exp(1/2)`, `log(pi)`, `2^pi`) would need relations that
cannot be applied exactly: it is an error (`unsupported_constant`) that gives its decimal
value to write instead. A constant that is not a real number is `bad_value`.

The coefficient field is then Q(alpha)(unknowns, symbols kept, pi, e, logarithms, and
functions of kept symbols such as sqrt(q)).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from fractions import Fraction

import sympy
from sympy.polys.domains import QQ
from sympy.polys.domains.algebraicfield import AlgebraicField
from sympy.polys.domains.domain import Domain
from sympy.polys.numberfields.subfield import primitive_element

from mtt.language.measures import MAX_DEGREE

MAX_FIELD_DEGREE = 16  # of the algebraic numbers of a model, together
MAX_LOG_ARGUMENT = 10**18  # logarithms of rationals: their arguments are factored


class Unsupported(Exception):
    """A constant the field cannot hold: its kind, and a message about `constant`."""

    def __init__(self, kind: str, message: str):
        super().__init__(message)
        self.kind = kind


def _decimal(value: sympy.Expr) -> str:
    return sympy.N(value, 17).__str__()


def _unsupported(constant: sympy.Expr) -> Unsupported:
    return Unsupported(
        "unsupported_constant",
        f"{constant} is a constant mtt cannot compute with exactly (rational numbers, their "
        f"roots, pi, exp of an integer and logarithms of rational numbers are); write its "
        f"value as a decimal, {_decimal(constant)}",
    )


def _algebraic(expr: sympy.Expr) -> bool:
    """Made of rational numbers by + - * / and rational powers (a real algebraic number)."""
    if expr.is_Rational:
        return True
    if expr.is_Add or expr.is_Mul:
        return all(_algebraic(a) for a in expr.args)
    if expr.is_Pow:
        return expr.exp.is_Rational and _algebraic(expr.base)
    return False


class NumberField(AlgebraicField):
    """sympy's algebraic number field, converting its own elements as they are (sympy
    converts between two algebraic fields through sympy expressions and a search for a
    field isomorphism, for each element, even when the two are the same field)."""

    alias = "AlgebraicField"  # the name other domains convert from it by

    def from_AlgebraicField(self, a, K0):  # noqa: N802 - sympy's name for the conversion
        return a if self == K0 else super().from_AlgebraicField(a, K0)


def _degree_bound(expr: sympy.Expr) -> int:
    """A bound on the degree of an algebraic number over Q, from how it is written."""
    if expr.is_Rational:
        return 1
    if expr.is_Pow:
        return expr.exp.q * _degree_bound(expr.base)
    return math.prod(_degree_bound(a) for a in expr.args)


@dataclass
class Constants:
    """What the values of a model's components hold besides rational numbers."""

    algebraic: set = field(default_factory=set)  # the roots (Pow atoms) met
    transcendental: set = field(default_factory=set)  # pi, E, log(p)
    functions: set = field(default_factory=set)  # of kept symbols: sqrt(q), exp(q)...
    elements: dict = field(default_factory=dict)  # each root, as an element of `ground()`

    def scan(self, value: sympy.Expr) -> sympy.Expr:
        """Record what `value` holds and return it with every logarithm of a rational
        number written with those of primes; raise `Unsupported` for what the field cannot
        hold."""
        logs = [a for a in value.atoms(sympy.log) if a.args[0].is_Rational]
        for log in logs:
            argument = log.args[0]
            if argument > 0 and max(abs(argument.p), argument.q) > MAX_LOG_ARGUMENT:
                raise _unsupported(log)  # its argument would be factored
        value = value.xreplace({log: self._logs(log.args[0]) for log in logs if log.args[0] > 0})
        self._scan(value)
        return value

    def _scan(self, expr: sympy.Expr) -> None:
        if expr.is_Rational or expr.is_Symbol:
            return
        if expr.is_number:
            self._constant(expr)
        elif expr.is_Add or expr.is_Mul or (expr.is_Pow and expr.exp.is_Integer):
            for argument in expr.args:
                self._scan(argument)
        else:  # sqrt(q), exp(q), 2^q, of parameters kept symbolic: variables of their own
            self.functions.add(expr)

    def _constant(self, expr: sympy.Expr) -> None:
        if expr.is_extended_real is False:
            raise Unsupported("bad_value", f"{expr} is not a real number")
        if _algebraic(expr):
            self.algebraic.update(
                a for a in sympy.preorder_traversal(expr) if a.is_Pow and not a.exp.is_Integer
            )
        elif expr in (sympy.pi, sympy.E):
            self.transcendental.add(expr)
        elif isinstance(expr, sympy.exp) and expr.args[0].is_Integer:
            if abs(expr.args[0]) > MAX_DEGREE:
                message = f"{expr} is out of range: a power of e above {MAX_DEGREE}"
                raise Unsupported("syntax", message)
            self.transcendental.add(sympy.E)
        elif isinstance(expr, sympy.log) and expr.args[0].is_Integer and expr.args[0].is_prime:
            self.transcendental.add(expr)  # the logarithm of a prime (see `scan`)
        elif expr.is_Add or expr.is_Mul or (expr.is_Pow and expr.exp.is_Integer):
            for argument in expr.args:
                self._scan(argument)
        else:
            raise _unsupported(expr)

    @staticmethod
    def _logs(argument: sympy.Rational) -> sympy.Expr:
        """log(argument) written with the logarithms of primes: log(12) = 2 log(2) + log(3)."""
        return sympy.expand_log(sympy.log(argument), force=True, factor=True)

    def ground(self) -> Domain:
        """QQ, or the algebraic number field of the roots met: Q(theta) for a primitive
        element theta, each root written as a polynomial in it once (`elements`)."""
        if not self.algebraic:
            return QQ
        roots = sorted(self.algebraic, key=sympy.default_sort_key)
        degree = 1
        for root in roots:  # a bound first: 2^(1/1000) must not reach minimal_polynomial
            bound = _degree_bound(root)
            if bound <= MAX_FIELD_DEGREE:
                bound = sympy.degree(sympy.minimal_polynomial(root, sympy.Dummy()))
            degree *= bound
            if degree > MAX_FIELD_DEGREE:
                raise Unsupported(
                    "too_large",
                    f"the roots in the model ({', '.join(map(str, roots))}) together need a "
                    f"number field of degree above {MAX_FIELD_DEGREE}; write some of them as "
                    "decimals",
                )
        minimal, coefficients, polynomials = primitive_element(roots, sympy.Dummy(), ex=True)
        theta = sympy.Add(*(c * root for c, root in zip(coefficients, roots, strict=True)))
        field_ = NumberField(QQ, (minimal, theta))
        self.elements = {
            root: field_.new(rep) for root, rep in zip(roots, polynomials, strict=True)
        }
        return field_

    def element(self, K: Domain, value: sympy.Expr):
        """`value` as an element of the coefficient field K (over `ground()`): its roots
        are put in as the field's elements, not found again by sympy for each value."""
        if not self.elements:
            return K.from_sympy(value)
        names = tuple(K.symbols) if K.is_FractionField else ()
        # the field's variables that are expressions (log(q - sqrt(2))) keep their roots
        kept = {g: sympy.Dummy() for g in names if not g.is_Symbol}
        dummies = {root: sympy.Dummy() for root in self.elements}
        helper = QQ.frac_field(*(kept.get(g, g) for g in names), *dummies.values())
        fraction = helper.from_sympy(value.xreplace(kept).xreplace(dummies))
        ground = K.domain if K.is_FractionField else K
        roots = list(self.elements.values())

        def mapped(poly) -> dict:
            terms: dict = {}
            for monom, coefficient in poly.terms():
                constant = ground.convert(coefficient, QQ)
                for root, power in zip(roots, monom[len(names) :], strict=True):
                    constant *= root**power
                key = monom[: len(names)]
                terms[key] = terms.get(key, ground.zero) + constant
            return terms

        numerator, denominator = mapped(fraction.numer), mapped(fraction.denom)
        if not K.is_FractionField:
            return numerator.get((), ground.zero) / denominator[()]
        ring = K.field.ring
        return K.field.new(ring.from_dict(numerator), ring.from_dict(denominator))

    def variables(self) -> list[sympy.Expr]:
        """pi, e, the logarithms and the functions of symbols, in a fixed order."""
        return sorted(self.transcendental | self.functions, key=sympy.default_sort_key)


# The determinants of a matrix over Q(theta), by integers: theta as one more variable t ----


def over_integers(entries: dict, ring) -> tuple[dict, dict, object]:
    """Polynomials over Q(theta) (a number field's elements are polynomials in theta of
    degree below the field's) as polynomials over ZZ with one more variable t for theta,
    each row scaled by the least common denominator of its rational numbers: the entries,
    each row's scale, and the new ring. A determinant of them, reduced by `reduced`, is the
    determinant over Q(theta) times the product of the scales."""
    from sympy.polys.domains import ZZ
    from sympy.polys.rings import PolyRing

    integers = PolyRing((*ring.symbols, sympy.Dummy("theta")), ZZ)
    rational: dict = {}
    for (i, j), poly in entries.items():
        terms = rational.setdefault(i, {}).setdefault(j, {})
        for monom, coefficient in poly.terms():
            for power, q in enumerate(reversed(coefficient.to_list())):
                if q:
                    terms[(*monom, power)] = Fraction(int(q.numerator), int(q.denominator))
    scales, converted = {}, {}
    for i, row in rational.items():
        scales[i] = math.lcm(*(q.denominator for terms in row.values() for q in terms.values()))
        for j, terms in row.items():
            converted[(i, j)] = integers.from_dict(
                {monom: int(q * scales[i]) for monom, q in terms.items()}
            )
    return converted, scales, integers


def reduced(poly, ring):
    """A polynomial over ZZ in `ring`'s variables and theta, as one over Q(theta) (`ring`'s
    domain): every power of theta reduced by theta's minimal polynomial."""
    field = ring.domain
    theta = field.new([1, 0])
    powers = [field.one]
    terms: dict = {}
    for monom, coefficient in poly.terms():
        *rest, power = monom
        while len(powers) <= power:
            powers.append(powers[-1] * theta)
        key = tuple(rest)
        terms[key] = terms.get(key, field.zero) + field.convert(int(coefficient)) * powers[power]
    return ring.from_dict({k: v for k, v in terms.items() if v})
