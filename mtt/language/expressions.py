"""Expressions of the .bg language: a small tree of their own, turned into sympy when used.

The parser builds every expression as a tree of frozen nodes (numbers are exact
fractions, folded as they are read), measured as it is built (`measure`): the language
stage checks names, signals and the limits of the implementation on these trees without
importing sympy. A stage that computes (the derivation, reports) asks for `value`, the
exact sympy object, built node by node from the tree: no text from a model ever reaches
eval, exec, sympify or parse_expr.

Signal terms `e(X)`, `f(X)`, `q(X)` and `p(X)` (in the argument of a modulated source,
TF or GY, and a component's own variables in its constitutive relation) become the
Symbols `e(X)`, `f(X)`, `q(X)`, `p(X)`, which no parameter can be called.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from fractions import Fraction
from functools import cached_property
from typing import TYPE_CHECKING

from mtt.language.diagnostics import Position

if TYPE_CHECKING:
    import sympy

# the functions a model may call, with their number of arguments (None: two or more)
FUNCTIONS = {
    "sqrt": 1, "exp": 1, "log": 1, "sin": 1, "cos": 1, "tan": 1, "tanh": 1, "atan": 1,
    "abs": 1, "sign": 1, "sat": 1, "min": None, "max": None,
}  # fmt: skip
# functions only derivation writes (the inverses of relations), never read from a model
INVERSES = ("asin", "acos", "atanh")
CONSTANTS = ("pi",)
# e(X) and f(X) read a bond's variables; q(X) and p(X) their time integrals (a C's or an
# I's state, or a state of their own)
SIGNALS = {"e": "effort", "f": "flow", "q": "displacement", "p": "momentum"}
LAPLACE = "s"
# the names version 2 reserved; the functions added since may also name parameters (a
# call and a name are told apart by the parenthesis), so that no version 2 model breaks
RESERVED = frozenset({LAPLACE, "sqrt", "exp", "log", "sin", "cos", *CONSTANTS})


@dataclass(frozen=True)
class NameUse:
    name: str
    position: Position


@dataclass(frozen=True)
class SignalUse:
    """`e(X)` or `f(X)`: the effort or flow of the component X (dotted for a subsystem's)."""

    kind: str  # "e" or "f"
    target: str
    position: Position

    @property
    def text(self) -> str:
        return f"{self.kind}({self.target})"

    @property
    def symbol(self) -> sympy.Symbol:
        import sympy

        return sympy.Symbol(self.text)


@dataclass(frozen=True)
class SignalProblem:
    """Where an expression stops being a linear combination of signals, and why."""

    message: str
    position: Position
    malformed: bool = False  # a signal badly written (else: only where linearity ends)


# The tree --------------------------------------------------------------------------


@dataclass(frozen=True)
class Node:
    position: Position


@dataclass(frozen=True)
class Number(Node):
    value: Fraction


@dataclass(frozen=True)
class Name(Node):
    name: str


@dataclass(frozen=True)
class Constant(Node):
    name: str  # pi


@dataclass(frozen=True)
class Signal(Node):
    kind: str
    target: str


@dataclass(frozen=True)
class Call(Node):
    function: str
    arguments: tuple[Node, ...]

    @property
    def argument(self) -> Node:
        """The first (for most functions, the only) argument."""
        return self.arguments[0]


@dataclass(frozen=True)
class Negative(Node):
    operand: Node


@dataclass(frozen=True)
class Sum(Node):
    """t1 ± t2 ± ...: each term with whether it is subtracted (a chain `a - b + c` is one
    node; a parenthesised sum inside it is a term of its own)."""

    parts: tuple[tuple[bool, Node], ...]


@dataclass(frozen=True)
class Product(Node):
    """f1 */ f2 */ ...: each factor with whether it divides."""

    parts: tuple[tuple[bool, Node], ...]


@dataclass(frozen=True)
class Power(Node):
    base: Node
    exponent: Node


@dataclass(frozen=True)
class Placeholder(Node):
    """Stands where a problem was reported, so that no second error follows from it."""


# Printing ------------------------------------------------------------------------------


def _simple_number(node: Node) -> bool:
    """A number that prints as a plain non-negative integer."""
    return isinstance(node, Number) and node.value >= 0 and node.value.denominator == 1


def _wrapped(node: Node, bare: tuple[type, ...]) -> str:
    """The node's text, in parentheses unless it is a leaf or one of the `bare` kinds."""
    leaf = isinstance(node, Name | Constant | Signal | Call | Placeholder) or _simple_number(node)
    inner = text(node)
    return inner if leaf or isinstance(node, bare) else f"({inner})"


def text(node: Node) -> str:
    """The expression as it could be written, with the parentheses it needs."""
    if isinstance(node, Number):
        value = node.value
        return str(value.numerator) if value.denominator == 1 else str(value)
    if isinstance(node, Name | Constant):
        return node.name
    if isinstance(node, Signal):
        return f"{node.kind}({node.target})"
    if isinstance(node, Call):
        return f"{node.function}({', '.join(text(a) for a in node.arguments)})"
    if isinstance(node, Negative):
        return "-" + _wrapped(node.operand, (Product, Power))
    if isinstance(node, Sum):
        (_, first), *rest = node.parts  # a chain starts with a term added
        parts = [_wrapped(first, (Product, Power, Number))]
        for subtracted, term in rest:
            parts.append(
                f" {'-' if subtracted else '+'} {_wrapped(term, (Product, Power, Number))}"
            )
        return "".join(parts)
    if isinstance(node, Product):
        (_, first), *rest = node.parts  # a chain starts with a factor multiplied
        parts = [_wrapped(first, (Power, Product))]
        for divides, factor in rest:
            parts.append(
                ("/" if divides else "*")
                + _wrapped(factor, (Power,) if divides else (Power, Product))
            )
        return "".join(parts)
    if isinstance(node, Power):
        return f"{_wrapped(node.base, ())}^{_wrapped(node.exponent, (Power,))}"
    return "?"


# Conversion to sympy ---------------------------------------------------------------


def _saturation(x: sympy.Expr) -> sympy.Expr:
    """sat(x) = x / sqrt(1 + x^2): a smooth saturation, odd, of slope 1 at 0, tending to
    -1 and 1 (written out, so that it differentiates and prints as itself)."""
    import sympy

    return x / sympy.sqrt(1 + x**2)


def _sympy_function(name: str):
    import sympy

    special = {"abs": sympy.Abs, "min": sympy.Min, "max": sympy.Max, "sat": _saturation}
    return special.get(name) or getattr(sympy, name)


def to_sympy(node: Node) -> sympy.Expr:
    """The exact sympy value of a tree (the tree is at most `MAX_DEPTH` deep)."""
    import sympy

    if isinstance(node, Number):
        return sympy.Rational(node.value.numerator, node.value.denominator)
    if isinstance(node, Name):
        return sympy.Symbol(node.name)
    if isinstance(node, Constant):
        return sympy.pi
    if isinstance(node, Signal):
        return sympy.Symbol(f"{node.kind}({node.target})")
    if isinstance(node, Call):
        return _sympy_function(node.function)(*(to_sympy(a) for a in node.arguments))
    if isinstance(node, Negative):
        return -to_sympy(node.operand)
    if isinstance(node, Sum):
        value = sympy.Integer(0)
        for subtracted, term in node.parts:
            value = value - to_sympy(term) if subtracted else value + to_sympy(term)
        return value
    if isinstance(node, Product):
        value = sympy.Integer(1)
        for divides, factor in node.parts:
            value = value / to_sympy(factor) if divides else value * to_sympy(factor)
        return value
    if isinstance(node, Power):
        return to_sympy(node.base) ** to_sympy(node.exponent)
    return sympy.Dummy()


def rename(node: Node, names: dict[str, str], signals: dict[str, str], where) -> Node:
    """The tree with parameter names and signal targets renamed (`where` moves positions)."""
    position = where(node.position)

    def again(child: Node) -> Node:
        return rename(child, names, signals, where)

    if isinstance(node, Name):
        return Name(position, names.get(node.name, node.name))
    if isinstance(node, Signal):
        return Signal(position, node.kind, signals.get(node.target, node.target))
    if isinstance(node, Call):
        return Call(position, node.function, tuple(again(a) for a in node.arguments))
    if isinstance(node, Negative):
        return Negative(position, again(node.operand))
    if isinstance(node, Sum):
        return Sum(position, tuple((sign, again(term)) for sign, term in node.parts))
    if isinstance(node, Product):
        return Product(position, tuple((sign, again(factor)) for sign, factor in node.parts))
    if isinstance(node, Power):
        return Power(position, again(node.base), again(node.exponent))
    return replace(node, position=position)


# The record ------------------------------------------------------------------------


@dataclass(frozen=True)
class Measure:
    """What is known of an expression before any algebra, to keep it within the limits.

    `exact` is its value when it is a rational number; `approx` a float value of a
    constant that is not rational (pi, roots, functions) and `bounds` an interval sure to
    hold it (None when unknown), which decides the sign of the argument of a root or a
    logarithm before sympy is asked (sympy's work on a logarithm of a logarithm of a
    negative number grows exponentially with the nesting); `degree` bounds the degrees of
    its numerator and denominator in its atoms (names, signals, constants, functions)
    once written as one fraction, `terms` their numbers of terms, and `digits` the
    decimal digits of their coefficients; `depth` and `size` count its nodes.
    """

    exact: Fraction | None = None
    approx: float | None = None
    bounds: tuple[float, float] | None = None
    degree: tuple[int, int] = (0, 0)
    terms: tuple[int, int] = (1, 1)
    digits: tuple[float, float] = (0.0, 0.0)
    depth: int = 1
    size: int = 1

    @property
    def constant(self) -> bool:
        return self.exact is not None or self.approx is not None


ATOM = Measure(degree=(1, 0))


@dataclass(frozen=True)
class Expression:
    """A parsed expression: its tree, every name it uses with its place, its signal terms
    and `signal_problem`, the first place where it is not a linear combination of them
    (None when it is one, or has no signal at all)."""

    tree: Node
    names: tuple[NameUse, ...]
    position: Position
    signals: tuple[SignalUse, ...] = ()
    signal_problem: SignalProblem | None = None
    measure: Measure = field(default=ATOM, compare=False)

    @cached_property
    def value(self) -> sympy.Expr:
        """The exact sympy value (Rationals, Symbols, sympy functions), built when asked."""
        return to_sympy(self.tree)

    @property
    def exact(self) -> Fraction | None:
        """The value when it is a rational number known without algebra."""
        return self.measure.exact

    def __str__(self) -> str:
        return text(self.tree)


def name_expression(name: str, position: Position) -> Expression:
    """The expression made of one parameter name (`R:ra` means `R:ra(ra)`)."""
    return Expression(Name(position, name), (NameUse(name, position),), position)


def renamed(expression: Expression, prefix: str, parameters, where) -> Expression:
    """A subsystem's expression as the whole model names it: its parameters and signal
    targets prefixed, its places moved to its file by `where`."""
    names = {u.name: prefix + u.name for u in expression.names if u.name in parameters}
    signals = {u.target: prefix + u.target for u in expression.signals}
    return Expression(
        rename(expression.tree, names, signals, where),
        tuple(NameUse(prefix + u.name, where(u.position)) for u in expression.names),
        where(expression.position),
        tuple(SignalUse(u.kind, prefix + u.target, where(u.position)) for u in expression.signals),
        expression.signal_problem,
        expression.measure,
    )
