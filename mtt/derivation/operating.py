"""Operating points of a nonlinear model and its small-signal (linearised) model there.

`equilibria`: the steady states f(x, u0) = 0 for a constant input u0, every branch, exact
(in the unknowns and kept parameters) where sympy solves the equations, numeric (at the
file's values) where it does not. `operating_point` completes a point given in part (u,
or some states) from the steady state; `linearise` gives A = df/dx, B = df/du, C = dg/dx,
D = dg/du there, exact, ready for the linear chain (transfer function, Theta, estimator).

The parameters take, in the algebra, the sign of their value in the file (a positive
orifice coefficient a makes sqrt(a^2) = a): what sympy cannot decide otherwise, such as
which side of max(e - h, 0) the point is on, is decided at the file's values too.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType

import sympy

from mtt.derivation.equilibria import (
    Signs,
    equilibria,
    number,
    settled,
)
from mtt.derivation.nonlinear import NonlinearStateSpace
from mtt.derivation.parameters import ParameterChoice, Parametrisation
from mtt.language.diagnostics import Diagnostic, ModelError, error, warning


@dataclass(frozen=True)
class OperatingPoint:
    """Values given for the input u and for some states (by name), exact; `branch`
    chooses among several steady states (1-based)."""

    given: MappingProxyType  # name -> exact value
    branch: int | None = None


def _fail(ss: NonlinearStateSpace, problem: Diagnostic) -> ModelError:
    return ModelError(ss.source, [problem])


def values(parametrisation: Parametrisation) -> dict[sympy.Symbol, sympy.Expr]:
    """The file's values of the unknowns (their true values) and of the kept symbols, where
    it gives them: where sympy cannot decide a sign or a side, these decide it."""
    given = {**parametrisation.defaults, **parametrisation.true_values}
    return {sympy.Symbol(name): value for name, value in given.items() if value is not None}


def point(choice: ParameterChoice) -> OperatingPoint:
    return OperatingPoint(choice.at or MappingProxyType({}), choice.branch)


def operating_point(
    ss: NonlinearStateSpace, point: OperatingPoint, values: dict
) -> tuple[dict[sympy.Symbol, sympy.Expr], sympy.Expr, list[Diagnostic]]:
    """The state x0 and input u0 of a point given in part: the states not given are those
    of the steady state for the given u (all of them when only u is given); u, when not
    given, the value that makes the given states steady. Returns the notes too (a point
    that is not a steady state: the small-signal model is then about a moving point)."""
    by_name = {s.name: s for s in ss.states}
    named = dict(point.given)
    if "x" in named and "x" not in by_name:  # x=V1;V2;...: every state, in order
        vector = named.pop("x")
        if len(vector) != len(ss.states):
            names = ", ".join(by_name)
            message = f"x has {len(vector)} values; the states are {names}"
            raise _fail(ss, error("bad_point", message))
        named.update(zip(by_name, vector, strict=True))
    point = OperatingPoint(MappingProxyType(named), point.branch)
    unknown = [n for n in point.given if n != "u" and n not in by_name]
    if unknown:
        names = ", ".join(["u", *by_name])
        message = f"--at names {unknown[0]!r}: an operating point names {names}"
        raise _fail(ss, error("bad_point", message))
    given = {by_name[n]: v for n, v in point.given.items() if n != "u"}
    u0 = point.given.get("u")
    notes: list[Diagnostic] = []
    if u0 is None:
        u0 = _steady_input(ss, given)
    rest = [s for s in ss.states if s not in given]
    if rest:
        partial = NonlinearStateSpace(
            ss.name, tuple(rest), ss.input, ss.output, ss.unknowns, ss.known,
            ss.f.xreplace(given), ss.g.xreplace(given), ss.source,
            tuple(c.xreplace(given) for c in ss.domain),
        )  # fmt: skip
        found = equilibria(partial, u0, values)
        branches = found.branches
        if not branches:
            raise _fail(ss, error("no_equilibrium", f"no steady state found at u = {u0}"))
        if point.branch is None and len(branches) > 1:
            listed = "; ".join(
                f"{i}: " + ", ".join(f"{s} = {v:.6g}" for s, v in b.numeric.items())
                for i, b in enumerate(branches, 1)
            )
            message = (
                f"{len(branches)} steady states at u = {u0} ({listed}): choose one with "
                "--branch N (see mtt equilibrium)"
            )
            raise _fail(ss, error("several_equilibria", message))
        index = (point.branch or 1) - 1
        if not 0 <= index < len(branches):
            message = f"--branch {point.branch}: there are {len(branches)} steady states"
            raise _fail(ss, error("bad_point", message))
        branch = branches[index]
        if not branch.exact:
            notes.append(
                warning(
                    "numeric_point",
                    f"the steady state at u = {u0} was found numerically, at the file's "
                    "values of the parameters (sympy could not solve it exactly): the "
                    "small-signal model's numbers are rounded to 17 digits, and its "
                    "dependence on the unknowns leaves out how the point moves with them",
                )
            )
        if branch.free:
            names = ", ".join(map(str, branch.free))
            message = f"every value of {names} is steady at u = {u0}: give it with --at"
            raise _fail(ss, error("bad_point", message))
        given = {**given, **branch.x}
    residual = [r for r in ss.f.xreplace({**given, ss.input: u0}) if r != 0]
    moving = [r for r in residual if abs(number(r, values) or 0) > 1e-12]
    if moving and not rest:  # a steady state found above is one, to its rounding
        notes.append(
            warning(
                "not_equilibrium",
                f"the point is not a steady state (x' = {moving[0]} there, at the file's "
                "values): the small-signal model is about a moving point",
            )
        )
    return given, u0, notes


def _steady_input(ss: NonlinearStateSpace, given: dict) -> sympy.Expr:
    """The input that makes the given states steady (from the first state equation that
    holds the input)."""
    for equation in ss.f.xreplace(given):
        if equation.has(ss.input):
            solutions = sympy.solve(equation, ss.input)
            if len(solutions) == 1:
                return solutions[0]
            break
    message = (
        "give the input's value with --at u=VALUE (no one value makes the given states steady)"
    )
    raise _fail(ss, error("bad_point", message))


def _rational(value: sympy.Expr) -> sympy.Rational:
    """A number as the exact decimal of its 17 significant digits."""
    return sympy.Rational(str(sympy.N(value, 17)))


def _decimals(expr: sympy.Expr) -> sympy.Expr:
    """Every number in the expression as the exact decimal of its 17 significant digits."""
    rounded = sympy.nfloat(expr, 17)
    return rounded.xreplace({n: _rational(n) for n in rounded.atoms(sympy.Float)})


def representable(expr: sympy.Expr, notes: list[Diagnostic]) -> sympy.Expr:
    """The expression with every constant the exact linear chain cannot hold (exp(3/2),
    cos(1/2), a LambertW) replaced by the exact decimal of its 17 significant digits, each
    named in a `rounded_constant` warning; rational numbers, their roots, pi and the other
    constants the chain holds stay exact."""
    from mtt.derivation.constants import Constants, Unsupported

    if expr.is_Rational or expr.is_Symbol or not expr.args:
        return expr
    if expr.is_number:
        try:
            Constants().scan(expr)
            return expr
        except Unsupported as problem:
            if problem.kind != "unsupported_constant":
                return expr  # the chain reports it
        inner = expr.func(*(representable(a, notes) for a in expr.args))
        try:
            Constants().scan(inner)
            return inner
        except Unsupported:
            value = _rational(expr)
            notes.append(
                warning(
                    "rounded_constant",
                    f"{expr} is taken as {sympy.N(expr, 17)} in the small-signal model "
                    "(the exact chain holds rational numbers, their roots, pi, e and "
                    "logarithms)",
                )
            )
            return value
    return expr.func(*(representable(a, notes) for a in expr.args))


@dataclass(frozen=True)
class SmallSignal:
    """x' = A x + B u, y = C x + D u about (x0, u0): exact sympy matrices."""

    x0: MappingProxyType
    u0: sympy.Expr
    y0: sympy.Expr
    A: sympy.Matrix
    B: sympy.Matrix
    C: sympy.Matrix
    D: sympy.Matrix
    notes: tuple[Diagnostic, ...] = ()


def linearise(ss: NonlinearStateSpace, point: OperatingPoint, values: dict) -> SmallSignal:
    """The small-signal model at the operating point."""
    x0, u0, notes = operating_point(ss, point, values)
    signs = Signs(ss, values)
    at = {ss.input: u0, **x0}
    states = list(ss.states)

    notes = list(notes)

    numeric = any(v.has(sympy.Float) for v in x0.values())

    def evaluated(matrix: sympy.Matrix) -> sympy.Matrix:
        entries = matrix.xreplace(at)
        if numeric:  # a numeric point: its numbers as 17-digit decimals, exactly
            entries = entries.applyfunc(lambda e: _decimals(settled(e, values)))
        return entries.applyfunc(
            lambda e: representable(signs.fro(sympy.cancel(signs.to(settled(e, values)))), notes)
        )

    y0 = evaluated(ss.g)[0]
    A, B = evaluated(ss.f.jacobian(states)), evaluated(ss.f.jacobian([ss.input]))
    C, D = evaluated(ss.g.jacobian(states)), evaluated(ss.g.jacobian([ss.input]))
    unique = list({(n.kind, n.message): n for n in notes}.values())
    return SmallSignal(MappingProxyType(x0), u0, y0, A, B, C, D, tuple(unique))
