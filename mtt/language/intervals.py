"""Intervals sure to hold a constant's value, for deciding its sign before any algebra.

The measures of mtt.language.measures carry a float value of each irrational constant; an
interval around it decides whether the argument of a root or a logarithm is negative (a
`bad_value` at once) without trusting the float: floating-point results are widened by a
few units in the last place (IEEE arithmetic and sqrt round correctly; the C library's
exp, log, sin, cos and pow are within an ulp). None stands for "not known": an interval
that holds zero, or a value beyond floats, decides nothing and is left to exact algebra.
"""

from __future__ import annotations

import math

Interval = tuple[float, float]
SLACK = 4  # ulps added on each side of every result


def widened(low: float, high: float) -> Interval | None:
    if math.isnan(low) or math.isnan(high):
        return None
    for _ in range(SLACK):
        low, high = math.nextafter(low, -math.inf), math.nextafter(high, math.inf)
    return low, high


def hull(values: list[float]) -> Interval | None:
    return None if any(math.isnan(v) for v in values) else widened(min(values), max(values))


def combined(operator: str, a: Interval | None, b: Interval | None) -> Interval | None:
    """An interval holding x operator y for any x in a and y in b (+ - * /)."""
    if a is None or b is None:
        return None
    if operator == "+":
        return widened(a[0] + b[0], a[1] + b[1])
    if operator == "-":
        return widened(a[0] - b[1], a[1] - b[0])
    if operator == "/":
        if b[0] <= 0 <= b[1]:
            return None
        b = widened(1 / b[1], 1 / b[0])
        if b is None:
            return None
    return hull([x * y for x in a for y in b])


def power(base: Interval | None, exponent: Interval | None) -> Interval | None:
    """x^y for x in base, y in exponent: an integer power of any base (an exponent given
    as an exact pair), or any power of a positive base."""
    if base is None or exponent is None:
        return None
    try:
        if exponent[0] == exponent[1] == int(exponent[0]):
            n = int(exponent[0])
            ends = [base[0] ** n, base[1] ** n]
            if base[0] < 0 < base[1]:
                if n < 0:
                    return None
                ends.append(0.0)
            return hull(ends)
        if base[0] > 0:
            return hull([x**y for x in base for y in exponent])
    except (OverflowError, ZeroDivisionError):
        return None
    return None


def _sat(x: float) -> float:
    return x / math.sqrt(1 + x * x) if abs(x) < 1e150 else math.copysign(1.0, x)


def function(name: str, a: Interval | None) -> Interval | None:
    """name(x) for x in a: the increasing functions (sqrt and log of a positive interval,
    exp, tanh, atan, sat), sign, sin and cos, abs; None for the others (tan)."""
    if a is None:
        return None
    try:
        if name in ("sqrt", "log", "exp", "tanh", "atan", "sat"):
            if name in ("sqrt", "log") and a[0] <= 0:
                return None
            f = _sat if name == "sat" else getattr(math, name)
            return widened(f(a[0]), f(a[1]))
        if name == "sign":  # exact: -1, 0 or 1 at each end
            return tuple(float((x > 0) - (x < 0)) for x in a)
        if name == "abs":
            ends = (abs(a[0]), abs(a[1]))
            return (0.0 if a[0] <= 0 <= a[1] else min(ends)), max(ends)
        if name not in ("sin", "cos"):
            return None
        centre, radius = (a[0] + a[1]) / 2, (a[1] - a[0]) / 2
        if not radius < 1:  # |sin'|, |cos'| <= 1
            return (-1.0, 1.0)
        value = getattr(math, name)(centre)
        low, high = widened(value - radius, value + radius)
        return max(low, -1.0), min(high, 1.0)
    except (OverflowError, ValueError):
        return None


def negative(a: Interval | None) -> bool:
    """Whether every value in `a` is below zero."""
    return a is not None and a[1] < 0
