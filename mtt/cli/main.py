"""The `mtt` command: one subcommand per representation a user may want to see.

Building the parser imports nothing heavy: each command imports the stages it runs
(sympy, scipy, matplotlib...) in its own body, so `mtt --help` starts at once and no
command pays for another's libraries (tests/test_cli_startup.py holds this).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import sys
import traceback
from typing import TYPE_CHECKING

from mtt import files
from mtt.cli import experiment_args, identify, loading, operating, views
from mtt.cli.options import (
    Parser,
    add_output_options,
    add_parameter_options,
    add_selection_options,
    choice_from_args,
    selection_from_args,
)
from mtt.derivation import deadline
from mtt.language.diagnostics import ModelError, MttError
from mtt.version import __version__

if TYPE_CHECKING:
    from mtt.language.bondgraph import BondGraph

EXIT_OK, EXIT_MODEL_ERROR, EXIT_BUG = 0, 2, 3
WRITERS = ("compile", "simulate", "estimate", "fit", "draw", "bode", "examples")
OUTPUTS = ("out", "path", "csv", "plot", "data_plot", "cost_plot")  # options naming files written
BUG_REPORT = (
    "mtt: internal error: {error}\n"
    "This is a bug in mtt, not in your model. Please report it on the mtt issue tracker\n"
    "with the model file and this message (set MTT_DEBUG=1 to print the traceback)."
)


def _print_json(value) -> None:
    print(json.dumps(value, sort_keys=False))


class UsageExit(SystemExit):
    """argparse's exit on a bad command line (status 2), with its message kept, so that
    `main` can also print it as JSON when --json was asked for."""

    def __init__(self, message: str):
        super().__init__(EXIT_MODEL_ERROR)
        self.message = message


class _Parser(Parser):
    """mtt's parser (its subcommands' too: negative numbers are values), exiting with a
    `UsageExit`."""

    def error(self, message: str):
        self.print_usage(sys.stderr)
        print(f"{self.prog}: error: {message}", file=sys.stderr)
        raise UsageExit(message)


# check / show -----------------------------------------------------------------


def cmd_check(args) -> int:
    from mtt.derivation.checking import check
    from mtt.present.summary import check_record, check_text

    choice = choice_from_args(args) if args.identifiability else None
    status = EXIT_OK
    records = []
    for file in args.files:
        checked = check(file, selection_from_args(args), choice)
        record = check_record(checked)
        if checked.problem is not None:
            status = EXIT_MODEL_ERROR
        if args.json:
            records.append(record)
            continue
        for note in (*(checked.graph.warnings if checked.graph else ()), *checked.notes):
            print(note.render(), file=sys.stderr)
        if checked.problem is not None:
            print(checked.problem.render(), file=sys.stderr)
            count = len(checked.problem.errors)
            print(f"{file}: {count} error{'s' * (count != 1)}", file=sys.stderr)
            continue
        print(check_text(checked.graph, record))
    if args.json:  # one document, of one shape for one file or several
        _print_json({"ok": all(r["ok"] for r in records), "files": records})
    return status


def cmd_show(args) -> int:
    from mtt.present import report, summary

    graph = loading.load_graph(args)
    if args.json:
        _print_json(report.show_json(graph))
    else:
        print(summary.describe(graph))
    return EXIT_OK


def cmd_causality(args) -> int:
    from mtt.derivation.causality import assign
    from mtt.derivation.causality import describe as describe_causality
    from mtt.present import report

    causal = assign(loading.load_graph(args))
    if args.json:
        _print_json(report.causality_json(causal))
    else:
        print(describe_causality(causal))
    return EXIT_OK


def cmd_ss(args) -> int:
    from mtt.derivation.nonlinear import nonlinear_parts
    from mtt.present import report

    if not args.at and nonlinear_parts(graph := loading.load_graph(args)):
        return _nonlinear_ss(args, graph)
    equations = loading.equations(args)
    if args.json:
        _print_json(report.ss_json(equations))
    else:
        print(report.ss_latex(equations) if args.latex else report.ss_text(equations))
    return EXIT_OK


def _nonlinear_ss(args, graph: BondGraph) -> int:
    """x' = f(x, u), y = g(x, u) of a nonlinear model (with --at: its linearisation)."""
    from mtt.derivation.pipeline import state_equations_for
    from mtt.present import nonlinear

    system, _ = state_equations_for(graph, choice_from_args(args))
    if args.json:
        _print_json(nonlinear.equations_json(system))
    else:
        print(nonlinear.equations_latex(system) if args.latex else nonlinear.equations_text(system))
    return EXIT_OK


def _derived(args, text, latex) -> int:
    from mtt.derivation.pipeline import NO_UNKNOWN
    from mtt.derivation.theta import refuse_cancelled, theta_matrix
    from mtt.derivation.transfer import transfer_function
    from mtt.present import report

    equations = loading.equations(args, identify=args.command == "theta")
    order = equations.causal.order
    if equations.several:
        return _derived_matrix(args, equations, order)
    theta = theta_matrix(transfer_function(equations))
    if args.command == "theta":
        if not theta.unknowns:
            raise ModelError(equations.causal.bondgraph.source, [NO_UNKNOWN])
        refuse_cancelled(theta)
    if args.json:
        _print_json(report.derived_json(theta, order=order))
    else:
        print(latex(theta) if args.latex else text(theta))
    return EXIT_OK


def _derived_matrix(args, equations, order: int) -> int:
    """`mtt tf` and `mtt theta` with several inputs or outputs: the transfer matrix."""
    from mtt.derivation.pipeline import NO_UNKNOWN
    from mtt.derivation.theta import refuse_cancelled
    from mtt.derivation.transfer_matrix import transfer_matrix
    from mtt.present import matrix as present

    matrix = transfer_matrix(equations)
    if args.command == "tf":
        record = lambda: present.matrix_json(matrix, order)  # noqa: E731
        shown = present.matrix_latex if args.latex else present.matrix_text
        printed = lambda: shown(matrix)  # noqa: E731
    else:
        thetas = matrix.thetas
        if not equations.parametrisation.unknowns:
            raise ModelError(equations.causal.bondgraph.source, [NO_UNKNOWN])
        refuse_cancelled(*thetas.values())
        record = lambda: present.thetas_json(matrix, thetas, order)  # noqa: E731
        if args.latex:
            printed = lambda: present.thetas_latex(thetas)  # noqa: E731
        else:
            printed = lambda: present.thetas_text(matrix, thetas)  # noqa: E731
    _print_json(record()) if args.json else print(printed())
    return EXIT_OK


def cmd_tf(args) -> int:
    from mtt.present import report

    return _derived(args, report.tf_text, report.tf_latex)


def cmd_theta(args) -> int:
    from mtt.present import report

    return _derived(args, report.theta_text, report.theta_latex)


# the parser --------------------------------------------------------------------


def make_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="mtt",
        description="Bond graph models of partially known systems: check them, derive their "
        "transfer function polynomial in the unknown parameter, and generate estimators.",
    )
    parser.add_argument("--version", action="version", version=f"mtt {__version__}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    check = commands.add_parser(
        "check",
        help="validate model files",
        description="Validate .bg model files; exit 0 when every file is valid, 2 otherwise.",
    )
    check.add_argument("files", nargs="+", metavar="FILE")
    check.add_argument(
        "--json",
        action="store_true",
        help='print one JSON document, {"ok": ..., "files": [a record per file, in order]}',
    )
    check.add_argument(
        "--identifiability",
        action="store_true",
        help="also derive the transfer function and warn (not_identifiable) when the data "
        "could not determine the unknowns (slower: computer algebra)",
    )
    add_selection_options(check)
    check.set_defaults(run=cmd_check)

    show = commands.add_parser(
        "show",
        help="summarise a model",
        description="Print a model's parameters, components, numbered bonds, input and output.",
    )
    show.add_argument("file", metavar="FILE")
    add_selection_options(show)
    show.add_argument("--json", action="store_true", help="print one JSON object")
    show.set_defaults(run=cmd_show)

    causality = commands.add_parser(
        "causality",
        help="show causal strokes, dependent storage and algebraic loops",
        description="Assign causality (sources first, then integral causality for C and I, "
        "then free resistors) and print every bond with its causal stroke.",
    )
    causality.add_argument("file", metavar="FILE")
    add_selection_options(causality)
    causality.add_argument("--json", action="store_true", help="print one JSON object")
    causality.set_defaults(run=cmd_causality)

    for name, run, summary in (
        ("ss", cmd_ss, "print the causal equations and the descriptor state-space form"),
        ("tf", cmd_tf, "print the exact transfer function, polynomial in the unknown"),
        ("theta", cmd_theta, "print Theta, the matrix the estimator is built from"),
    ):
        command = commands.add_parser(
            name, help=summary, description=summary[0].upper() + summary[1:] + "."
        )
        command.add_argument("file", metavar="FILE")
        add_parameter_options(command)
        command.add_argument("--latex", action="store_true", help="print LaTeX")
        command.add_argument("--json", action="store_true", help="print one JSON object")
        command.set_defaults(run=run)

    experiment_args.register(commands)
    compile_ = commands.choices["compile"]
    compile_.set_defaults(run=identify.warn_on_compile(compile_.get_default("run")))
    identify.register(commands)
    operating.register(commands)
    views.register(commands)
    for name in WRITERS:
        add_output_options(commands.choices[name])
    return parser


def _outputs(args) -> list[str]:
    """The files the command line names for writing (compile -o may be a directory)."""
    return [value for name in OUTPUTS if isinstance(value := getattr(args, name, None), str)]


def _tolerant_output() -> None:
    """Text a terminal's encoding cannot show (a model's non-ASCII description on an ASCII
    stdout) is escaped, not an error."""
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(AttributeError, ValueError):  # not a text file: leave it
            stream.reconfigure(errors="backslashreplace")


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    _tolerant_output()
    try:
        args = make_parser().parse_args(argv)
    except UsageExit as exc:  # --json promises {"ok": false, ...} for every failure
        if "--json" in argv:
            _print_json(MttError(exc.message, kind="usage").to_json())
        raise
    try:
        outputs, parents = _outputs(args), getattr(args, "parents", False)
        with files.session(outputs, parents), deadline.budget(getattr(args, "time_limit", None)):
            status = args.run(args)
        sys.stdout.flush()  # a closed pipe shows here, inside the handlers below
        return status
    except MttError as exc:  # a ModelError renders every problem in the model
        print(exc.render(), file=sys.stderr)
        if getattr(args, "json", False) and args.command != "check":  # check has its records
            _print_json(exc.to_json())
        return EXIT_MODEL_ERROR
    except KeyboardInterrupt:
        print("mtt: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # `mtt tf ... | head`: the reader had enough
        # what is still buffered would fail again when Python flushes at exit
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_OK
    except Exception as exc:  # noqa: BLE001 - the last line of defence: never a raw traceback
        if os.environ.get("MTT_DEBUG"):
            traceback.print_exc()
        print(BUG_REPORT.format(error=f"{type(exc).__name__}: {exc}"), file=sys.stderr)
        return EXIT_BUG
