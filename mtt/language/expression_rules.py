"""The grammar's expression rules: parse tree -> `Expression` trees, within the limits.

Each node is measured as it is built (`measures`: rational numbers folded exactly, bounds
on everything else), so that the limits of the implementation are reported at their
place before sympy ever sees an expression. Lark's tree is transformed without recursion
(`Transformer_NonRecursive`): a line of thousands of minus signs is a located error, not
a crash.
"""

from __future__ import annotations

from collections.abc import Callable

from lark import Token, Transformer_NonRecursive

from mtt.language import measures
from mtt.language.diagnostics import Diagnostic, Position, error
from mtt.language.expressions import (
    CONSTANTS,
    FUNCTIONS,
    SIGNALS,
    Call,
    Constant,
    Expression,
    Measure,
    Name,
    NameUse,
    Negative,
    Number,
    Placeholder,
    Power,
    Product,
    Signal,
    SignalProblem,
    SignalUse,
    Sum,
)
from mtt.language.measures import MAX_DIGITS, Problem

__all__ = ["MAX_DIGITS", "ExpressionRules"]


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
    if constant.exact == 0:
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


class ExpressionRules(Transformer_NonRecursive):
    """The expression rules of the grammar; `problems` collects positioned errors.

    `line` is the line the text being transformed starts on (the parser reads one line
    at a time).
    """

    def __init__(self, problems: list[Diagnostic], line: int = 1):
        super().__init__()
        self.problems = problems
        self.first_line = line

    def at(self, token: Token) -> Position:
        return Position(token.line + self.first_line - 1, token.column)

    @staticmethod
    def _placeholder(position: Position, *parts: Expression) -> Expression:
        """Stands for an expression where a problem was found: no second error follows."""
        names = tuple(u for p in parts for u in p.names)
        signals = tuple(u for p in parts for u in p.signals)
        return Expression(Placeholder(position), names, position, signals, _first_problem(*parts))

    def _build(self, make, node: Callable[[Measure], object], position, parts, problem):
        """The expression whose measure `make()` gives and whose tree `node(measure)`
        builds (a number when the measure is an exact rational); a placeholder, with the
        problem reported, when `make` meets one."""
        if any(isinstance(p.tree, Placeholder) for p in parts):
            return self._placeholder(position, *parts)
        try:
            measure = make()
        except Problem as found:
            self.problems.append(error(found.kind, str(found), found.position))
            return self._placeholder(position, *parts)
        names = tuple(u for p in parts for u in p.names)
        signals = tuple(u for p in parts for u in p.signals)
        if measure.exact is not None:
            tree, names = Number(position, measure.exact), ()
        else:
            tree = node(measure)
        return Expression(tree, names, position, signals, problem, measure)

    # leaves

    def number(self, children):
        (token,) = children
        where = self.at(token)
        try:
            value = measures.number(str(token))
        except ValueError as problem:
            self.problems.append(error("syntax", str(problem), where))
            return self._placeholder(where)
        return self._build(lambda: measures.rational(value, where), None, where, [], None)

    def name(self, children):
        (token,) = children
        where = self.at(token)
        if str(token) in CONSTANTS:
            return Expression(Constant(where, str(token)), (), where, measure=measures.PI)
        return Expression(Name(where, str(token)), (NameUse(str(token), where),), where)

    def _signal(self, token: Token, target: str | None, where: Position) -> Expression:
        if target is None:
            problem = SignalProblem(
                f"{token}(...) reads a signal: its argument is a component's name", where, True
            )
            return Expression(Placeholder(self.at(token)), (), self.at(token), (), problem)
        use = SignalUse(str(token), target, self.at(token))
        return Expression(Signal(use.position, use.kind, target), (), use.position, (use,))

    # functions

    def call(self, children):
        token, *arguments = children
        where, function = self.at(token), str(token)
        if function in SIGNALS and len(arguments) == 1:
            (argument,) = arguments
            bare = isinstance(argument.tree, Name) and not argument.signals
            return self._signal(token, argument.tree.name if bare else None, argument.position)
        if function not in FUNCTIONS:
            known = " ".join(FUNCTIONS)
            self.problems.append(
                error("syntax", f"unknown function {function!r} (known: {known})", where)
            )
            return self._placeholder(where, *arguments)
        wanted = FUNCTIONS[function]
        if (wanted or 2) > len(arguments) or (wanted and len(arguments) > wanted):
            count = "one argument" if wanted == 1 else "two or more arguments"
            self.problems.append(error("syntax", f"{function} takes {count}", where))
            return self._placeholder(where, *arguments)
        return self._build(
            lambda: measures.call(function, [a.measure for a in arguments], where),
            lambda _: Call(where, function, tuple(a.tree for a in arguments)),
            where,
            arguments,
            _nonlinear("a signal inside a function", *arguments),
        )

    def signal_path(self, children):
        """`e(a.b)`: a signal of a subsystem's component; other calls take no dotted name."""
        token, path = children
        if str(token) in SIGNALS:
            return self._signal(token, str(path), self.at(path))
        message = f"{path}: a dotted name only names a signal, in e(...) or f(...)"
        self.problems.append(error("syntax", message, self.at(path)))
        return self._placeholder(self.at(path))

    # operators

    def _arithmetic(self, operator: str, a: Expression, b: Expression, problem) -> Expression:
        kind = Sum if operator in "+-" else Product
        chained = isinstance(a.tree, kind)
        first = a.tree.parts if chained else ((False, a.tree),)
        return self._build(
            lambda: measures.arithmetic(operator, a.measure, b.measure, a.position, chained),
            lambda _: kind(a.position, (*first, (operator in "-/", b.tree))),
            a.position,
            [a, b],
            problem,
        )

    def add(self, children):
        a, b = children
        return self._arithmetic("+", a, b, _sum_problem(a, b))

    def sub(self, children):
        a, b = children
        return self._arithmetic("-", a, b, _sum_problem(a, b))

    def mul(self, children):
        a, b = children
        return self._arithmetic("*", a, b, _product_problem(a, b))

    def div(self, children):
        a, b = children
        if b.exact == 0:
            self.problems.append(error("syntax", "division by zero", b.position))
            return self._placeholder(a.position, a, b)
        problem = _first_problem(a) or _nonlinear("a signal in a denominator", b)
        return self._arithmetic("/", a, b, problem)

    def neg(self, children):
        (a,) = children
        return self._build(
            lambda: measures.negative(a.measure, a.position),
            lambda _: Negative(a.position, a.tree),
            a.position,
            [a],
            a.signal_problem,
        )

    def pow(self, children):
        base, operator, exponent = children
        return self._build(
            lambda: measures.power(base.measure, exponent.measure, self.at(operator)),
            lambda _: Power(base.position, base.tree, exponent.tree),
            base.position,
            [base, exponent],
            _nonlinear("a signal in a power", base, exponent),
        )

    def expression(self, children):
        (partial,) = children
        return partial
