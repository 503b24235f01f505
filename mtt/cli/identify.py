"""`mtt identifiability`: can input/output data tell the unknowns apart? Also `mtt
compile`'s `not_identifiable` warning, printed before it writes (mtt.derivation.checking
derives it, for `mtt check --identifiability` too).

The argparse wiring is light; the command imports sympy and the stages when it runs.
"""

from __future__ import annotations

import json
import sys

from mtt.cli import loading
from mtt.cli.options import add_parameter_options
from mtt.language.diagnostics import MttError

EXIT_OK = 0


def register(commands) -> None:
    """Add identifiability to the `mtt` subcommands."""
    command = commands.add_parser(
        "identifiability",
        help="can input/output data determine the unknowns?",
        description="Decide exactly, for generic true values, whether the transfer function "
        "determines the unknowns: globally (one set of values), locally (finitely many: "
        "which) or not at all (which combinations of them it determines).",
    )
    command.add_argument("file", metavar="FILE")
    add_parameter_options(command)
    command.add_argument("--json", action="store_true", help="print one JSON object")
    command.set_defaults(run=cmd_identifiability)


def cmd_identifiability(args) -> int:
    from mtt.derivation.identifiability import identifiability, matrix_identifiability
    from mtt.derivation.pipeline import NO_UNKNOWN
    from mtt.derivation.theta import theta_matrix
    from mtt.derivation.transfer import transfer_function
    from mtt.derivation.transfer_matrix import transfer_matrix
    from mtt.language.diagnostics import ModelError
    from mtt.present.identifiability import (
        identifiability_json,
        identifiability_text,
        matrix_json,
        matrix_text,
    )

    equations = loading.equations(args, identify=True)
    if not equations.parametrisation.unknowns:
        raise ModelError(equations.causal.bondgraph.source, [NO_UNKNOWN])
    if equations.several:  # from every entry of the matrix, and from fewer signals
        derived = transfer_matrix(equations)
        result = matrix_identifiability(derived)
        record, text = matrix_json, matrix_text
    else:
        derived = theta_matrix(transfer_function(equations))
        result = identifiability(derived)
        record, text = identifiability_json, identifiability_text
    print(json.dumps(record(derived, result)) if args.json else text(derived, result))
    return EXIT_OK


def warn_on_compile(run):
    """`mtt compile`, printing the `not_identifiable` warning first."""

    def compile_(args) -> int:
        from mtt.cli.options import choice_from_args
        from mtt.derivation.checking import identifiability_warnings
        from mtt.derivation.pipeline import load

        choice = choice_from_args(args)
        try:
            graph = load(args.file, choice.selection)
        except MttError:
            return run(args)  # compile reports the errors
        for note in identifiability_warnings(graph, choice):
            print(note.render(), file=sys.stderr)
        return run(args)

    return compile_
