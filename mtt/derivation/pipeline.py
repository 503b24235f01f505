"""The chain of representations, stage by stage, for callers that start from a file."""

from __future__ import annotations

from pathlib import Path

from mtt.derivation.equations import Equations, derive
from mtt.derivation.parameters import ParameterChoice, parametrise
from mtt.derivation.structure import causal_for
from mtt.derivation.theta import Theta, theta_matrix
from mtt.derivation.transfer import TransferFunction, transfer_function
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
    """Bond graph -> causal bond graph -> equations, with the parameters as chosen."""
    return derive(causal_for(graph, identify), parametrise(graph, choice), choice.budget)


def transfer_for(path: str | Path, choice: ParameterChoice = DEFAULT_CHOICE) -> TransferFunction:
    """Text -> ... -> exact canonical transfer function."""
    return transfer_function(equations_for(load(path, choice.selection), choice))


def theta_for(path: str | Path, choice: ParameterChoice = DEFAULT_CHOICE) -> Theta:
    """Text -> ... -> Theta: everything a generated estimator needs (so, an unknown)."""
    graph = load(path, choice.selection)
    theta = theta_matrix(transfer_function(equations_for(graph, choice, identify=True)))
    if not theta.unknowns:
        raise ModelError(read_source(path), [NO_UNKNOWN])
    return theta
