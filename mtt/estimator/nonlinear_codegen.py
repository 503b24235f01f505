"""Stage 7 for nonlinear models: NonlinearStateSpace -> a standalone simulator module.

The linear chain ends in Theta and the paper's estimator (`codegen`); a model whose
constitutive relations are nonlinear ends here, in a module that simulates x' = f(x, u, k),
y = g(x, u, k) fast, for one parameter set or many at once, with forward sensitivities
to the unknowns and the initial state (what a prediction-error fit needs). The
algorithm lives in templates/nonlinear/; what is particular to one model is its kernels
(`mtt.estimator.kernels`): straight-line Python printed from the exact equations, with
the model's names only ever in strings through repr.
"""

from __future__ import annotations

import re
import types
from typing import TYPE_CHECKING

import sympy

from mtt.estimator.codegen import environment, is_name, load_source, shadows
from mtt.estimator.kernels import Frozen, Kernel, KernelError, freeze, kernel
from mtt.estimator.rosenbrock import sensitivity_kernel, step_kernel
from mtt.language.diagnostics import ModelError, Source, error
from mtt.version import __version__

if TYPE_CHECKING:
    from mtt.derivation.nonlinear import NonlinearStateSpace

# Keyword names of the generated functions: a kept parameter (a keyword argument) must
# not take one of them.
RESERVED = frozenset({"t", "u", "k", "x", "x0", "hold", "rtol", "atol", "known"})


def _fail(system: NonlinearStateSpace, kind: str, message: str) -> ModelError:
    source = system.source if isinstance(system.source, Source) else Source(system.name, "")
    return ModelError(source, [error(kind, message, None)])


def _check(system: NonlinearStateSpace, kept: list[sympy.Symbol]) -> None:
    """Refuse what the generated module could not carry safely or use meaningfully."""
    name = system.name
    if not (isinstance(name, str) and is_name(name, dotted=False)):
        raise _fail(system, "bad_name", f"the model name {name!r} is not a Python identifier")
    if shadows(name):
        raise _fail(
            system,
            "reserved_name",
            f"the model name {name!r} is the name of a Python module: the simulator module "
            f"{name}.py would shadow it wherever it is imported; rename the model",
        )
    for symbol in kept:
        if not is_name(symbol.name, dotted=False) or symbol.name in RESERVED:
            raise _fail(
                system,
                "reserved_name",
                f"the parameter {symbol.name!r} cannot be kept symbolic in a simulator (it is "
                "no identifier, or the name of one of its arguments): give it a value",
            )
    n = len(system.states)
    if system.f.shape != (n, 1) or system.g.shape != (1, 1):
        raise ValueError(f"f must be {n} x 1 and g 1 x 1, not {system.f.shape}, {system.g.shape}")


def _kept(system: NonlinearStateSpace) -> list[sympy.Symbol]:
    """The parameters kept symbolic: the free symbols that are no state, input or unknown."""
    fixed = {*system.states, system.input, *system.unknowns}
    free = set().union(*(e.free_symbols for e in (*system.f, *system.g)))
    return sorted(free - fixed, key=lambda symbol: symbol.name)


def _kernels(system: NonlinearStateSpace, kept: list[sympy.Symbol]) -> tuple[Frozen, list]:
    n = len(system.states)
    frozen = freeze([*system.f, system.g[0]])
    f = sympy.Matrix(frozen.expressions[:n])
    g = frozen.expressions[n]
    x, u, k, m = list(system.states), system.input, list(system.unknowns), list(frozen.modes)
    names = {s: f"x{i}" for i, s in enumerate(x)} | {u: "u"}
    names |= {s: f"k{i}" for i, s in enumerate(k)} | {s: f"c{i}" for i, s in enumerate(kept)}
    names |= {s: s.name for s in m}
    base = [*x, u, *k, *kept]
    arguments = base + m
    f_x, f_k = f.jacobian(x), f.jacobian(k)
    gm = sympy.Matrix([g])
    s = [switch.function for switch in frozen.switches]
    sm = sympy.Matrix(s) if s else sympy.zeros(0, 1)
    first = [*f_x, *f.diff(u), *f_k, *gm.jacobian(x), g.diff(u), *gm.jacobian(k)]
    v = [sympy.Symbol(f"v{i}") for i in range(n)]
    du = sympy.Symbol("du")

    def along(matrix: sympy.Matrix) -> list[sympy.Expr]:
        return [
            sum((entry.diff(xi) * vi for xi, vi in zip(x, v, strict=True)), entry.diff(u) * du)
            for entry in matrix
        ]

    second_names = names | {s_: s_.name for s_ in v} | {du: "du"}
    zeros = {(i, j) for i in range(n) for j in range(n) if f_x[i, j] == 0}
    rest = [names[a] for a in arguments[n + 1 :]]
    prelude = frozen.selectors
    kernels = [
        kernel("rhs", arguments, list(f), names, prelude),
        kernel("output", arguments, [g], names, prelude),
        kernel("jacobian", arguments, first, names, prelude),
        kernel("switches", arguments, s, names, prelude),
        _modes_kernel(base, frozen, names),
        kernel(
            "switch_gradient",
            arguments,
            [*sm.jacobian(x), *sm.diff(u), *sm.jacobian(k)] if s else [],
            names,
            prelude,
        ),
        kernel("second", [*arguments, *v, du], along(f_x) + along(f_k), second_names, prelude),
        step_kernel(n, zeros, rest),
        sensitivity_kernel(n, len(k), zeros, rest),
    ]
    return frozen, kernels


def _modes_kernel(base: list[sympy.Symbol], frozen: Frozen, names: dict) -> Kernel:
    """m_i = side(s_i), in order: a switching function may read the modes before it."""
    body: list[str] = []
    for i, switch in enumerate(frozen.switches):
        one = kernel("m", base + list(frozen.modes[:i]), [switch.function], names,
                     frozen.selectors)  # fmt: skip
        renamed = {f"w{j}": f"w{i}_{j}" for j in range(len(one.body))}

        def rename(text: str, renamed=renamed) -> str:
            return re.sub(r"\bw\d+\b", lambda match: renamed[match.group(0)], text)

        body += [rename(line) for line in one.body]
        body.append(f"m{i} = side({rename(one.results[0])})")
    results = tuple(f"m{i}" for i in range(len(frozen.switches)))
    return Kernel("modes", tuple(names[a] for a in base), tuple(body), results)


def _float(value: sympy.Expr) -> float:
    number = sympy.N(value, 30)
    if not (number.is_real and number.is_finite):
        raise ValueError(f"not a finite real number: {value}")
    return float(number)


def _context(
    system: NonlinearStateSpace,
    true_values: dict[str, sympy.Expr] | None,
    defaults: dict[str, sympy.Expr] | None,
    description: str | None,
) -> dict:
    kept = _kept(system)
    _check(system, kept)
    try:
        frozen, kernels = _kernels(system, kept)
    except KernelError as exc:
        raise _fail(system, "unsupported_relation", str(exc)) from None
    unknowns = tuple(symbol.name for symbol in system.unknowns)
    p = len(unknowns)
    given = {name: _float(value) for name, value in (true_values or {}).items()}
    complete = all(name in given for name in unknowns)
    values = [given[name] for name in unknowns] if complete else None
    true_float = repr(values and (values[0] if p == 1 else tuple(values)))
    example = repr(values[0] if p == 1 else values) if values else repr([1.0] * p)
    defaults = {symbol.name: (defaults or {}).get(symbol.name) for symbol in kept}
    return {
        "version": __version__,
        "model": system.name,
        "description": description,
        "source": getattr(system.source, "name", system.name),
        "states": tuple(symbol.name for symbol in system.states),
        "input": system.input.name,
        "output": system.output.name,
        "unknowns": unknowns,
        "true_value": ", ".join(f"{name} = {given[name]!r}" for name in unknowns)
        if complete
        else None,
        "true_value_float": true_float,
        "example_k": example,
        "symbols": tuple(defaults),
        "parameters_doc": ", ".join(
            f"{name} = {value!r}" if value is not None else f"{name} (no value)"
            for name, value in ((name, _maybe_float(v)) for name, v in defaults.items())
        ),
        "defaults": "{"
        + ", ".join(f"{name!r}: {_maybe_float(value)!r}" for name, value in defaults.items())
        + "}",
        "equations": [
            f"d{state.name}/dt = {expression}"
            for state, expression in zip(system.states, system.f, strict=True)
        ]
        + [f"{system.output.name} = {system.g[0]}"],
        "switches": [
            f"{i}: {switch.kind}, s = {switch.function}" for i, switch in enumerate(frozen.switches)
        ],
        "switch_kinds": tuple(switch.kind for switch in frozen.switches),
        "continuous": tuple(switch.continuous for switch in frozen.switches),
        "kernels": [k.source() for k in kernels],
        "n": len(system.states),
        "p": p,
        "r": len(frozen.switches),
    }


def _maybe_float(value: sympy.Expr | None) -> float | None:
    return None if value is None else _float(value)


def render(
    system: NonlinearStateSpace,
    *,
    true_values: dict[str, sympy.Expr] | None = None,
    defaults: dict[str, sympy.Expr] | None = None,
    description: str | None = None,
) -> str:
    """The simulator module's source text for `system` (deterministic). `true_values`:
    the model file's values of the unknowns (the module's default k); `defaults`: those
    of the parameters kept symbolic."""
    context = _context(system, true_values, defaults, description)
    return environment().get_template("nonlinear/simulator.py.j2").render(context)


def load(system: NonlinearStateSpace, **options) -> types.ModuleType:
    """The simulator module for `system`, imported without writing a file."""
    return load_source(system.name, render(system, **options))
