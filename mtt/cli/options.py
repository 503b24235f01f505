"""Command-line options shared by the commands that read a model.

Light to import (sympy is imported by a `--set` value or when a command runs), so that
building the `mtt` parser stays fast.
"""

from __future__ import annotations

import argparse
import re
from types import MappingProxyType
from typing import TYPE_CHECKING

from mtt.cli.value_options import Flatten, is_name

if TYPE_CHECKING:
    import sympy

    from mtt.derivation.parameters import ParameterChoice
    from mtt.language.bondgraph import Selection


# argparse takes an argument that starts with "-" for an option unless it looks like a
# negative number, which to Python 3.11's argparse -1e-3, -inf and -1:0 do not (`--k0 -inf`
# said "expected one argument"). No option of mtt starts with a digit, ".", inf or nan.
NEGATIVE_NUMBER = re.compile(r"-(?:\.?[0-9]|inf|nan)", re.IGNORECASE)


class Parser(argparse.ArgumentParser):
    """An ArgumentParser (its subcommands' too) that reads every negative number as a value
    and takes options only as spelled: argparse's abbreviations read `simulate --data f.csv`
    as --data-plot and then refused the CSV as an image format."""

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("allow_abbrev", False)
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = NEGATIVE_NUMBER


def given(text: str) -> str:
    """A file or directory named on the command line: an empty name is refused (it read as
    an option not given: `--csv ''` wrote nothing, `--copy ''` copied into '.')."""
    if not text:
        raise argparse.ArgumentTypeError("an empty name")
    return text


def assignment(text: str) -> tuple[str, sympy.Expr]:
    from mtt.language.parse import parse_expression

    name, equals, value = text.partition("=")
    if not equals or not is_name(name.strip()):
        raise argparse.ArgumentTypeError(f"expected NAME=VALUE, not {text!r}")
    try:
        return name.strip(), parse_expression(value, variables=frozenset())
    except Exception as exc:  # ModelError: a bad expression on the command line
        raise argparse.ArgumentTypeError(f"bad value in {text!r}: {exc}") from None


def _point(text: str) -> list[tuple[str, object]]:
    """`--at u=3.2,q_t=1/2`: values of the input and of states, exact; `x=V1;V2...` the
    states in order."""
    values = []
    for part in words(text):
        name, equals, value = part.partition("=")
        if name.strip() == "x" and equals:
            values.append(("x", tuple(assignment(f"x={v}")[1] for v in value.split(";"))))
        else:
            values.append(assignment(part))
    if not values:
        raise argparse.ArgumentTypeError(f"expected NAME=VALUE[,NAME=VALUE...], not {text!r}")
    return values


def _components(text: str) -> list[str]:
    """TYPE:NAME, or several (several inputs or outputs) as every list is given."""
    parts = words(text)
    for part in parts:
        kind, colon, name = part.partition(":")
        if not (colon and kind and is_name(name)):
            raise argparse.ArgumentTypeError(
                f"expected TYPE:NAME, not {part!r} (several: TYPE:NAME,TYPE:NAME or "
                "TYPE:NAME TYPE:NAME)"
            )
    return parts


def _signals(given: list[str] | None) -> str | None:
    """--input or --output as the model's selection takes it (several joined by commas)."""
    return None if not given else ",".join(given)


def words(text: str) -> list[str]:
    """A list option's word: items separated by commas (`a,b`); the option (nargs="+",
    action `Flatten`) extends its list with them, so that `a,b c` and `a b c` say the same,
    as for every list of mtt's options. A model file is not an item: the list took it from
    the command's FILE, which goes before the option (or after `--`)."""
    items = [item.strip() for item in text.split(",") if item.strip()]
    if not items:
        raise argparse.ArgumentTypeError(f"expected items separated by commas, not {text!r}")
    for item in items:
        if item.endswith(".bg"):
            raise argparse.ArgumentTypeError(
                f"{item!r} is a model file, not an item of the list: put the model file "
                "before the option, or end the list with --"
            )
    return items


def _assignments(text: str) -> list[tuple[str, sympy.Expr]]:
    """--set's word (NAME=VALUE, one a word: a value may hold commas, as max(a, b))."""
    if text.endswith(".bg") and "=" not in text:
        words(text)  # the model file's message
    return [assignment(text)]


def add_selection_options(parser: argparse.ArgumentParser) -> None:
    """The choices over the file that every command reading a model takes."""
    group = parser.add_argument_group("model")
    group.add_argument(
        "--unknown",
        metavar="NAME",
        type=words,
        nargs="+",
        action=Flatten,
        dest="unknowns",
        help="the parameters to identify, in this order (default: those the model declares "
        "'unknown'): --unknown a,b or --unknown a b",
    )
    for role, what, example in (
        ("input", "source", "Se:v, or a subsystem's Se:motor.v"),
        ("output", "detector", "Df:w, or a subsystem's De:motor.vc"),
    ):
        group.add_argument(
            f"--{role}",
            metavar="TYPE:NAME",
            type=_components,
            nargs="+",
            action=Flatten,
            help=f"the {what} to use as the {role}, over the file's '{role}' statement "
            f"(e.g. {example}); several {what}s for several {role}s",
        )
    group.add_argument(
        "--time-limit",
        metavar="SECONDS",
        type=_seconds,
        help="stop deriving after this many seconds of processor time with a too_large error "
        "(default 30, or MTT_TIME_LIMIT from the environment; inf for none)",
    )
    group.add_argument(
        "--include",
        metavar="DIR",
        type=given,
        action="append",
        default=[],
        help="also read subsystem files from DIR (by default only the model's directory tree "
        "and mtt's shipped parts)",
    )


def _seconds(text: str) -> float:
    try:
        seconds = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of seconds, not {text!r}") from None
    if not seconds > 0:  # also refuses nan
        raise argparse.ArgumentTypeError(f"must be above 0 seconds, not {text!r}")
    return seconds


def add_output_options(parser: argparse.ArgumentParser) -> None:
    """What every command that writes files takes."""
    parser.add_argument(
        "--parents",
        action="store_true",
        help="create missing directories of the files written anywhere (by default only "
        "inside the working directory)",
    )


def add_parameter_options(parser: argparse.ArgumentParser) -> None:
    add_selection_options(parser)
    group = parser.add_argument_group("parameters")
    group.add_argument(
        "--keep",
        metavar="NAME",
        type=words,
        nargs="+",
        action=Flatten,
        default=[],
        help="keep these parameters symbolic instead of substituting their values: --keep "
        "a,b or --keep a b",
    )
    group.add_argument("--symbolic", action="store_true", help="keep every parameter symbolic")
    group.add_argument(
        "--set",
        metavar="NAME=VALUE",
        type=_assignments,
        nargs="+",
        action=Flatten,
        default=[],
        dest="overrides",
        help="override parameters' values (exact expressions, e.g. --set ra=1.5 or --set "
        "ra=1.5 jl=2: a word each, as a value may hold commas)",
    )
    group.add_argument(
        "--max-terms",
        metavar="N",
        type=_positive,
        help="the most terms a polynomial of the derivation may have before it stops with "
        "too_large (default 30000: symbolic results can grow exponentially)",
    )

    group = parser.add_argument_group("operating point (nonlinear models)")
    group.add_argument(
        "--at",
        metavar="NAME=VALUE",
        type=_point,
        nargs="+",
        action=Flatten,
        help="linearise about this point: the input u and/or states by name (q_tank=0.5), "
        "or x=V1;V2;... for all states in order; what is not given is the steady state "
        "(see mtt equilibrium)",
    )
    group.add_argument(
        "--branch",
        metavar="N",
        type=_positive,
        help="which steady state, when there are several (as mtt equilibrium numbers them)",
    )


def _positive(text: str) -> int:
    if not text.isascii() or not text.isdigit() or int(text) < 1:
        raise argparse.ArgumentTypeError(f"expected a positive whole number, not {text!r}")
    return int(text)


def _unknowns(args: argparse.Namespace) -> tuple[str, ...] | None:
    return None if args.unknowns is None else tuple(args.unknowns)


def selection_from_args(args: argparse.Namespace) -> Selection:
    from mtt.language.bondgraph import Selection

    return Selection(
        _unknowns(args), _signals(args.input), _signals(args.output), tuple(args.include)
    )


def choice_from_args(args: argparse.Namespace) -> ParameterChoice:
    from mtt.derivation.budget import DEFAULT_BUDGET, Budget
    from mtt.derivation.parameters import ParameterChoice

    terms = getattr(args, "max_terms", None)
    return ParameterChoice(
        unknowns=_unknowns(args),
        keep=frozenset(getattr(args, "keep", ())),  # commands with selection options only
        symbolic=getattr(args, "symbolic", False),
        overrides=MappingProxyType(dict(getattr(args, "overrides", ()))),
        input=_signals(args.input),
        output=_signals(args.output),
        budget=DEFAULT_BUDGET if terms is None else Budget(terms),
        at=MappingProxyType(dict(args.at)) if getattr(args, "at", None) else None,
        branch=getattr(args, "branch", None),
        include=tuple(args.include),
    )
