"""Steady states of a nonlinear model: f(x, u0) = 0 for a constant input, every branch.

Exact (in the unknowns and the kept parameters) where sympy solves the equations: the
equations that give a state linearly are solved first, then sympy solves the rest within
a budget of processor time (`bounded`), every parameter taking the sign of its value in
the file; otherwise numeric, at the file's values, from many starting points. Where abs,
sign, min or max hold states, which side each steady state is on is found numerically,
and that side's equations are solved exactly. A steady state outside the domain of an
inverse the equations use (sqrt's, say) is not one of the model's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from types import MappingProxyType

import sympy

from mtt.derivation import bounded
from mtt.derivation.nonlinear import NonlinearStateSpace
from mtt.language.diagnostics import ModelError, error

MAX_EXACT_STATES = 6  # sympy.solve of larger systems can take unbounded time
NUMERIC_STARTS = 40  # starting points of the numeric search for steady states
NUMERIC_TOLERANCE = 1e-9  # relative residual of a numeric steady state
PIECEWISE = (sympy.Heaviside, sympy.sign, sympy.Abs, sympy.Max, sympy.Min)


@dataclass(frozen=True)
class Branch:
    """One steady state: each state's value, exact (in the unknowns and kept parameters)
    or numeric (a Float, at the file's values); `free`: states any value of which is
    steady (a continuum)."""

    x: MappingProxyType  # state -> value
    numeric: MappingProxyType  # state -> float, at the file's values
    y: sympy.Expr
    y_numeric: float
    exact: bool
    free: tuple[sympy.Symbol, ...] = ()


@dataclass(frozen=True)
class Equilibria:
    u: sympy.Expr
    branches: tuple[Branch, ...]
    method: str  # "exact" or "numeric"


class Signs:
    """The model's free symbols replaced by symbols with the sign of their value in the
    file (for sympy's algebra), and back."""

    def __init__(self, ss: NonlinearStateSpace, values: dict[sympy.Symbol, sympy.Expr]):
        self.forward, self.back = {}, {}
        for symbol, value in values.items():
            sign = sympy.sign(value) if value.is_number else 0
            if sign:
                signed = sympy.Symbol(symbol.name, positive=sign > 0, negative=sign < 0)
                self.forward[symbol], self.back[signed] = signed, symbol

    def to(self, expr: sympy.Expr) -> sympy.Expr:
        return expr.xreplace(self.forward)

    def fro(self, expr: sympy.Expr) -> sympy.Expr:
        return expr.xreplace(self.back)


def number(expr: sympy.Expr, values: dict) -> complex | None:
    try:
        return complex(expr.xreplace(values).evalf(30))
    except (TypeError, ValueError):
        return None


def is_real(value: complex | None) -> bool:
    return (
        value is not None
        and math.isfinite(value.real)
        and abs(value.imag) <= 1e-12 * max(1.0, abs(value.real))
    )


def equilibria(ss: NonlinearStateSpace, u0: sympy.Expr, values: dict) -> Equilibria:
    """Every steady state x0 with f(x0, u0) = 0: exact branches where sympy solves the
    equations (real at the file's `values`), else numeric ones found from many starts."""
    f = ss.f.xreplace({ss.input: u0})
    if not any(f.has(p) for p in PIECEWISE):
        exact = _exact(ss, f, u0, values)
        if exact is not None:
            return Equilibria(u0, exact, "exact")
        return Equilibria(u0, _numeric_branches(ss, f, u0, values), "numeric")
    # abs, sign, max, min: which side of each a steady state is on is found numerically,
    # then the equations of that side are solved exactly
    # (a root is polished in 30 digits only where no exact branch replaces it)
    branches = []
    for root in _numeric_roots(ss, f, u0, values):
        found = dict(zip(ss.states, map(float, root), strict=True))
        local = {**values, **{x: sympy.Float(v, 17) for x, v in found.items()}}
        smooth = sympy.Matrix([settled(e, local) for e in f])
        side = _exact(ss, smooth, u0, values) or ()
        same = [b for b in side if _close(b.numeric, found)]
        branches.append(same[0] if same else _numeric_branch(ss, f, u0, values, root))
    method = "exact" if branches and all(b.exact for b in branches) else "numeric"
    return Equilibria(u0, tuple(branches), method)


def _close(a: dict, b: dict) -> bool:
    return all(math.isclose(a[x], b[x], rel_tol=1e-7, abs_tol=1e-9) for x in b)


def _exact(ss: NonlinearStateSpace, f: sympy.Matrix, u0, values: dict) -> tuple[Branch, ...] | None:
    if len(ss.states) > MAX_EXACT_STATES or any(f.has(p) for p in PIECEWISE):
        return None  # sympy.solve would take long, or not decide the sides
    signs = Signs(ss, values)
    states = [signs.to(x) for x in ss.states]
    linear, equations, rest = _linear_steps([signs.to(e) for e in f if e != 0], states)
    if any(_mixed(e, x) for e in equations for x in rest):
        return None  # exp(x) beside x: no closed form sympy finds (Lambert W at best)
    solutions = bounded.within(_solve, equations, rest) if equations else [{}]
    if not solutions:
        return None
    solutions = [_back(linear, solution) for solution in solutions]
    branches = []
    for solution in solutions:
        x = {s: signs.fro(solution[s]) for s in ss.states if s in solution}
        free = tuple(s for s in ss.states if s not in solution)
        numeric = {s: number(v, values) for s, v in x.items()}
        if not all(is_real(v) for v in numeric.values()):
            continue  # a complex branch, or one undefined at the file's values
        if not _inside(ss, {**x, ss.input: u0}, values):
            continue  # outside the domain of an inverse mtt derived
        check = f.xreplace({**x, **{s: 0 for s in free}}).xreplace(values)
        residual = [number(r, {}) for r in check]
        if not all(r is not None and abs(r) < 1e-9 * (1 + _scale(numeric)) for r in residual):
            continue  # spurious: solve squared something
        y = ss.g[0].xreplace({ss.input: u0, **x})
        y_value = number(y, values)
        branches.append(
            Branch(
                MappingProxyType(x),
                MappingProxyType({s: v.real for s, v in numeric.items()}),
                y,
                y_value.real if is_real(y_value) else math.nan,
                True,
                free,
            )
        )
    branches.sort(key=lambda b: tuple(b.numeric[x] for x in ss.states if x in b.numeric))
    return tuple(branches) if branches else None


TRANSCENDENTAL = (sympy.exp, sympy.log, sympy.sin, sympy.cos, sympy.tan, sympy.tanh, sympy.atan)


def _linear_steps(equations: list, states: list) -> tuple[list, list, list]:
    """Equations that give one state linearly (x = an expression of the others, with a
    coefficient free of the states), solved in turn and put into the rest: what sympy
    then solves is smaller, and a friction's tanh(p) beside p vanishes once p = 0."""
    steps, rest = [], list(states)
    progress = True
    while progress:
        progress = False
        for equation in equations:
            for x in rest:
                slope = equation.diff(x)
                if slope == 0 or slope.has(*rest) or _inside_function(equation, x):
                    continue
                value = sympy.cancel(-equation.xreplace({x: 0}) / slope)
                steps.append((x, value))
                rest.remove(x)
                equations = [e.xreplace({x: value}) for e in equations]
                equations = [e for e in equations if e != 0]
                progress = True
                break
            if progress:
                break
    return steps, equations, rest


def _inside_function(equation: sympy.Expr, x: sympy.Symbol) -> bool:
    return any(f.has(x) for f in equation.atoms(sympy.Function, sympy.Pow) if f != x)


def _back(steps: list, solution: dict) -> dict:
    """A solution of the rest completed with the states the linear steps gave."""
    full = dict(solution)
    for x, value in reversed(steps):
        full[x] = sympy.cancel(value.xreplace(full))
    return full


def _mixed(equation: sympy.Expr, x: sympy.Symbol) -> bool:
    """Whether x occurs both inside a transcendental function and outside every one."""
    inside = [f for f in equation.atoms(*TRANSCENDENTAL) if f.has(x)]
    if not inside:
        return False
    outside = equation.xreplace({f: sympy.Dummy() for f in inside})
    return outside.has(x)


def _solve(equations: list, states: list) -> list[dict]:
    """Every solution, as sympy finds them (run within a time budget: `bounded`): an
    equation in one state left is solved alone and put into the rest, branch by branch;
    what is left coupled, by sympy.solve at once. Solutions are not checked here (the
    caller checks each at the file's values, which also drops those that squaring made)."""
    options = {"dict": True, "check": False, "simplify": False}
    alone = next((e for e in equations if len([x for x in states if e.has(x)]) == 1), None)
    if alone is None:
        solutions = sympy.solve(equations, states, **options) if equations else [{}]
        return [{x: sympy.cancel(v) for x, v in s.items()} for s in solutions]
    (x,) = [x for x in states if alone.has(x)]
    rest = [x_ for x_ in states if x_ != x]
    found = []
    for value in sympy.solve(alone, x, check=False, simplify=False):
        value = sympy.cancel(value)
        others = [e.xreplace({x: value}) for e in equations if e is not alone]
        others = [e for e in others if e != 0]
        found += [{x: value, **s} for s in _solve(others, rest)]
    return found


def _inside(ss: NonlinearStateSpace, point: dict, values: dict) -> bool:
    """Whether a point is in the domain of every inverse the equations use."""
    for condition in ss.domain:
        value = number(condition.xreplace(point), values)
        if value is not None and is_real(value) and value.real < -1e-12 * (1 + abs(value.real)):
            return False
    return True


def _scale(numeric: dict) -> float:
    return max((abs(v) for v in numeric.values()), default=1.0)


def _numeric_branches(ss, f: sympy.Matrix, u0, values: dict) -> tuple[Branch, ...]:
    """Steady states found numerically (`_numeric_roots`), each polished to 30 digits."""
    return tuple(_numeric_branch(ss, f, u0, values, x) for x in _numeric_roots(ss, f, u0, values))


def _numeric_roots(ss, f: sympy.Matrix, u0, values: dict) -> list:
    """Steady states found by scipy's root finder from many starting points (a grid of
    scales and signs, seeded): distinct ones, each to `NUMERIC_TOLERANCE`, in order."""
    import numpy as np
    import scipy.optimize

    states = list(ss.states)
    substituted = f.xreplace(values)
    if substituted.free_symbols - set(states):
        missing = ", ".join(sorted(map(str, substituted.free_symbols - set(states))))
        message = f"a numeric steady state needs values for {missing}"
        raise ModelError(ss.source, [error("missing_value", message)])
    # the Jacobian by scipy's differences: printing it for lambdify costs more than that
    function = sympy.lambdify([states], list(substituted), modules="numpy")
    rng = np.random.default_rng(0)
    found: list[np.ndarray] = []
    for start in _starts(len(states), rng):
        with np.errstate(all="ignore"):
            try:
                result = scipy.optimize.root(
                    lambda z: np.asarray(function(z), float),
                    start,
                    method="hybr",
                )
            except (ValueError, ZeroDivisionError, OverflowError):
                continue
            x = result.x
            residual = np.asarray(function(x), float)
        if not np.all(np.isfinite(residual)) or np.max(np.abs(residual)) > NUMERIC_TOLERANCE * (
            1 + np.max(np.abs(x))
        ):
            continue
        if any(np.allclose(x, other, rtol=1e-7, atol=1e-9) for other in found):
            continue
        point = {s: sympy.Float(v, 17) for s, v in zip(states, x, strict=True)}
        if not _inside(ss, {**point, ss.input: u0}, values):
            continue
        found.append(x)
    found.sort(key=lambda x: tuple(x))
    return found


def _numeric_branch(ss, f: sympy.Matrix, u0, values: dict, x) -> Branch:
    """The branch of a numeric root, polished to 30 digits, with its output."""
    states = list(ss.states)
    point = _polished(f.xreplace(values), states, x)
    y = ss.g[0].xreplace({ss.input: u0, **point}).xreplace(values)
    y_value = number(y, {})
    return Branch(
        MappingProxyType(point),
        MappingProxyType({s: float(v) for s, v in zip(states, x, strict=True)}),
        y,
        y_value.real if is_real(y_value) else math.nan,
        False,
    )


def _polished(f: sympy.Matrix, states: list, x) -> dict:
    """A root from scipy, refined by Newton's method in 30 digits (mpmath, through
    sympy.nsolve), so that its 17 digits do not depend on the path the root finder took;
    scipy's own where that fails."""
    try:
        refined = sympy.nsolve(list(f), states, [float(v) for v in x], prec=30, verify=False)
        values = [sympy.Float(v, 30) for v in refined]
    except (ValueError, TypeError, ZeroDivisionError, ArithmeticError):
        values = [sympy.Float(float(v), 30) for v in x]
    return {s: sympy.Float(v, 17) for s, v in zip(states, values, strict=True)}


def _starts(n: int, rng):
    import numpy as np

    yield np.zeros(n)
    for scale in (1.0, 10.0, 0.1, 100.0):
        yield np.full(n, scale)
        yield np.full(n, -scale)
    while True:
        yield rng.standard_normal(n) * 10.0 ** rng.uniform(-2, 2, n)
        if rng.random() < 1.0 / NUMERIC_STARTS:
            return


# Operating points and linearisation ------------------------------------------------


def settled(expr: sympy.Expr, values: dict) -> sympy.Expr:
    """abs, sign, max, min and the step of a derivative decided at the file's values where
    their arguments are not numbers (which side of max(e - h, 0) the point is on)."""

    def decide(node):
        if not isinstance(node, PIECEWISE) or all(a.is_number for a in node.args):
            return node
        numbers = [number(a, values) for a in node.args]
        if not all(is_real(v) for v in numbers):
            return node
        reals = [v.real for v in numbers]
        if isinstance(node, sympy.Max | sympy.Min):
            pick = max if isinstance(node, sympy.Max) else min
            return node.args[reals.index(pick(reals))]
        (a,) = node.args[:1]
        sign = (reals[0] > 0) - (reals[0] < 0)
        if isinstance(node, sympy.Abs):
            return a if sign >= 0 else -a
        if isinstance(node, sympy.sign):
            return sympy.Integer(sign)
        return sympy.Integer(1 if sign > 0 else 0) if sign else sympy.Rational(1, 2)

    return expr.replace(lambda n: isinstance(n, PIECEWISE), decide)
