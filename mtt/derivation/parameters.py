"""Which parameters stay symbolic and what the others are worth, exactly.

The equations are written in the unknowns and the kept symbols only: every other
parameter is replaced by its value from the file (or from --set), resolved through
the parameters it names.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction
from functools import cache
from types import MappingProxyType

import sympy

from mtt.derivation.budget import DEFAULT_BUDGET, Budget
from mtt.language.bondgraph import BondGraph, Selection, values_problems
from mtt.language.diagnostics import Diagnostic, ModelError, error
from mtt.language.expressions import ATOM, Measure
from mtt.language.measures import Problem, rational


@dataclass(frozen=True)
class ParameterChoice:
    """What the user chooses over the file: the unknowns (in order), the input and output,
    which parameters stay symbolic, which values are overridden, and how large the
    derivation may let its polynomials grow (`budget`).

    By default every parameter with a value in the file is substituted exactly and
    the others stay symbolic; the unknowns always stay symbolic.
    """

    unknowns: tuple[str, ...] | None = None  # None: the model's `unknown` declarations
    keep: frozenset[str] = frozenset()
    symbolic: bool = False
    overrides: MappingProxyType = field(default_factory=lambda: MappingProxyType({}))
    input: str | None = None  # TYPE:NAME, over the file's `input` statement
    output: str | None = None
    budget: Budget = DEFAULT_BUDGET
    # a nonlinear model's operating point: values of u and of states by name (exact), and
    # which steady state when there are several (1-based); None: the model as it is
    at: MappingProxyType | None = None
    branch: int | None = None
    include: tuple[str, ...] = ()  # directories subsystem files may also come from

    @property
    def selection(self) -> Selection:
        """The part of the choice that building the bond graph needs."""
        return Selection(self.unknowns, self.input, self.output, self.include)


@dataclass(frozen=True)
class Parametrisation:
    unknowns: tuple[str, ...]  # in the order chosen
    symbols: tuple[str, ...]  # kept symbolic, in model order (the unknowns not included)
    assumed: MappingProxyType  # name -> exact value substituted
    defaults: MappingProxyType  # kept symbol -> its numeric value from the file, or None
    true_values: MappingProxyType  # unknown -> its value from the file or --set, or None
    substitution: MappingProxyType  # Symbol -> value, for every assumed parameter

    def apply(self, expression: sympy.Expr) -> sympy.Expr:
        return expression.xreplace(self.substitution)  # a copy would cost every call

    @property
    def free(self) -> tuple[str, ...]:
        """The names the equations are written in: the unknowns first, then the symbols."""
        return self.unknowns + self.symbols


def _measure(name: str, value: sympy.Expr) -> Measure | Diagnostic:
    """What the limits know of a value given on the command line (a number), or why it is
    refused."""
    try:
        if value.is_Rational:
            return rational(Fraction(int(value.p), int(value.q)), None)
        approx = float(value)
    except Problem as problem:
        return error(problem.kind, f"--set {name}: {problem}")
    except (TypeError, OverflowError):  # not real, or beyond floats
        return error("bad_value", f"--set {name}: {value} is not a finite real number")
    return Measure(approx=approx, degree=ATOM.degree)


def parametrise(graph: BondGraph, choice: ParameterChoice) -> Parametrisation:
    """Resolve the parameters of `graph` under `choice` (raise `ModelError` for bad names)."""
    problems = [
        error("undeclared_parameter", f"{option} names {name!r}, which is not a parameter")
        for option, names in (("--keep", choice.keep), ("--set", choice.overrides))
        for name in sorted(names)
        if name not in graph.parameters
    ]
    if problems:
        raise ModelError(graph.source, problems)
    unknowns = graph.unknowns
    # --symbolic keeps the parameters given numbers; one given by others (`a = f(b)`, a
    # subsystem's parameter its parent sets) stays bound to them
    bound = {
        name
        for name, p in graph.parameters.items()
        if name not in choice.overrides and p.value is not None and p.value.value.free_symbols
    }
    symbolic = {
        name
        for name, p in graph.parameters.items()
        if (p.value is None and name not in choice.overrides)
        or (choice.symbolic and name not in bound)
        or name in choice.keep
        or name in unknowns
    }
    overrides = {name: _measure(name, value) for name, value in choice.overrides.items()}
    problems = [p for p in overrides.values() if isinstance(p, Diagnostic)]
    if not problems:
        problems = values_problems(graph.parameters, graph.components, symbolic, overrides)
    if problems:
        raise ModelError(graph.source, problems)
    values = {
        name: choice.overrides.get(name, p.value.value if p.value is not None else None)
        for name, p in graph.parameters.items()
    }

    @cache
    def resolved(name: str, keep_symbols: bool) -> sympy.Expr | None:
        """The value of a parameter in terms of the kept symbols (or fully, if not keeping)."""
        if keep_symbols and name in symbolic:
            return sympy.Symbol(name)
        value = values[name]
        if value is None:
            return None
        replacements = {}
        for symbol in value.free_symbols:
            inner = resolved(symbol.name, keep_symbols)
            if inner is None:
                return None
            replacements[symbol] = inner
        return value.xreplace(replacements)

    assumed = {n: resolved(n, True) for n in graph.parameters if n not in symbolic}
    symbols = tuple(n for n in graph.parameters if n in symbolic and n not in unknowns)
    return Parametrisation(
        unknowns=unknowns,
        symbols=symbols,
        assumed=MappingProxyType(assumed),
        defaults=MappingProxyType({n: resolved(n, False) for n in symbols}),
        true_values=MappingProxyType({n: resolved(n, False) for n in unknowns}),
        substitution=MappingProxyType({sympy.Symbol(n): v for n, v in assumed.items()}),
    )
