"""What can be told of a model file before its algebra (`mtt check`), and the
`not_identifiable` warning that `check --identifiability` and `compile` add.

Heavy stages are imported when a check runs, so that the command line's parser stays light.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

from mtt.language.diagnostics import ModelError, MttError

if TYPE_CHECKING:
    from mtt.derivation.parameters import ParameterChoice
    from mtt.language.bondgraph import BondGraph, Selection
    from mtt.language.diagnostics import Diagnostic
    from mtt.language.parse import ParsedModel


@dataclass(frozen=True)
class Checked:
    """One file's check: what was read of it (`parsed`, `graph`: None where it stopped
    earlier), the errors that stopped it (`problem`) and the identifiability `notes`."""

    file: str
    parsed: ParsedModel | None
    graph: BondGraph | None
    problem: ModelError | None
    notes: tuple[Diagnostic, ...] = ()


def check(file: str, selection: Selection, choice: ParameterChoice | None = None) -> Checked:
    """Everything that can be told of a model before algebra: the language's rules, then
    causality and the structure (can the input reach the output, the unknowns matter);
    with `choice` (--identifiability), whether the data can determine the unknowns (a
    warning). A part (open ports) gets its own rules and causality (its ports' is free)."""
    from mtt.derivation.causality import assign
    from mtt.derivation.structure import causal_for
    from mtt.language.bondgraph import build
    from mtt.language.parse import parse
    from mtt.language.subsystems import read_source

    parsed = graph = problem = None
    notes = []
    try:
        parsed = parse(read_source(file))
        graph = build(parsed, selection, part=True)
        if graph.open_ports:
            assign(graph)
        else:
            causal_for(graph, identify=True)
        if choice is not None and not graph.open_ports:  # algebra: sympy and G(s)
            notes = identifiability_warnings(graph, choice)
    except ModelError as exc:
        problem = exc
    return Checked(file, parsed, graph, problem, tuple(notes))


def identifiability_warnings(graph: BondGraph, choice: ParameterChoice) -> list[Diagnostic]:
    """The `not_identifiable` warning of a model whose unknowns are not globally
    identifiable; nothing when it has none or its transfer function cannot be derived
    (the commands that derive it report why)."""
    from mtt.derivation.identifiability import (
        identifiability,
        matrix_identifiability,
        warning_for,
    )
    from mtt.derivation.pipeline import equations_for
    from mtt.derivation.theta import theta_matrix
    from mtt.derivation.transfer import transfer_function
    from mtt.derivation.transfer_matrix import transfer_matrix
    from mtt.language.diagnostics import Origin

    if not graph.unknowns:
        return []
    try:
        equations = equations_for(graph, choice, identify=True)
        if equations.several:
            matrix = transfer_matrix(equations)
        else:
            theta = theta_matrix(transfer_function(equations))
    except MttError:
        return []
    positions = {name: p.position for name, p in graph.parameters.items()}
    try:
        if equations.several:
            result = matrix_identifiability(matrix, parts=False)
        else:
            result = identifiability(theta)
        found = warning_for(result, positions)
    except MttError:  # undecidable here (mtt identifiability says why)
        return []
    if found is None:
        return []
    return [found if found.origin else replace(found, origin=Origin(graph.source))]
