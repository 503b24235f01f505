"""The model a command line names: its file read with the selection options, warnings
on stderr (light to import: each function imports the stages it runs)."""

from __future__ import annotations

import sys
from typing import TYPE_CHECKING

from mtt.cli.options import choice_from_args, selection_from_args

if TYPE_CHECKING:
    from mtt.derivation.equations import Equations
    from mtt.language.bondgraph import BondGraph


def load_graph(args) -> BondGraph:
    """The file's bond graph; its warnings go to stderr, its errors raise `ModelError`."""
    from mtt.derivation.pipeline import load

    graph = load(args.file, selection_from_args(args))
    for note in graph.warnings:
        print(note.render(), file=sys.stderr)
    return graph


def equations(args, identify: bool = False) -> Equations:
    """The equations of the model the arguments name; `identify`: check that its unknowns
    can be identified (they reach the output)."""
    from mtt.derivation.pipeline import equations_for

    graph = load_graph(args)
    for name, _ in args.overrides:
        if name in graph.unknowns:
            print(
                f"mtt {args.command}: warning: --set {name}=...: {name} is an unknown, which "
                "stays symbolic here (its value is the true value of simulations)",
                file=sys.stderr,
            )
    found = equations_for(graph, choice_from_args(args), identify)
    for note in found.notes:  # how a nonlinear model's linearisation was made
        print(note.render(graph.source), file=sys.stderr)
    return found
