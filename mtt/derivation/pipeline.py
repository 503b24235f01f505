"""The chain of representations, stage by stage, for callers that start from a file."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from mtt.derivation import nonlinear, operating
from mtt.derivation.equations import Equations, derive
from mtt.derivation.nonlinear import nonlinear_model_error
from mtt.derivation.operating import values
from mtt.derivation.parameters import ParameterChoice, parametrise
from mtt.derivation.small_signal import small_signal
from mtt.derivation.structure import causal_for
from mtt.derivation.theta import Theta
from mtt.derivation.transfer import TransferFunction, signal_labels, transfer_function
from mtt.derivation.transfer_matrix import estimator_theta
from mtt.language.bondgraph import BondGraph, Selection, build
from mtt.language.diagnostics import ModelError, error
from mtt.language.parse import parse
from mtt.language.subsystems import read_source

__all__ = ["causal_for", "read_source", "load", "equations_for", "transfer_for", "theta_for"]


def load(path: str | Path, selection: Selection | None = None, part: bool = False) -> BondGraph:
    """Text -> parse tree -> validated bond graph (`part`: a part's file, alone, too)."""
    return build(parse(read_source(path)), selection, part)


DEFAULT_CHOICE = ParameterChoice()
NO_UNKNOWN = error(
    "no_unknown",
    "the model declares no unknown parameter: declare one with 'unknown NAME' or choose "
    "with --unknown NAME[,NAME...]",
)


def equations_for(
    graph: BondGraph, choice: ParameterChoice = DEFAULT_CHOICE, identify: bool = False
) -> Equations:
    """Bond graph -> causal bond graph -> equations, with the parameters as chosen; for a
    nonlinear model, those of its small-signal model at the operating point `choice.at`."""
    problem = nonlinear_model_error(graph)
    if problem is None:
        return derive(causal_for(graph, identify), parametrise(graph, choice), choice.budget)
    if choice.at is None:
        raise problem
    return linearised_for(graph, choice, identify)[2]


def _one_signal(graph: BondGraph) -> None:
    """The state equations x' = f(x, u), y = g(x, u) have one input and one output."""
    if graph.several:
        inputs, outputs = signal_labels(graph, graph.inputs), signal_labels(graph, graph.outputs)
        message = (
            f"from {inputs} to {outputs}: the state equations "
            "x' = f(x, u), y = g(x, u) (a nonlinear model's, its equilibria and its "
            "small-signal model) take one input and one output: choose them with --input "
            "TYPE:NAME --output TYPE:NAME"
        )
        raise ModelError(graph.source, [error("several_signals", message)])


def linearised_for(
    graph: BondGraph, choice: ParameterChoice, identify: bool = False
) -> tuple[nonlinear.NonlinearStateSpace, operating.SmallSignal, Equations]:
    """Bond graph -> state equations -> the small-signal model at the operating point
    `choice.at`, and its equations for the linear chain."""
    _one_signal(graph)
    causal = causal_for(graph, identify)
    parametrisation = parametrise(graph, choice)
    system = nonlinear.derive(causal, parametrisation)
    small = operating.linearise(system, operating.point(choice), values(parametrisation))
    equations = small_signal(
        causal,
        parametrisation,
        tuple(x.name for x in system.states),
        {"A": small.A, "B": small.B, "C": small.C, "D": small.D},
        small.notes,
    )
    return system, small, replace(equations, budget=choice.budget)


def state_equations_for(
    graph: BondGraph, choice: ParameterChoice = DEFAULT_CHOICE
) -> tuple[nonlinear.NonlinearStateSpace, dict]:
    """Bond graph -> x' = f(x, u), y = g(x, u) (any model, linear or not), with the file's
    values of the parameters that stay symbolic (for numbers and signs)."""
    _one_signal(graph)
    parametrisation = parametrise(graph, choice)
    return nonlinear.derive(causal_for(graph), parametrisation), values(parametrisation)


def transfer_for(path: str | Path, choice: ParameterChoice = DEFAULT_CHOICE) -> TransferFunction:
    """Text -> ... -> exact canonical transfer function."""
    return transfer_function(equations_for(load(path, choice.selection), choice))


def theta_for(path: str | Path, choice: ParameterChoice = DEFAULT_CHOICE) -> Theta:
    """Text -> ... -> Theta: everything a generated estimator needs (so, an unknown)."""
    graph = load(path, choice.selection)
    theta = estimator_theta(equations_for(graph, choice, identify=True))
    if not theta.unknowns:
        raise ModelError(read_source(path), [NO_UNKNOWN])
    return theta
