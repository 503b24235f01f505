"""Nonlinear state equations of a bond graph: x' = f(x, u, theta), y = g(x, u, theta).

The stage after causality for models whose constitutive relations are nonlinear
(language version 3). Its result, `NonlinearStateSpace`, is the interface between the
derivation and everything downstream of it: the generated nonlinear simulator (in
mtt/estimator), operating points and linearisation.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import sympy

from mtt.derivation import deadline
from mtt.derivation.causal_equations import INPUT, OUTPUT, state_equations
from mtt.derivation.causality import CausalBondGraph
from mtt.derivation.parameters import ParameterChoice, Parametrisation
from mtt.language.bondgraph import BondGraph
from mtt.language.diagnostics import ModelError, Position, error
from mtt.language.elements import Component


@dataclass(frozen=True)
class NonlinearStateSpace:
    """x' = f(x, u, theta), y = g(x, u, theta), exact and simplified.

    The states are the energy variables of the storage elements in integral causality
    (q of a C, p of an I), in the model's component order; `f` and `g` are exact sympy
    expressions in the states, the input, the unknowns and the known parameters kept
    symbolic. Every known parameter with a value is in `known` (its exact value) and has
    already been substituted in `f` and `g`; a parameter kept symbolic is in neither, and
    appears in `f` and `g` as a free symbol. Downstream code (simulator generation,
    linearisation) may rely on: the free symbols of f and g are among states, input,
    unknowns and the kept symbols, nothing else.
    """

    name: str  # the model's name
    states: tuple[sympy.Symbol, ...]  # x: the storage elements' energy variables, in order
    input: sympy.Symbol  # u (one input for now)
    output: sympy.Symbol  # y's symbol (a name for display)
    unknowns: tuple[sympy.Symbol, ...]  # theta: the parameters to identify
    known: dict[sympy.Symbol, sympy.Expr]  # known parameters' exact values (kept ones absent)
    f: sympy.Matrix  # x' = f(x, u, unknowns, kept symbols), len(states) x 1
    g: sympy.Matrix  # y = g(x, u, ...), 1 x 1
    source: object = None  # where it came from (for located errors), optional
    # expressions of x, u and the parameters that are >= 0 wherever the equations hold:
    # the domains of the inverses mtt derived (f = a sqrt(e) used as e = (f/a)^2 holds
    # for f/a >= 0 only); a state outside them is not one of the model's
    domain: tuple[sympy.Expr, ...] = ()


def kept(system: NonlinearStateSpace) -> tuple[sympy.Symbol, ...]:
    """The parameters kept symbolic: the free symbols of f and g that are no state, input
    or unknown, by name."""
    fixed = {*system.states, system.input, *system.unknowns}
    free = set().union(*(e.free_symbols for e in (*system.f, *system.g)))
    return tuple(sorted(free - fixed, key=lambda symbol: symbol.name))


@deadline.timed("the state equations", lambda causal: causal.bondgraph)
def derive(causal: CausalBondGraph, parametrisation: Parametrisation) -> NonlinearStateSpace:
    """The causal bond graph's state equations x' = f(x, u), y = g(x, u), exact; raise
    `ModelError` for a loop that cannot be solved or a state that needs the input's
    derivative."""
    graph = causal.bondgraph
    states, f, g, domain = state_equations(causal, parametrisation)
    return NonlinearStateSpace(
        name=graph.name,
        states=states,
        input=INPUT,
        output=OUTPUT,
        unknowns=tuple(sympy.Symbol(n) for n in parametrisation.unknowns),
        known={sympy.Symbol(n): v for n, v in parametrisation.assumed.items()},
        f=f,
        g=g,
        source=graph.source,
        domain=domain,
    )


def nonlinear_parts(graph: BondGraph) -> list[tuple[Component, str, Position]]:
    """The components that make a model nonlinear (its equations are then those of this
    module, and its transfer function exists only about an operating point), with why."""
    parts = []
    for c in graph.components:
        if c.nonlinear_relation:
            parts.append((c, f"its relation {c.relation.text()} is nonlinear", c.relation.position))
        elif c.argument is None:
            continue
        elif c.type.modulated and (
            c.argument.signal_problem
            or not c.argument.signals
            or any(use.kind in ("q", "p") for use in c.argument.signals)
        ):
            why = f"its value {c.argument} is not a linear combination of efforts and flows"
            parts.append((c, why, c.argument.position))
        elif c.type.modulable and c.argument.signals:
            parts.append((c, f"its ratio {c.argument} reads signals", c.argument.position))
    return parts


def nonlinear_model_error(graph: BondGraph) -> ModelError | None:
    """`nonlinear_model` for a command that needs a linear model, at the first nonlinear
    part; None for a linear model."""
    parts = nonlinear_parts(graph)
    if not parts:
        return None
    component, why, where = parts[0]
    message = (
        f"the model is nonlinear ({component.label}: {why}): a transfer function exists only "
        "about an operating point; add --at u=VALUE (mtt equilibrium lists the steady "
        "states), and mtt ss prints its nonlinear state equations"
    )
    return ModelError(graph.source, [error("nonlinear_model", message, where)])


def nonlinear_state_space(
    path_or_text: str | Path, choice: ParameterChoice | None = None
) -> NonlinearStateSpace:
    """A model file (or its text: a str with a line break) -> its state equations
    x' = f(x, u), y = g(x, u), exact (`ModelError` for anything wrong in the model)."""
    from mtt.derivation.parameters import parametrise
    from mtt.derivation.structure import causal_for
    from mtt.language.bondgraph import build
    from mtt.language.diagnostics import Source
    from mtt.language.parse import parse
    from mtt.language.subsystems import read_source

    choice = choice or ParameterChoice()
    if isinstance(path_or_text, str) and "\n" in path_or_text:
        source = Source("<string>", path_or_text.removeprefix("\ufeff"))
    else:
        source = read_source(path_or_text)
    graph = build(parse(source), choice.selection)
    return derive(causal_for(graph), parametrise(graph, choice))
