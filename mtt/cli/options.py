"""Command-line options shared by the commands that read a model.

Light to import (sympy is imported by a `--set` value or when a command runs), so that
building the `mtt` parser stays fast.
"""

from __future__ import annotations

import argparse
from types import MappingProxyType
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import sympy

    from mtt.derivation.parameters import ParameterChoice
    from mtt.language.bondgraph import Selection


def _is_name(text: str) -> bool:
    """A parameter name, dotted for a subsystem's (`motor.ra`)."""
    return all(part.isidentifier() for part in text.split("."))


def _assignment(text: str) -> tuple[str, sympy.Expr]:
    from mtt.language.parse import parse_expression

    name, equals, value = text.partition("=")
    if not equals or not _is_name(name.strip()):
        raise argparse.ArgumentTypeError(f"expected NAME=VALUE, not {text!r}")
    try:
        return name.strip(), parse_expression(value, variables=frozenset())
    except Exception as exc:  # ModelError: a bad expression on the command line
        raise argparse.ArgumentTypeError(f"bad value in {text!r}: {exc}") from None


def _component(text: str) -> str:
    kind, colon, name = text.partition(":")
    if not (colon and kind and _is_name(name)):
        raise argparse.ArgumentTypeError(f"expected TYPE:NAME, not {text!r}")
    return text


def _names(text: str) -> list[str]:
    return [name.strip() for name in text.split(",") if name.strip()]


def add_selection_options(parser: argparse.ArgumentParser) -> None:
    """The choices over the file that every command reading a model takes."""
    group = parser.add_argument_group("model")
    group.add_argument(
        "--unknown",
        metavar="A,B",
        type=_names,
        action="extend",
        dest="unknowns",
        help="the parameters to identify, in this order (default: those the model declares "
        "'unknown')",
    )
    for role, what in (("input", "source"), ("output", "detector")):
        group.add_argument(
            f"--{role}",
            metavar="TYPE:NAME",
            type=_component,
            help=f"the {what} to use as the {role}, over the file's '{role}' statement "
            "(dotted names for a subsystem's: Se:motor.v)",
        )


def add_parameter_options(parser: argparse.ArgumentParser) -> None:
    add_selection_options(parser)
    group = parser.add_argument_group("parameters")
    group.add_argument(
        "--keep",
        metavar="A,B",
        type=_names,
        action="extend",
        default=[],
        help="keep these parameters symbolic instead of substituting their values",
    )
    group.add_argument("--symbolic", action="store_true", help="keep every parameter symbolic")
    group.add_argument(
        "--set",
        metavar="NAME=VALUE",
        type=_assignment,
        action="append",
        default=[],
        dest="overrides",
        help="override a parameter's value (an exact expression, e.g. --set ra=1.5)",
    )


def _unknowns(args: argparse.Namespace) -> tuple[str, ...] | None:
    return None if args.unknowns is None else tuple(args.unknowns)


def selection_from_args(args: argparse.Namespace) -> Selection:
    from mtt.language.bondgraph import Selection

    return Selection(_unknowns(args), args.input, args.output)


def choice_from_args(args: argparse.Namespace) -> ParameterChoice:
    from mtt.derivation.parameters import ParameterChoice

    return ParameterChoice(
        unknowns=_unknowns(args),
        keep=frozenset(getattr(args, "keep", ())),  # commands with selection options only
        symbolic=getattr(args, "symbolic", False),
        overrides=MappingProxyType(dict(getattr(args, "overrides", ()))),
        input=args.input,
        output=args.output,
    )
