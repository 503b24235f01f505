"""How model-derived values are written into generated code: exact numbers as Python
text, text as literals and docstring-safe reprs, names checked as identifiers (for the
estimator of mtt.estimator.codegen and the simulator of mtt.estimator.nonlinear_codegen).

Everything taken from a model reaches generated code through these: so the generated
text is safe to run, and the same value always gives the same bytes.
"""

from __future__ import annotations

import keyword
import re
import textwrap

import sympy

# Characters that sympy's printing of an exact number may use; text made only of them
# cannot end a docstring or a string literal.
PLAIN = re.compile(r"[\w .*/+\-()]+")


def is_name(name: str, dotted: bool = True) -> bool:
    """A model-derived name the generated code may carry (as a string, through repr): an
    identifier that is no keyword, or (`dotted`) a subsystem's dotted path of them."""
    parts = name.split(".") if dotted else [name]
    return all(part.isidentifier() and not keyword.iskeyword(part) for part in parts)


def number(value: sympy.Expr) -> str:
    """Python text for an exact real number: integers and fractions exact, others as floats."""
    if value.is_Integer:
        return str(int(value))
    if value.is_Rational:
        return f"{int(value.p)} / {int(value.q)}"
    return repr(finite_float(value))


def finite_float(value: sympy.Expr) -> float:
    number = sympy.N(value, 30)
    if not (number.is_real and number.is_finite):
        raise ValueError(f"not a finite real number: {value}")
    return float(number)


def doc_text(text: str) -> str:
    """Text for the docstring: as it is when plain (names, numbers, operators), else repr'd."""
    return text if PLAIN.fullmatch(text) else docstring_safe(text)


def wrapped(label: str, polynomial: sympy.Expr) -> str:
    """`label = polynomial` for the docstring, wrapped between terms."""
    lines = textwrap.wrap(
        f"{label} = {doc_text(str(polynomial))}",
        width=84,
        subsequent_indent=" " * (len(label) + 3),
        break_on_hyphens=False,
    )
    return "\n        ".join(lines)


def docstring_safe(value: object) -> str:
    """repr(value), escaped to read as itself inside a (non-raw, triple-quoted) docstring."""
    return repr(value).replace("\\", "\\\\").replace('"', '\\"')


def literal(text: str | None, width: int = 76) -> str:
    """A Python literal for `text`: repr'd pieces, one per line when it is long."""
    if text is None or len(text) <= width:
        return repr(text)
    pieces = []
    while len(text) > width:
        cut = text.rfind(" ", 0, width) + 1 or width
        pieces.append(text[:cut])
        text = text[cut:]
    pieces.append(text)
    return "(\n" + "".join(f"    {piece!r}\n" for piece in pieces) + ")"
