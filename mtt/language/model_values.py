"""The limits of mtt.language.measures over a whole model: every parameter's value with
the values of the parameters it names put in, and every component's argument, measured
before sympy sees any of them (`check_values`)."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import replace
from graphlib import TopologicalSorter

from mtt.language import measures
from mtt.language.diagnostics import Diagnostic, error
from mtt.language.expressions import (
    ATOM,
    Call,
    Constant,
    Expression,
    Measure,
    Name,
    Negative,
    Node,
    Number,
    Power,
    Product,
    Sum,
)


def _measure(node: Node, names: Callable[[str], Measure]) -> Measure:
    """A tree's measure with each name measured by `names` (its value's measure, or ATOM
    for a name that stays symbolic). Sums, products and minus signs do not nest here:
    sympy flattens them when values are substituted; functions and powers do."""
    if isinstance(node, Number):
        return measures.rational(node.value, node.position)
    if isinstance(node, Name):
        return replace(names(node.name), size=1)
    if isinstance(node, Constant):
        return measures.PI
    if isinstance(node, Call):
        arguments = [_measure(a, names) for a in node.arguments]
        return measures.call(node.function, arguments, node.position)
    if isinstance(node, Power):
        base, exponent = _measure(node.base, names), _measure(node.exponent, names)
        return measures.power(base, exponent, node.position)
    if isinstance(node, Negative):
        m = measures.negative(_measure(node.operand, names), node.position)
        return replace(m, depth=max(m.depth - 1, 1))
    if isinstance(node, Sum | Product):
        operators = ("+", "-") if isinstance(node, Sum) else ("*", "/")
        (_, first), *rest = node.parts
        m = _measure(first, names)
        for inverse, part in rest:
            other = _measure(part, names)
            if operators[1] == "/" and other.exact == 0:
                raise measures.Infinite("division by zero", part.position)
            m = measures.arithmetic(operators[inverse], m, other, node.position, chained=True)
        return m
    return ATOM  # a signal, or a placeholder


def check_values(
    values: dict[str, Expression | Measure | None],
    symbolic: Iterable[str],
    arguments: Iterable[Expression],
) -> list[Diagnostic]:
    """The problems of the model's expressions once the parameters' values are put in:
    each parameter's value (`values`: its expression, or a measure for a value given
    otherwise, or None for none), then each component's argument, with the `symbolic`
    parameters (and those without a value) kept as names. Each problem is reported once,
    at the place in the expression where it appears."""
    problems: dict[tuple, Diagnostic] = {}
    measured: dict[str, Measure] = {}
    symbolic = set(symbolic)

    def of(name: str) -> Measure:
        return measured.get(name, ATOM)

    def measure(expression: Expression) -> Measure:
        try:
            return _measure(expression.tree, of)
        except measures.Infinite:  # reported by the derivation, as an infinite parameter
            return ATOM
        except measures.Problem as problem:
            found = error(problem.kind, str(problem), problem.position)
            problems.setdefault((problem.position, str(problem)), found)
            return ATOM

    order = TopologicalSorter(
        {
            name: {u.name for u in value.names} if isinstance(value, Expression) else set()
            for name, value in values.items()
        }
    ).static_order()
    for name in order:
        value = values.get(name)
        if isinstance(value, Measure):
            measured[name] = value
        elif value is not None:
            full = measure(value)
            if name not in symbolic:
                measured[name] = full
    for argument in arguments:
        measure(argument)
    return list(problems.values())
