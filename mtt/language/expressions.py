"""Expressions of the .bg language: from parse tree to exact sympy values, node by node.

The grammar's expression rules are transformed bottom-up here: numbers become exact
Rationals, names become Symbols, operators become sympy operations, and no text from a
model ever reaches eval, exec, sympify or parse_expr. Limits keep untrusted input from
asking for astronomically large numbers.

Signal terms `e(X)` and `f(X)` (the argument of a modulated source) become the Symbols
`e(X)` and `f(X)`, which no parameter can be called; each partial expression also records
whether it is still a linear combination of signals, and where it first stops being one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction

import sympy
from lark import Token, Transformer

from mtt.language.diagnostics import Diagnostic, Position, error

FUNCTIONS = {
    "sqrt": sympy.sqrt,
    "exp": sympy.exp,
    "log": sympy.log,
    "sin": sympy.sin,
    "cos": sympy.cos,
}
CONSTANTS = {"pi": sympy.pi}
SIGNALS = {"e": "effort", "f": "flow"}
LAPLACE = "s"
RESERVED = frozenset({LAPLACE, *FUNCTIONS, *CONSTANTS})

# Exact arithmetic on untrusted input must not be asked to build astronomically
# large numbers (`1e999999999`, `10^10^10`): these bounds keep every literal and
# every numeric result to at most this many decimal digits. It stays below the
# 4300 digits CPython converts between int and str by default (sys.int_info), so
# every accepted value can still be printed.
MAX_DIGITS = 4000
# Roots and transcendental functions of a number make sympy look for perfect powers
# and factors: quick for numbers of everyday size, minutes for thousands of digits.
MAX_ROOT_DIGITS = 100


@dataclass(frozen=True)
class NameUse:
    name: str
    position: Position


@dataclass(frozen=True)
class SignalUse:
    """`e(X)` or `f(X)`: the effort or flow of the component X (dotted for a subsystem's)."""

    kind: str  # "e" or "f"
    target: str
    position: Position

    @property
    def text(self) -> str:
        return f"{self.kind}({self.target})"

    @property
    def symbol(self) -> sympy.Symbol:
        return sympy.Symbol(self.text)


@dataclass(frozen=True)
class SignalProblem:
    """Where an expression stops being a linear combination of signals, and why."""

    message: str
    position: Position


@dataclass(frozen=True)
class Expression:
    """A parsed expression: its exact sympy value and every name it uses, with places.

    `signals` are its signal terms and `signal_problem` the first place where it is not a
    linear combination of them (None when it is one, or has no signal at all).
    """

    value: sympy.Expr
    names: tuple[NameUse, ...]
    position: Position
    signals: tuple[SignalUse, ...] = ()
    signal_problem: SignalProblem | None = None


def _number(text: str) -> sympy.Rational:
    mantissa, _, exponent = text.lower().partition("e")
    if len(mantissa) > MAX_DIGITS:
        raise _ExpressionProblem("number has too many digits")
    sign = -1 if exponent.startswith("-") else 1
    exponent = exponent.lstrip("+-").lstrip("0") or "0"
    if len(exponent) > len(str(MAX_DIGITS)):
        raise _ExpressionProblem("number out of range")
    value = Fraction(mantissa) * Fraction(10) ** (sign * int(exponent))
    return sympy.Rational(value.numerator, value.denominator)


def _digits(value: sympy.Expr) -> float:
    """The decimal digits of the largest numerator or denominator among value's numbers."""
    return max(
        (math.log10(max(abs(r.p), abs(r.q), 1)) for r in value.atoms(sympy.Rational)), default=0
    )


class _ExpressionProblem(Exception):
    """Raised inside the transformer; becomes a positioned `syntax` diagnostic."""


def _at(token: Token) -> Position:
    return Position(token.line, token.column)


def _first_problem(*parts: Expression) -> SignalProblem | None:
    return next((p.signal_problem for p in parts if p.signal_problem), None)


def _nonlinear(message: str, *parts: Expression) -> SignalProblem | None:
    """Where `parts` take no signal at all (a function's argument, a power, a denominator):
    the problem is their first signal, or else any problem inside them."""
    signals = [s for p in parts for s in p.signals]
    return SignalProblem(message, signals[0].position) if signals else _first_problem(*parts)


def _sum_problem(a: Expression, b: Expression) -> SignalProblem | None:
    """A sum stays linear unless it adds a (nonzero) constant term to signal terms."""
    first = _first_problem(a, b)
    if first is not None or bool(a.signals) == bool(b.signals):
        return first
    constant = b if a.signals else a
    if constant.value == 0:
        return None
    return SignalProblem(
        "a constant term: every term must be a coefficient times one signal",
        constant.position,
    )


def _product_problem(a: Expression, b: Expression) -> SignalProblem | None:
    """A product stays linear when at most one factor holds signals."""
    first = _first_problem(a, b)
    if first is None and a.signals and b.signals:
        return SignalProblem("a product of signals", b.signals[0].position)
    return first


def _binary(op, signal_problem):
    def build(self, children: list[Expression]) -> Expression:
        a, b = children
        return self._result(
            op(a.value, b.value),
            a.names + b.names,
            a.position,
            a.signals + b.signals,
            signal_problem(a, b),
        )

    return build


class ExpressionRules(Transformer):
    """The expression rules of the grammar; `problems` collects positioned syntax errors."""

    def __init__(self, problems: list[Diagnostic]):
        super().__init__()
        self.problems = problems

    def _result(self, value, names, position: Position, signals=(), problem=None) -> Expression:
        """A computed value, unless it is undefined or too large: that is reported, and a
        placeholder symbol stands in for it so that no second error follows from it."""
        trouble = None
        if value.has(sympy.nan, sympy.zoo, sympy.oo, -sympy.oo):
            trouble = "the value is undefined or infinite"
        elif _digits(value) > MAX_DIGITS:
            trouble = "number out of range"
        if trouble:
            self.problems.append(error("syntax", trouble, position))
            return Expression(sympy.Dummy(), names, position, signals, problem)
        return Expression(value, names, position, signals, problem)

    def number(self, children):
        (token,) = children
        try:
            value = _number(str(token))
        except _ExpressionProblem as problem:
            self.problems.append(error("syntax", str(problem), _at(token)))
            return Expression(sympy.Integer(0), (), _at(token))
        return self._result(value, (), _at(token))

    def name(self, children):
        (token,) = children
        if str(token) in CONSTANTS:
            return Expression(CONSTANTS[str(token)], (), _at(token))
        use = NameUse(str(token), _at(token))
        return Expression(sympy.Symbol(str(token)), (use,), _at(token))

    def _signal(self, token: Token, target: str | None, where: Position) -> Expression:
        if target is None:
            problem = SignalProblem(
                f"{token}(...) reads a signal: its argument is a component's name", where
            )
            return Expression(sympy.Dummy(), (), _at(token), (), problem)
        use = SignalUse(str(token), target, _at(token))
        return Expression(use.symbol, (), _at(token), (use,))

    def call(self, children):
        token, argument = children
        if str(token) in SIGNALS:
            bare = (
                len(argument.names) == 1
                and not argument.signals
                and argument.value == sympy.Symbol(argument.names[0].name)
            )
            return self._signal(token, argument.names[0].name if bare else None, argument.position)
        function = FUNCTIONS.get(str(token))
        if function is None:
            known = " ".join(FUNCTIONS)
            self.problems.append(
                error("syntax", f"unknown function {str(token)!r} (known: {known})", _at(token))
            )
            return argument
        if _digits(argument.value) > MAX_ROOT_DIGITS:
            self.problems.append(error("syntax", f"argument of {token} out of range", _at(token)))
            return argument
        problem = _nonlinear("a signal inside a function", argument)
        return self._result(
            function(argument.value), argument.names, _at(token), argument.signals, problem
        )

    def signal_path(self, children):
        """`e(a.b)`: a signal of a subsystem's component; other calls take no dotted name."""
        token, path = children
        if str(token) in SIGNALS:
            return self._signal(token, str(path), _at(path))
        self.problems.append(
            error(
                "syntax",
                f"{path}: a dotted name only names a signal, in e(...) or f(...)",
                _at(path),
            )  # fmt: skip
        )
        return Expression(sympy.Integer(0), (), _at(token))

    add = _binary(lambda a, b: a + b, _sum_problem)
    sub = _binary(lambda a, b: a - b, _sum_problem)
    mul = _binary(lambda a, b: a * b, _product_problem)

    def div(self, children):
        a, b = children
        if b.value == 0:
            self.problems.append(error("syntax", "division by zero", b.position))
            return a
        problem = _first_problem(a) or _nonlinear("a signal in a denominator", b)
        return self._result(
            a.value / b.value, a.names + b.names, a.position, a.signals + b.signals, problem
        )

    def neg(self, children):
        (a,) = children
        return Expression(-a.value, a.names, a.position, a.signals, a.signal_problem)

    def pow(self, children):
        base, operator, exponent = children
        b, x = base.value, exponent.value
        if isinstance(x, sympy.Number):
            size = _digits(b) if isinstance(b, sympy.Number) else max(_digits(b), 1)
            too_big = abs(x) * size > MAX_DIGITS or (b == 0 and x < 0)
            too_big |= not x.is_Integer and _digits(b) > MAX_ROOT_DIGITS
        else:
            too_big = False
        if too_big:
            self.problems.append(error("syntax", "power out of range", _at(operator)))
            return base
        return self._result(
            b**x,
            base.names + exponent.names,
            base.position,
            base.signals + exponent.signals,
            _nonlinear("a signal in a power", base, exponent),
        )

    def expression(self, children):
        (partial,) = children
        return partial
