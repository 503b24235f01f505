"""Command-line options shared by the commands that read a model.

Light to import (sympy is imported by a `--set` value or when a command runs), so that
building the `mtt` parser stays fast.
"""

from __future__ import annotations

import argparse
import re
from types import MappingProxyType
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import sympy

    from mtt.derivation.parameters import ParameterChoice
    from mtt.language.bondgraph import Selection


# argparse takes an argument that starts with "-" for an option unless it looks like a
# negative number, which to Python 3.11's argparse -1e-3, -inf and -1:0 do not (`--k0 -inf`
# said "expected one argument"). No option of mtt starts with a digit, ".", inf or nan.
NEGATIVE_NUMBER = re.compile(r"-(?:\.?[0-9]|inf|nan)", re.IGNORECASE)


class Parser(argparse.ArgumentParser):
    """An ArgumentParser (its subcommands' too) that reads every negative number as a value."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = NEGATIVE_NUMBER


def given(text: str) -> str:
    """A file or directory named on the command line: an empty name is refused (it read as
    an option not given: `--csv ''` wrote nothing, `--copy ''` copied into '.')."""
    if not text:
        raise argparse.ArgumentTypeError("an empty name")
    return text


def _is_name(text: str) -> bool:
    """A parameter name, dotted for a subsystem's (`motor.ra`)."""
    return all(part.isidentifier() for part in text.split("."))


def assignment(text: str) -> tuple[str, sympy.Expr]:
    from mtt.language.parse import parse_expression

    name, equals, value = text.partition("=")
    if not equals or not _is_name(name.strip()):
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
        if not (colon and kind and _is_name(name)):
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


# Values per unknown, for the commands that simulate and estimate several unknowns:
# --k0 a=1,b=2 (a starting point; repeat the option's values for several), --true
# a=10,b=1, --bounds a=0:5,b=1:20. With one unknown a bare value stays valid (--k0 5,
# --bounds 0:5). The parser checks the form; `in_unknowns_order` checks the names against
# the model's unknowns once it is known.

Named = dict[str, float] | float  # by name, or a bare value (a model with one unknown)
NamedBounds = dict[str, tuple[float, float]] | tuple[float, float]


def _finite(text: str, whole: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text.strip()!r} in {whole!r} is not a number") from None
    if value != value or value in (float("inf"), float("-inf")):
        raise argparse.ArgumentTypeError(f"{text.strip()!r} in {whole!r} is not finite")
    return value


def _interval(text: str, whole: str) -> tuple[float, float]:
    low, colon, high = text.partition(":")
    if not colon:
        raise argparse.ArgumentTypeError(f"expected LO:HI, not {text.strip()!r} in {whole!r}")
    low, high = _finite(low, whole), _finite(high, whole)
    if not low < high:
        raise argparse.ArgumentTypeError(f"{text.strip()!r} in {whole!r}: LO must be below HI")
    return low, high


def _by_name(text: str, value) -> dict:
    """`a=X,b=Y` -> {"a": value(X), "b": value(Y)}, each name once."""
    found = {}
    for part in text.split(","):
        name, equals, rest = part.partition("=")
        name = name.strip()
        if not equals or not _is_name(name):
            raise argparse.ArgumentTypeError(f"expected NAME=VALUE,..., not {text!r}")
        if name in found:
            raise argparse.ArgumentTypeError(f"{name} is given twice in {text!r}")
        found[name] = value(rest, text)
    return found


def named_values(text: str) -> Named:
    """The type of --k0 and --true: `a=1,b=2`, or a bare `5` for one unknown."""
    return _by_name(text, _finite) if "=" in text else _finite(text, text)


def state_values(text: str) -> dict[str, float] | list[float]:
    """The type of simulate's --x0: `q1=1,q2=2` by name, or bare numbers in the order of
    the model's states (`1,2`)."""
    return _by_name(text, _finite) if "=" in text else numbers(text)


def numbers(text: str) -> list[float]:
    """A list option's word: finite numbers separated by commas (`1,5,10`); the option
    (action `Flatten`) extends its list with them: `1,5 10` and `1 5 10` say the same."""
    parts = [part for part in text.split(",") if part.strip()]
    if not parts:
        raise argparse.ArgumentTypeError(f"expected numbers separated by commas, not {text!r}")
    return [_finite(part, text) for part in parts]


class Flatten(argparse.Action):
    """nargs="+" over a type that gives lists (`numbers`, `starts`): one flat list, the
    option repeated or not."""

    def __call__(self, parser, namespace, values, option_string=None) -> None:
        items = list(getattr(namespace, self.dest, None) or [])
        setattr(namespace, self.dest, items + [value for group in values for value in group])


def starts(text: str) -> list[Named]:
    """The type of estimate's --k0 (action `Flatten`): each word a point by name
    (`a=1,b=2`), or bare numbers for one unknown, several separated by commas (`0,5,20`)."""
    return [_by_name(text, _finite)] if "=" in text else numbers(text)


def named_bounds(text: str) -> NamedBounds:
    """The type of --bounds: `a=0:5,b=1:20`, or a bare `0:5` for one unknown."""
    return _by_name(text, _interval) if "=" in text else _interval(text, text)


def in_unknowns_order(given, unknowns: tuple[str, ...], option: str, complete: bool = True):
    """The values of `option` as a tuple in the order of `unknowns` (None for one not given
    when not `complete`); raise `MttError` (bad_value) for a bare value with several
    unknowns, a name that is not an unknown, or (`complete`) an unknown left out."""
    from mtt.language.diagnostics import MttError

    if not isinstance(given, dict):
        if len(unknowns) != 1:
            raise MttError(
                f"{option}: the model has {len(unknowns)} unknowns ({', '.join(unknowns)}): "
                f"give each by name, {option} {','.join(f'{n}=...' for n in unknowns)}",
                kind="bad_value",
            )
        return (given,)
    strangers = [name for name in given if name not in unknowns]
    if strangers:
        raise MttError(
            f"{option}: {', '.join(strangers)} {'is' if len(strangers) == 1 else 'are'} not "
            f"an unknown of the model (its unknowns: {', '.join(unknowns)})",
            kind="bad_value",
        )
    missing = [name for name in unknowns if name not in given]
    if complete and missing:
        example = ",".join(f"{name}=..." for name in unknowns)
        raise MttError(
            f"{option}: no value for {', '.join(missing)} (one point names every unknown, "
            f"joined by commas: {option} {example}; a space starts another point)",
            kind="bad_value",
        )
    return tuple(given.get(name) for name in unknowns)


class BoundsAction(argparse.Action):
    """--bounds with nargs="+": `LO HI` (two bare numbers, the first spelling, one unknown),
    or `named_bounds` values (`LO:HI`; `a=LO:HI,b=LO:HI`, also over several words)."""

    def __call__(self, parser, namespace, values, option_string=None) -> None:
        try:
            setattr(namespace, self.dest, _bounds_words(values))
        except argparse.ArgumentTypeError as exc:
            parser.error(f"argument {option_string}: {exc}")


def _bounds_words(words: list[str]) -> NamedBounds:
    if len(words) == 2 and all(":" not in word and "=" not in word for word in words):
        return _interval(":".join(words), " ".join(words))
    found: dict = {}
    for word in words:
        given = named_bounds(word)
        if not isinstance(given, dict):
            if len(words) > 1:
                raise argparse.ArgumentTypeError(
                    f"give one interval LO:HI, or each unknown's by name, not {' '.join(words)!r}"
                )
            return given
        repeated = sorted(set(found) & set(given))
        if repeated:
            raise argparse.ArgumentTypeError(f"{repeated[0]} is given twice")
        found |= given
    return found
