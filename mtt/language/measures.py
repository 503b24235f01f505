"""Measuring expressions before any algebra: exact rational arithmetic, bounds on the rest.

Untrusted text must not ask the later stages (sympy, the derivation) for unbounded work,
so every expression is measured as it is read, and again once the parameters' values are
known (`model_values.check_values`), before sympy ever sees it. Rational numbers are folded exactly
(fractions); every other value gets bounds on its degree, terms and digits once written
as one expanded fraction, its nesting depth and size, and, for a constant that is not
rational (pi, roots, functions), a float value. The limits, reported at their place:

* numbers: at most `MAX_DIGITS` digits in a numerator or denominator (`1e999999999`,
  `10^10^10`), roots and functions of numbers of at most `MAX_ROOT_DIGITS` digits;
* nesting at most `MAX_DEPTH` deep, at most `MAX_SIZE` numbers, names and operators;
* degree in the names and constants at most `MAX_DEGREE` (`k^500`), at most `MAX_TERMS`
  terms once expanded (`(a+b+c+d+e)^100`);
* constants that are not rational at most `MAX_MAGNITUDE` in size (`exp(exp(exp(9)))`),
  `exp` of at most `MAX_EXP_ARGUMENT` (`exp(1e100)`).
"""

from __future__ import annotations

import math
from dataclasses import replace
from fractions import Fraction

from mtt.language import intervals
from mtt.language.diagnostics import Position
from mtt.language.expressions import (
    Measure,
)

MAX_DIGITS = 4000  # below the 4300 digits CPython converts between int and str by default
MAX_ROOT_DIGITS = 100  # sympy looks for perfect powers and factors of a root's argument
MAX_DEPTH = 100
MAX_SIZE = 1000
MAX_DEGREE = 100
MAX_TERMS = 10_000
MAX_MAGNITUDE = 1e300
MAX_EXP_ARGUMENT = 690  # exp(690) ~ 1e300

PI = Measure(approx=math.pi, bounds=intervals.widened(math.pi, math.pi), degree=(1, 0))
DIGITS_LIMIT = 10**MAX_DIGITS  # a numerator or denominator this large has too many digits


class Problem(Exception):
    """A limit or an undefined value met while measuring: its kind, message and place."""

    def __init__(self, kind: str, message: str, position: Position):
        super().__init__(message)
        self.kind, self.position = kind, position


class Infinite(Problem):
    """A value that is undefined or infinite (1/0, 0^-1, log(0)): a syntax error in the
    text; once parameters' values are put in, an infinite parameter (`singular_model`,
    reported by the derivation)."""

    def __init__(self, message: str, position: Position):
        super().__init__("syntax", message, position)


def number(text: str) -> Fraction:
    """A decimal literal's exact value; ValueError when it is out of range."""
    mantissa, _, exponent = text.lower().partition("e")
    if len(mantissa) > MAX_DIGITS:
        raise ValueError("number has too many digits")
    sign = -1 if exponent.startswith("-") else 1
    exponent = exponent.lstrip("+-").lstrip("0") or "0"
    if len(exponent) > len(str(MAX_DIGITS)):
        raise ValueError("number out of range")
    return Fraction(mantissa) * Fraction(10) ** (sign * int(exponent))


def _log10(value: int) -> float:
    return math.log10(abs(value)) if value else 0.0


def _digits(value: Fraction) -> float:
    return max(_log10(value.numerator), _log10(value.denominator))


def rational(value: Fraction, where: Position) -> Measure:
    """The measure of a rational number, which must have at most `MAX_DIGITS` digits."""
    if abs(value.numerator) >= DIGITS_LIMIT or value.denominator >= DIGITS_LIMIT:
        raise Problem("syntax", "number out of range", where)
    return Measure(exact=value, digits=(_log10(value.numerator), _log10(value.denominator)))


def _float(m: Measure) -> float | None:
    if m.exact is None:
        return m.approx
    try:
        return float(m.exact)
    except OverflowError:
        return math.inf if m.exact > 0 else -math.inf


def _interval(m: Measure) -> intervals.Interval | None:
    """An interval sure to hold the value of `m` (None: unknown)."""
    if m.exact is None:
        return m.bounds
    value = _float(m)
    return intervals.widened(value, value)


def _root(value: int, order: int) -> int | None:
    """The exact integer `order`-th root of a non-negative integer, if there is one."""
    if value >= 1 << 1000:  # beyond floats; never asked: roots take at most 100 digits
        return None
    guess = round(value ** (1 / order))
    return next((c for c in (guess - 1, guess, guess + 1) if c >= 0 and c**order == value), None)


def _exact_power(base: Fraction, exponent: Fraction) -> Fraction | None:
    """base^(p/q) when it is rational (a perfect q-th power), else None."""
    num, den = (
        _root(base.numerator, exponent.denominator),
        _root(base.denominator, exponent.denominator),
    )
    if num is None or den is None:
        return None
    return Fraction(num, den) ** exponent.numerator


def _multisets(terms: int, power: int) -> int:
    """Terms of a sum of `terms` terms raised to `power`, at most, once expanded (or just
    over `MAX_TERMS`, without computing them, when they are more)."""
    if terms <= 1 or power == 0:
        return 1
    log = math.lgamma(power + terms) - math.lgamma(power + 1) - math.lgamma(terms)
    if log > math.log(MAX_TERMS) + 1:
        return MAX_TERMS + 1
    return math.comb(power + terms - 1, terms - 1)


def check(m: Measure, where: Position) -> Measure:
    """`m`, or `Problem` if it is beyond a limit."""
    if m.depth > MAX_DEPTH:
        raise Problem("syntax", f"expression nested more than {MAX_DEPTH} deep (a limit)", where)
    if m.size > MAX_SIZE:
        message = f"expression of more than {MAX_SIZE} numbers, names and operators (a limit)"
        raise Problem("syntax", message, where)
    if max(m.degree) > MAX_DEGREE:
        message = f"out of range: degree above {MAX_DEGREE} in the parameters and constants"
        raise Problem("syntax", message, where)
    if max(m.terms) > MAX_TERMS:
        message = f"expression out of range: more than {MAX_TERMS} terms once expanded"
        raise Problem("syntax", message, where)
    if max(m.digits) > MAX_DIGITS:
        raise Problem("syntax", "number out of range", where)
    if m.approx is not None and not abs(m.approx) <= MAX_MAGNITUDE and not math.isnan(m.approx):
        raise Problem("syntax", f"value out of range (beyond {MAX_MAGNITUDE:g} in size)", where)
    return m


def arithmetic(
    operator: str, a: Measure, b: Measure, where: Position, chained: bool = False
) -> Measure:
    """a operator b, for + - * / (the divisor is not 0); `chained`: `a` is a chain of the
    same operators, which b extends (a chain is one node, not a nesting)."""
    if a.exact is not None and b.exact is not None:
        x, y = a.exact, b.exact
        value = (
            x + y
            if operator == "+"
            else x - y
            if operator == "-"
            else x * y
            if operator == "*"
            else x / y
        )
        return rational(value, where)
    (an, ad), (bn, bd) = a.degree, b.degree
    (tan, tad), (tbn, tbd) = a.terms, b.terms
    (dan, dad), (dbn, dbd) = a.digits, b.digits
    if operator in "+-":  # (an bd + bn ad) / (ad bd)
        degree = (max(an + bd, bn + ad), ad + bd)
        terms = (tan * tbd + tbn * tad, tad * tbd)
        digits = (max(dan + dbd, dbn + dad) + math.log10(2), dad + dbd)
    elif operator == "*":
        degree = (an + bn, ad + bd)
        terms = (tan * tbn, tad * tbd)
        digits = (dan + dbn + math.log10(min(tan, tbn)), dad + dbd + math.log10(min(tad, tbd)))
    else:  # (an bd) / (ad bn)
        degree = (an + bd, ad + bn)
        terms = (tan * tbd, tad * tbn)
        digits = (dan + dbd + math.log10(min(tan, tbd)), dad + dbn + math.log10(min(tad, tbn)))
    approx, x, y = None, _float(a), _float(b)
    if x is not None and y is not None and (operator != "/" or y != 0):
        approx = {"+": x + y, "-": x - y, "*": x * y}[operator] if operator != "/" else x / y
    bounds = intervals.combined(operator, _interval(a), _interval(b))
    depth = max(a.depth if chained else a.depth + 1, b.depth + 1)
    measure = Measure(None, approx, bounds, degree, terms, digits, depth, a.size + b.size + 1)
    return check(measure, where)


def negative(a: Measure, where: Position) -> Measure:
    if a.exact is not None:
        return rational(-a.exact, where)
    approx = None if a.approx is None else -a.approx
    bounds = None if a.bounds is None else (-a.bounds[1], -a.bounds[0])
    return check(
        replace(a, approx=approx, bounds=bounds, depth=a.depth + 1, size=a.size + 1), where
    )


def _rational_power(b: Fraction, x: Fraction, where: Position) -> Fraction | None:
    """b^x for rational b and x: its rational value, or None for an irrational root;
    `Problem` when it is out of range, undefined or not real."""
    out_of_range = Problem("syntax", "power out of range", where)
    if b == 0 and x < 0:
        raise Infinite("power out of range: 0 to a negative power", where)
    if b < 0 and x.denominator != 1:
        raise _not_real_power(f"({b})^({x})", where)
    if b in (0, 1, -1):
        return b ** int(x) if x.denominator == 1 else b
    if abs(x) > MAX_DIGITS / _digits(b):  # b is not 0, 1 or -1: it has digits
        raise out_of_range
    if x.denominator == 1:
        return b ** int(x)
    if _digits(b) > MAX_ROOT_DIGITS or x.denominator > MAX_DEGREE:
        raise out_of_range
    return _exact_power(b, x)


def _not_real_power(written: str, where: Position) -> Problem:
    message = f"{written} is not a real number (a negative number to a fractional power)"
    return Problem("bad_value", message, where)


def power(base: Measure, exponent: Measure, where: Position) -> Measure:
    """base^exponent (`where`: the operator)."""
    b, n = base.exact, exponent.exact
    if b is not None and n is not None:
        value = _rational_power(b, n, where)
        if value is not None:
            return rational(value, where)
    depth, size = max(base.depth, exponent.depth) + 1, base.size + exponent.size + 1
    approx, x, y = None, _float(base), _float(exponent)
    integral = n is not None and n.denominator == 1
    if n is not None and not integral and intervals.negative(_interval(base)):
        raise _not_real_power(f"(about {x:.6g})^({n})", where)
    exact_power = integral and abs(n) < 1 << 30  # an integer power: exactly that exponent
    exponent_bounds = (float(n), float(n)) if exact_power else _interval(exponent)
    bounds = intervals.power(_interval(base), exponent_bounds)
    if x is not None and y is not None and (x > 0 or (integral and x != 0)):
        try:
            approx = x ** (int(n) if integral and abs(n) < 1 << 30 else y)
        except OverflowError:
            approx = math.inf
    if integral and abs(n) <= MAX_DIGITS:
        k = abs(int(n))
        (bn, bd), (tn, td), (dn, dd) = base.degree, base.terms, base.digits
        if n < 0:
            bn, bd, tn, td, dn, dd = bd, bn, td, tn, dd, dn
        measure = Measure(
            approx=approx,
            bounds=bounds,
            degree=(k * bn, k * bd),
            terms=(_multisets(tn, k), _multisets(td, k)),
            digits=(k * (dn + math.log10(tn)), k * (dd + math.log10(td))),
            depth=depth,
            size=size,
        )
        return check(measure, where)
    if n is not None and abs(n) > MAX_DIGITS:  # a huge power of anything but 0, 1 and -1
        degree = MAX_DEGREE + 1
    elif n is not None:  # a root: a new atom, of the degree of its integer part at most
        degree = math.ceil(abs(n)) * max(sum(base.degree), 1)
    else:
        degree = 1
    measure = Measure(approx=approx, bounds=bounds, degree=(degree, 0), depth=depth, size=size)
    return check(measure, where)


def _function_value(function: str, value: Fraction, where: Position) -> Fraction | None:
    """The rational value of a function of a rational number, when there is one;
    `Problem` for an argument out of range or outside the function's domain."""
    if function == "abs":
        return abs(value)
    if function == "sign":
        return Fraction((value > 0) - (value < 0))
    if _digits(value) > MAX_ROOT_DIGITS:
        raise Problem("syntax", f"argument of {function} out of range", where)
    if function == "sqrt":
        if value < 0:
            message = f"sqrt({value}) is not a real number (a negative argument)"
            raise Problem("bad_value", message, where)
        return _exact_power(value, Fraction(1, 2))
    if function == "log":
        if value == 0:
            raise Infinite("the value is undefined or infinite (log(0))", where)
        if value < 0:
            message = f"log({value}) is not a real number (a negative argument)"
            raise Problem("bad_value", message, where)
        return Fraction(0) if value == 1 else None
    if value == 0:
        return Fraction(1) if function in ("exp", "cos") else Fraction(0)
    return None


_APPROX = {
    "abs": abs,
    "sign": lambda x: float((x > 0) - (x < 0)),
    "sat": lambda x: x / math.sqrt(1 + x * x) if abs(x) < 1e150 else math.copysign(1.0, x),
}


def call(function: str, arguments: list[Measure], where: Position) -> Measure:
    """function(arguments), for the language's functions (`where`: the function's name)."""
    if function in ("min", "max"):
        return _extremum(function, arguments, where)
    (argument,) = arguments
    if argument.exact is not None:
        value = _function_value(function, argument.exact, where)
        if value is not None:
            return rational(value, where)
    x, approx = _float(argument), None
    if function == "exp" and x is not None and abs(x) > MAX_EXP_ARGUMENT:
        message = f"argument of exp out of range (at most {MAX_EXP_ARGUMENT} in size)"
        raise Problem("syntax", message, where)
    n = argument.exact
    if function == "exp" and n is not None and n.denominator == 1 and abs(n) > MAX_DEGREE:
        # e is a variable of the derivation: exp(n) is e^n, of degree n in it
        message = f"exp({n}) is out of range: a power of e above {MAX_DEGREE} (write its value)"
        raise Problem("syntax", message, where)
    bounds = _interval(argument)
    if function in ("sqrt", "log") and intervals.negative(bounds):  # (not in complex numbers)
        about = f"about {(bounds[0] + bounds[1]) / 2:.6g}"
        message = f"{function} of a negative number ({about}) is not a real number"
        raise Problem("bad_value", message, where)
    # an argument's sign not decided by its bounds is decided exactly, later
    if x is not None and (x > 0 or function not in ("sqrt", "log")) and math.isfinite(x):
        try:
            approx = _APPROX.get(function, getattr(math, function, None))(x)
        except (OverflowError, ValueError):  # tan near a pole, say: no estimate
            approx = None
    depth, size = argument.depth + 1, argument.size + 1
    bounds = intervals.function(function, bounds)
    measure = Measure(approx=approx, bounds=bounds, degree=(1, 0), depth=depth, size=size)
    return check(measure, where)


def _extremum(function: str, arguments: list[Measure], where: Position) -> Measure:
    """min or max of two or more values: exact when all are rational numbers."""
    exact = [m.exact for m in arguments]
    if all(x is not None for x in exact):
        return rational(min(exact) if function == "min" else max(exact), where)
    values = [_float(m) for m in arguments]
    approx = None
    if all(x is not None for x in values):
        approx = min(values) if function == "min" else max(values)
    depth = max(m.depth for m in arguments) + 1
    size = sum(m.size for m in arguments) + 1
    return check(Measure(approx=approx, degree=(1, 0), depth=depth, size=size), where)
