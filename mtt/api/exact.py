"""Exact numbers in, floats out: the values a user gives parameters, read exactly, and the
derivation's exact coefficients as floats (an error, not inf or a complex, when they are
not)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from fractions import Fraction
from types import MappingProxyType

import numpy as np
import sympy

from mtt.language.diagnostics import MttError


def exact(name: str, value: object) -> sympy.Expr:
    """A parameter value as an exact number: a float is read as the decimal it prints as
    (0.1 is 1/10, as if written in a model file); a str is an expression of numbers."""
    if isinstance(value, bool):
        raise MttError(f"{name} = {value!r}: expected a number", kind="bad_value")
    if isinstance(value, str):
        from mtt.language.parse import parse_expression

        return parse_expression(value, variables=frozenset())
    if isinstance(value, float | np.floating):
        if not math.isfinite(value):
            raise MttError(f"{name} = {value}: every value must be finite", kind="bad_value")
        return sympy.Rational(repr(float(value)))
    if isinstance(value, int | np.integer | Fraction):
        return sympy.Rational(value)
    if isinstance(value, sympy.Expr) and value.is_number and value.is_finite:
        return value
    raise MttError(f"{name} = {value!r}: expected a number", kind="bad_value")


def numeric(expr: sympy.Expr, what: str) -> float:
    try:
        number = float(expr)
    except OverflowError:
        raise MttError(f"{what} is too large for a float: {expr}", kind="out_of_range") from None
    except TypeError:  # complex, or a symbol left
        raise MttError(f"{what} is not a real number: {expr}", kind="bad_value") from None
    if not math.isfinite(number):
        raise MttError(f"{what} is too large for a float", kind="out_of_range")
    return number


def exact_point(at: Mapping[str, object] | None) -> MappingProxyType | None:
    """An operating point ({"u": 3.2}, states by name, or "x": [v1, v2]) read exactly."""
    if at is None:
        return None
    if not isinstance(at, Mapping):
        raise MttError(f"at takes a dict {{name: value}}, not {at!r}", kind="bad_value")
    return MappingProxyType(
        {
            name: tuple(exact(name, v) for v in value)
            if name == "x" and isinstance(value, list | tuple)
            else exact(name, value)
            for name, value in at.items()
        }
    )
