"""The chain of representations, stage by stage, for callers that start from a file."""

from __future__ import annotations

from pathlib import Path

from mtt.derivation.causality import assign
from mtt.derivation.equations import Equations, derive
from mtt.derivation.parameters import ParameterChoice, parametrise
from mtt.derivation.theta import Theta, theta_matrix
from mtt.derivation.transfer import TransferFunction, transfer_function
from mtt.language.bondgraph import BondGraph, Selection, build
from mtt.language.diagnostics import ModelError, Source, error
from mtt.language.parse import parse


def read_source(path: str | Path) -> Source:
    """A model file's text (a UTF-8 byte order mark is dropped); unreadable files are model
    errors too (kind `io`)."""
    name = str(path)
    try:
        return Source(name, Path(path).read_text(encoding="utf-8-sig"))
    except (OSError, UnicodeDecodeError) as exc:
        reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
        raise ModelError(
            Source(name, ""), [error("io", f"cannot read the file: {reason}")]
        ) from None


def load(path: str | Path, selection: Selection | None = None) -> BondGraph:
    """Text -> parse tree -> validated bond graph."""
    return build(parse(read_source(path)), selection)


DEFAULT_CHOICE = ParameterChoice()
NO_UNKNOWN = error(
    "no_unknown",
    "the model declares no unknown parameter: declare one with 'unknown NAME' or choose "
    "with --unknown NAME[,NAME...]",
)


def equations_for(graph: BondGraph, choice: ParameterChoice = DEFAULT_CHOICE) -> Equations:
    """Bond graph -> causal bond graph -> equations, with the parameters as chosen."""
    return derive(assign(graph), parametrise(graph, choice))


def transfer_for(path: str | Path, choice: ParameterChoice = DEFAULT_CHOICE) -> TransferFunction:
    """Text -> ... -> exact canonical transfer function."""
    return transfer_function(equations_for(load(path, choice.selection), choice))


def theta_for(path: str | Path, choice: ParameterChoice = DEFAULT_CHOICE) -> Theta:
    """Text -> ... -> Theta: everything a generated estimator needs (so, an unknown)."""
    theta = theta_matrix(transfer_for(path, choice))
    if not theta.unknowns:
        raise ModelError(read_source(path), [NO_UNKNOWN])
    return theta
