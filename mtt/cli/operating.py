"""`mtt equilibrium` and `mtt linearise`: a nonlinear model's steady states and its
small-signal model about one (which `mtt tf`, `theta`, `compile`... take with --at).

The argparse wiring is light; each command imports sympy and the stages when it runs.
"""

from __future__ import annotations

import json
import sys

from mtt.cli import loading
from mtt.cli.options import add_parameter_options

EXIT_OK = 0


def _value(text: str):
    from mtt.cli.options import assignment

    return assignment(f"u={text}")[1]


def register(commands) -> None:
    """Add equilibrium and linearise to the `mtt` subcommands."""
    equilibrium = commands.add_parser(
        "equilibrium",
        help="the steady states of a (nonlinear) model at a constant input",
        description="Solve f(x, u) = 0 for the states at a constant input u: every branch, "
        "exact (in the unknowns and kept parameters) where sympy can, otherwise numeric at "
        "the file's values.",
    )
    equilibrium.add_argument("file", metavar="FILE")
    equilibrium.add_argument(
        "--u", type=_value, required=True, metavar="VALUE", help="the input's value (exact)"
    )
    add_parameter_options(equilibrium)
    equilibrium.add_argument("--json", action="store_true", help="print one JSON object")
    equilibrium.set_defaults(run=cmd_equilibrium)

    linearise = commands.add_parser(
        "linearise",
        aliases=["linearize"],
        help="the small-signal model about an operating point",
        description="Linearise the state equations about a point (--at u=VALUE, or states "
        "by name): A, B, C, D exact, and the small-signal transfer function, polynomial in "
        "the unknowns. tf, theta, compile, simulate and estimate take the same --at.",
    )
    linearise.add_argument("file", metavar="FILE")
    add_parameter_options(linearise)
    linearise.add_argument("--json", action="store_true", help="print one JSON object")
    linearise.set_defaults(run=cmd_linearise)


def cmd_equilibrium(args) -> int:
    from mtt.cli.options import choice_from_args
    from mtt.derivation.equilibria import equilibria
    from mtt.derivation.pipeline import state_equations_for
    from mtt.present import nonlinear

    system, values = state_equations_for(loading.load_graph(args), choice_from_args(args))
    found = equilibria(system, args.u, values)
    if args.json:
        print(json.dumps(nonlinear.equilibria_json(system, found)))
    else:
        print(nonlinear.equilibria_text(system, found))
    return EXIT_OK


def cmd_linearise(args) -> int:
    from mtt.cli.options import choice_from_args
    from mtt.derivation.pipeline import linearised_for
    from mtt.derivation.theta import theta_matrix
    from mtt.derivation.transfer import transfer_function
    from mtt.language.diagnostics import MttError
    from mtt.present import nonlinear, report

    if not args.at:
        message = "linearise needs the operating point: --at u=VALUE (or states)"
        raise MttError(message, kind="usage")
    system, small, equations = linearised_for(loading.load_graph(args), choice_from_args(args))
    for note in small.notes:
        print(note.render(equations.causal.bondgraph.source), file=sys.stderr)
    theta = theta_matrix(transfer_function(equations))
    if args.json:
        tf = report.derived_json(theta, order=len(system.states))
        print(json.dumps(nonlinear.small_signal_json(system, small, tf)))
    else:
        print(nonlinear.small_signal_text(system, small, report.tf_text(theta)))
    return EXIT_OK
