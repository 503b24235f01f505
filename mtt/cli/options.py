"""Command-line options shared by every command that derives equations from a model.

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


def _assignment(text: str) -> tuple[str, sympy.Expr]:
    from mtt.language.parse import parse_expression

    name, equals, value = text.partition("=")
    if not equals or not name.strip().isidentifier():
        raise argparse.ArgumentTypeError(f"expected NAME=VALUE, not {text!r}")
    try:
        return name.strip(), parse_expression(value, variables=frozenset())
    except Exception as exc:  # ModelError: a bad expression on the command line
        raise argparse.ArgumentTypeError(f"bad value in {text!r}: {exc}") from None


def _names(text: str) -> list[str]:
    return [name.strip() for name in text.split(",") if name.strip()]


def add_parameter_options(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("parameters")
    group.add_argument(
        "--unknown",
        metavar="NAME",
        help="the parameter to identify (default: the one the model declares 'unknown')",
    )
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


def choice_from_args(args: argparse.Namespace) -> ParameterChoice:
    from mtt.derivation.parameters import ParameterChoice

    return ParameterChoice(
        unknown=args.unknown,
        keep=frozenset(args.keep),
        symbolic=args.symbolic,
        overrides=MappingProxyType(dict(args.overrides)),
    )
