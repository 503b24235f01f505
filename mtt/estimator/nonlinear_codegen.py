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

import types
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING

import sympy

from mtt.derivation.nonlinear import kept as kept_symbols
from mtt.estimator.codegen import environment, load_source, module_path, shadows
from mtt.estimator.kernels import (
    SIDE,
    TIE,
    Frozen,
    KernelError,
    field_kernel,
    freeze,
    kernel,
    shielded,
)
from mtt.estimator.literals import finite_float, is_name
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


def _edges(f: list, states: list[sympy.Symbol], unknowns: list, kept: list) -> list:
    """The domain edges the simulator can hold a state on: (state index, edge value, slope)
    for each power of f with a positive exponent that is not an integer (sqrt: a level under
    an orifice) whose base is a linear function alpha x_i + beta of one state and the
    parameters alone. f is finite on such an edge and its Jacobian is not (its column i
    is infinite there): a state that reaches it while the field points out of the domain
    (a tank run dry with no inflow) stays on it. Logarithms, negative exponents and bases
    of several states or of the input have no such edge: leaving their domain is an error."""
    constants = {*unknowns, *kept}
    found: dict[tuple[int, sympy.Expr], sympy.Expr] = {}
    for entry in f:
        for power in sympy.sympify(entry).atoms(sympy.Pow):
            base, exponent = power.args
            if not (exponent.is_number and exponent.is_positive and not exponent.is_integer):
                continue
            inside = base.free_symbols & set(states)
            if len(inside) != 1 or not base.free_symbols - inside <= constants:
                continue  # (a kink's guarded branch reads its selectors: never outside)
            (x,) = inside
            slope = sympy.simplify(base.diff(x))
            if slope.free_symbols - constants or slope == 0:
                continue
            edge = sympy.simplify(-base.subs(x, 0) / slope)
            found.setdefault((states.index(x), edge), slope)
    return [(i, edge, slope) for (i, edge), slope in sorted(found.items(), key=str)]


def _jacobian(matrix: sympy.Matrix, symbols: list) -> sympy.Matrix:
    """matrix's Jacobian by symbols, (rows, 0) for none (a model without unknowns: sympy's
    jacobian refuses an empty list)."""
    return matrix.jacobian(symbols) if symbols else sympy.zeros(matrix.rows, 0)


def _kernels(system: NonlinearStateSpace, kept: list[sympy.Symbol]) -> tuple[Frozen, list, list]:
    """The module's kernels. A kink (abs, min, max: f stays continuous) takes the branch
    the state is on, computed inside each kernel (its mode is side(s) there); a jump
    (sign) keeps the branch its mode argument says, frozen by the integrators between
    the events they locate. Also the domain edges (`_edges`)."""
    n = len(system.states)
    frozen = freeze([*system.f, system.g[0]])
    f = sympy.Matrix(frozen.expressions[:n])
    g = frozen.expressions[n]
    x, u, k = list(system.states), system.input, list(system.unknowns)
    held = [m for m, switch in zip(frozen.modes, frozen.switches, strict=True)
            if not switch.continuous]  # fmt: skip
    names = {s: f"x{i}" for i, s in enumerate(x)} | {u: "u"}
    names |= {s: f"k{i}" for i, s in enumerate(k)} | {s: f"c{i}" for i, s in enumerate(kept)}
    names |= {s: s.name for s in held}
    base = [*x, u, *k, *kept]
    arguments = base + held
    f_x, f_k = _jacobian(f, x), _jacobian(f, k)
    # (a branch switched off by a selector is kept inside its domain: no edge of the state's)
    edges = _edges([shielded(e, frozen.selectors) for e in f], x, k, kept)
    gm = sympy.Matrix([g])
    jumps = [switch.function for switch in frozen.switches if not switch.continuous]
    sm = sympy.Matrix(jumps) if jumps else sympy.zeros(0, 1)
    first = [*f_x, *f.diff(u), *f_k, *_jacobian(gm, x), g.diff(u), *_jacobian(gm, k)]
    v = [sympy.Symbol(f"v{i}") for i in range(n)]
    du = sympy.Symbol("du")

    def along(matrix: sympy.Matrix) -> list[sympy.Expr]:
        return [
            sum((entry.diff(xi) * vi for xi, vi in zip(x, v, strict=True)), entry.diff(u) * du)
            for entry in matrix
        ]

    second_names = names | {s_: s_.name for s_ in v} | {du: "du"}
    columns = len(k) + n  # sensitivities to the unknowns, then to the initial state
    S = sympy.Matrix(n, columns, lambda i, a: sympy.Symbol(f"s{i}_{a}"))
    flow = f_x * S + f_k.row_join(sympy.zeros(n, n))
    augmented_names = names | {entry: entry.name for entry in S}
    zeros = {(i, j) for i in range(n) for j in range(n) if f_x[i, j] == 0}
    rest = [names[a] for a in arguments[n + 1 :]]
    selectors = dict(frozen.selectors)
    prelude, every = [], []  # kinks' modes and all selectors; and every mode besides
    for m, switch in zip(frozen.modes, frozen.switches, strict=True):
        if switch.continuous:
            prelude.append((m, SIDE(switch.function)))
            every.append((m, SIDE(switch.function)))
        else:
            every.append((m, TIE(switch.function)))
        for selector in (sympy.Symbol(f"{m.name}p"), sympy.Symbol(f"{m.name}n")):
            if selector in selectors:
                prelude.append((selector, selectors[selector]))
                every.append((selector, selectors[selector]))
    prelude, every = tuple(prelude), tuple(every)
    # the kinks frozen on given branches (arguments after the jumps' modes): a run of many
    # sets at once keeps each set's kinks on their branches and checks their sides at the
    # samples, so that one set's kink does not cut every set's steps
    bent = [m for m, switch in zip(frozen.modes, frozen.switches, strict=True)
            if switch.continuous]  # fmt: skip
    selected = tuple((symbol, value) for symbol, value in prelude if symbol not in bent)
    frozen_names = names | {m: m.name for m in bent}
    kink_functions = [switch.function for switch in frozen.switches if switch.continuous]
    kernels = [
        kernel("rhs", arguments, list(f), names, prelude),
        kernel("output", arguments, [g], names, prelude),
        kernel("jacobian", arguments, first, names, prelude),
        kernel("switches", arguments, jumps, names, prelude),
        kernel("kinks", arguments, kink_functions, names, prelude),
        field_kernel(
            "frozen_field", arguments[n + 1 :] + bent, [*x, u], list(f), frozen_names, selected
        ),  # fmt: skip
        kernel("frozen_jacobian", arguments + bent, list(f_x), frozen_names, selected),
        kernel("modes", base, held, names, every),
        kernel(
            "switch_gradient",
            arguments,
            [*_jacobian(sm, x), *sm.diff(u), *_jacobian(sm, k)] if jumps else [],
            names,
            prelude,
        ),
        kernel("second", [*arguments, *v, du], along(f_x) + along(f_k), second_names, prelude),
        kernel(
            "augmented", [*x, *S, u, *arguments[n + 1 :]], [*f, *flow], augmented_names, prelude
        ),
        step_kernel(n, zeros, rest),
        sensitivity_kernel(n, len(k), zeros, rest),
        kernel("edges", [*k, *kept], [e for _, *pair in edges for e in pair], names),
    ]
    return frozen, kernels, edges


def _context(
    system: NonlinearStateSpace, values: dict[str, sympy.Expr], description: str | None
) -> dict:
    kept = list(kept_symbols(system))
    _check(system, kept)
    try:
        frozen, kernels, edges = _kernels(system, kept)
    except KernelError as exc:
        raise _fail(system, "unsupported_relation", str(exc)) from None
    jumps = [switch for switch in frozen.switches if not switch.continuous]
    unknowns = tuple(symbol.name for symbol in system.unknowns)
    p = len(unknowns)
    given = {name: finite_float(values[name]) for name in unknowns if values.get(name) is not None}
    complete = all(name in given for name in unknowns)
    values = [given[name] for name in unknowns] if complete else None
    true_float = repr(values and (values[0] if p == 1 else tuple(values)))
    example = repr(values[0] if p == 1 else values) if values else repr([1.0] * p)
    defaults = {symbol.name: values.get(symbol.name) for symbol in kept}
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
            f"{switch.kind}, s = {switch.function}: "
            + (
                "a kink, on the branch the state is on"
                if switch.continuous
                else f"a jump, event switch {jumps.index(switch)}"
            )  # fmt: skip
            for switch in frozen.switches
        ],
        "switch_kinds": tuple(switch.kind for switch in jumps),
        "kernels": [k.source() for k in kernels],
        "n": len(system.states),
        "p": p,
        "r": len(jumps),
        "kinks": len(frozen.switches) - len(jumps),
        "edge_states": tuple(i for i, _, _ in edges),
    }


def _maybe_float(value: sympy.Expr | None) -> float | None:
    return None if value is None else finite_float(value)


def render(
    system: NonlinearStateSpace,
    *,
    values: Mapping[str | sympy.Symbol, object] | None = None,
    description: str | None = None,
) -> str:
    """The simulator module's source text for `system` (deterministic). `values`: the
    model file's values of the unknowns (the module's default k) and of the parameters
    kept symbolic (their defaults), by name or symbol, as the derivation gives them."""
    named = {getattr(name, "name", name): value for name, value in (values or {}).items()}
    context = _context(system, named, description)
    return environment().get_template("nonlinear/simulator.py.j2").render(context)


def load(system: NonlinearStateSpace, **options) -> types.ModuleType:
    """The simulator module for `system`, imported without writing a file."""
    return load_source(system.name, render(system, **options))


def output_path(given: str | None, system: NonlinearStateSpace) -> Path:
    """Where `mtt compile -o GIVEN` writes the simulator (codegen.module_path)."""
    return module_path(given, system.name, lambda message: _fail(system, "reserved_name", message))
