"""Values on the command line: numbers and lists of them (each list option extends one
flat list, `Flatten`), and values per unknown, for the commands that simulate and estimate
several unknowns.

--k0 a=1,b=2 (a starting point; repeat the option's values for several), --true
a=10,b=1, --bounds a=0:5,b=1:20. With one unknown a bare value stays valid (--k0 5,
--bounds 0:5). The parser checks the form; `in_unknowns_order` checks the names against
the model's unknowns once it is known. Light to import, as mtt/cli/options.py.
"""

from __future__ import annotations

import argparse


def is_name(text: str) -> bool:
    """A parameter name, dotted for a subsystem's (`motor.ra`)."""
    return all(part.isidentifier() for part in text.split("."))


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
        if not equals or not is_name(name):
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
