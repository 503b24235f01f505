"""`mtt identifiability`: can input/output data tell the unknowns apart? Also the
`not_identifiable` warning of `mtt check` and `mtt compile`.

The argparse wiring is light; the command imports sympy and the stages when it runs.
"""

from __future__ import annotations

import json
import sys
from dataclasses import replace
from typing import TYPE_CHECKING

from mtt.cli.options import add_parameter_options
from mtt.language.diagnostics import MttError

if TYPE_CHECKING:
    from mtt.derivation.identifiability import Identifiability
    from mtt.derivation.parameters import ParameterChoice
    from mtt.derivation.theta import Theta
    from mtt.language.bondgraph import BondGraph
    from mtt.language.diagnostics import Diagnostic

EXIT_OK = 0
VERDICTS = {
    "global": "globally identifiable",
    "local": "locally identifiable",
    "none": "not identifiable",
}


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
    from mtt.cli.main import _equations
    from mtt.derivation.identifiability import identifiability
    from mtt.derivation.pipeline import NO_UNKNOWN
    from mtt.derivation.theta import theta_matrix
    from mtt.derivation.transfer import transfer_function
    from mtt.language.diagnostics import ModelError

    equations = _equations(args, identify=True)
    theta = theta_matrix(transfer_function(equations))
    if not theta.unknowns:
        raise ModelError(equations.causal.bondgraph.source, [NO_UNKNOWN])
    result = identifiability(theta)
    print(json.dumps(to_json(theta, result)) if args.json else text(theta, result))
    return EXIT_OK


def _number(value) -> str:
    """An exact value in the language's syntax; an approximate one to 15 digits."""
    from mtt.derivation.identifiability import expression_text

    if value.is_Rational:
        return expression_text(value)
    real, imaginary = (float(part) for part in value.as_real_imag())
    return f"{real:.15g}" if imaginary == 0 else f"{real:.15g}{imaginary:+.15g}i"


def text(theta: Theta, result: Identifiability) -> str:
    from mtt.derivation.identifiability import expression_text, point_text

    names = ", ".join(result.unknowns)
    several = len(result.unknowns) > 1
    values = f"({names})" if several else names
    lines = [
        f"model {theta.model}: from {theta.input} to {theta.output}; "
        f"unknown{'s' * several} {names}",
        VERDICTS[result.verdict],
    ]
    if result.verdict == "global":
        lines[-1] += f": the transfer function determines {names}"
        return "\n".join(lines)
    if result.verdict == "local":
        lines[-1] += (
            f": for generic true values {values}, {result.solutions} values give the same "
            "transfer function:"
        )
        lines += [f"  {point_text(m)}" for m in result.maps]
        others = result.solutions - len(result.maps)
        if others:
            lines.append(f"  and {others} more, algebraic (not rational) in the true values")
        if result.points:
            model = all(theta.true_values.get(n) == v for n, v in result.point.items())
            lines.append(
                f"for {'the model' + chr(39) + 's' if model else 'random'} values {values} = "
                f"{point_text(result.point, _number)} they are ({result.real} real, "
                f"{result.positive} positive):"
            )
            lines += [f"  {point_text(p, _number)}" for p in result.points]
    else:
        lines[-1] += (
            f": for generic true values, a {len(result.unknowns) - result.rank}-parameter "
            f"family of values of {values} gives the same transfer function"
        )
    combinations = ", ".join(expression_text(c) for c in result.combinations)
    lines.append(f"the data determine: {combinations or 'nothing'}")
    lines.append(
        f"identified on {'their' if several else 'its'} own: "
        f"{', '.join(result.identified) or 'none'}"
    )
    return "\n".join(lines)


def to_json(theta: Theta, result: Identifiability) -> dict:
    """The `identifiability --json` record (its shape is a public contract)."""
    from mtt.derivation.identifiability import expression_text

    return {
        "ok": True,
        "model": theta.model,
        "input": theta.input,
        "output": theta.output,
        "unknowns": list(result.unknowns),
        "verdict": result.verdict,
        "rank": result.rank,
        "solutions": result.solutions,
        "identified": list(result.identified),
        "combinations": [expression_text(c) for c in result.combinations],
        "maps": [{n: expression_text(v) for n, v in m.items()} for m in result.maps],
        "point": {n: _number(v) for n, v in result.point.items()} if result.point else None,
        "points": [{n: _number(v) for n, v in p.items()} for p in result.points],
        "real": result.real if result.points else None,
        "positive": result.positive if result.points else None,
    }


def warnings(graph: BondGraph, choice: ParameterChoice) -> list[Diagnostic]:
    """The `not_identifiable` warning of a model whose unknowns are not globally
    identifiable; nothing when it has none or its transfer function cannot be derived
    (the commands that derive it report why)."""
    from mtt.derivation.identifiability import identifiability, warning_for
    from mtt.derivation.pipeline import equations_for
    from mtt.derivation.theta import theta_matrix
    from mtt.derivation.transfer import transfer_function
    from mtt.language.diagnostics import Origin

    if not graph.unknowns:
        return []
    try:
        theta = theta_matrix(transfer_function(equations_for(graph, choice, identify=True)))
    except MttError:
        return []
    positions = {name: p.position for name, p in graph.parameters.items()}
    try:
        found = warning_for(identifiability(theta), positions)
    except MttError:  # undecidable here (mtt identifiability says why)
        return []
    if found is None:
        return []
    return [found if found.origin else replace(found, origin=Origin(graph.source))]


def warn_on_compile(run):
    """`mtt compile`, printing the `not_identifiable` warning first."""

    def compile_(args) -> int:
        from mtt.cli.options import choice_from_args
        from mtt.derivation.pipeline import load

        choice = choice_from_args(args)
        try:
            graph = load(args.file, choice.selection)
        except MttError:
            return run(args)  # compile reports the errors
        for note in warnings(graph, choice):
            print(note.render(), file=sys.stderr)
        return run(args)

    return compile_
