"""Constitutive relations written in a component's own variables: `R:o(f = a*sqrt(e))`.

A relation `VAR = EXPR` gives one of the two variables an R, C or I relates (R: e and f;
C: e and its displacement q; I: f and its momentum p) in terms of the other and of
parameters; a second one, after a comma, may give the inverse. Inside a relation the
names e, f, q and p are the component's own variables (read as the signals e(X), f(X),
q(X), p(X) of the component X itself).

Everything here works on the expression trees, without sympy, so that `mtt check` (and
causality, which needs to know which way a relation can be used) stays fast:

* `linear_parameter`: a relation that is linear through the origin (`f = e/r`,
  `C:c(e = q/c)`) is the linear component of the old syntax, with its parameter;
* `Constitutive.giving`: the relation that yields a variable, as written or inverted
  exactly (`inverse`): each function on the path from the variable to the top of the
  expression is undone in turn, on its domain (sqrt by squaring where its value is not
  negative, sin by asin on [-pi/2, pi/2], ...), and a relation in which the variable
  enters linearly (an affine function of it, in several places) is solved; abs, sign,
  min and max, and a variable that enters nonlinearly in several places, have no exact
  inverse.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

from mtt.language.diagnostics import Position
from mtt.language.expressions import (
    Call,
    Expression,
    Name,
    NameUse,
    Negative,
    Node,
    Number,
    Power,
    Product,
    Signal,
    SignalUse,
    Sum,
    text,
)

# which causality each variable serves when a relation gives it: giving e (R, C) or p (I)
# is imposing the port's effort; giving f (R, I) or q (C), its flow
IMPOSES_EFFORT = {"e": True, "f": False, "q": False, "p": True}
VARIABLE_NAMES = tuple(IMPOSES_EFFORT)


@dataclass(frozen=True)
class Relation:
    """`variable = expression`: the expression's own variables are Signal nodes (kind,
    the component's name); `domain` says where a derived inverse holds."""

    variable: str
    expression: Expression
    position: Position  # of the variable, on the left of '='
    derived: bool = False  # an inverse mtt derived, not one the model gives
    domain: tuple[str, ...] = ()
    # where a derived inverse holds, as expressions that are >= 0 there
    conditions: tuple[Expression, ...] = ()

    @property
    def target(self) -> str:
        return self.expression.signals[0].target if self.expression.signals else ""

    def text(self) -> str:
        """As written: the own variables by their bare names."""
        return f"{self.variable} = {text(bare(self.expression.tree))}"


def bare(node: Node) -> Node:
    """The tree with every signal written as its bare kind (`e(o)` as `e`), for display."""
    if isinstance(node, Signal):
        return Name(node.position, node.kind)
    return _map(node, bare)


def _map(node: Node, again) -> Node:
    """The node with `again` applied to its children."""
    if isinstance(node, Call):
        return Call(node.position, node.function, tuple(again(a) for a in node.arguments))
    if isinstance(node, Negative):
        return Negative(node.position, again(node.operand))
    if isinstance(node, Sum | Product):
        parts = tuple((flag, again(part)) for flag, part in node.parts)
        return type(node)(node.position, parts)
    if isinstance(node, Power):
        return Power(node.position, again(node.base), again(node.exponent))
    return node


def _children(node: Node) -> tuple[Node, ...]:
    if isinstance(node, Call):
        return node.arguments
    if isinstance(node, Negative):
        return (node.operand,)
    if isinstance(node, Sum | Product):
        return tuple(part for _, part in node.parts)
    if isinstance(node, Power):
        return (node.base, node.exponent)
    return ()


def own_variables(expression: Expression, target: str) -> Expression:
    """A relation's right-hand side as read (e, f, q, p as parameter names) with those
    names made the signals of the component `target`."""

    def convert(node: Node) -> Node:
        if isinstance(node, Name) and node.name in IMPOSES_EFFORT:
            return Signal(node.position, node.name, target)
        return _map(node, convert)

    own = [u for u in expression.names if u.name in IMPOSES_EFFORT]
    return Expression(
        convert(expression.tree),
        tuple(u for u in expression.names if u.name not in IMPOSES_EFFORT),
        expression.position,
        tuple(SignalUse(u.name, target, u.position) for u in own) + expression.signals,
        None,
        expression.measure,
    )


def written(relations: list[tuple[str, Position, Expression]], target: str) -> tuple[Relation, ...]:
    """The relations of the component `target` as read: (variable, its place, expression)."""
    return tuple(
        Relation(variable, own_variables(value, target), where)
        for variable, where, value in relations
    )


# Linearity -------------------------------------------------------------------------


def _degree(node: Node) -> int | None:
    """0 when no own variable (signal) occurs, 1 when the node is a constant times one,
    None otherwise (a sum of a constant and a variable term is None: affine is not linear)."""
    if isinstance(node, Signal):
        return 1
    if isinstance(node, Negative):
        return _degree(node.operand)
    if isinstance(node, Sum):
        degrees = {_degree(part) for _, part in node.parts}
        return degrees.pop() if len(degrees) == 1 else None
    if isinstance(node, Product):
        total = 0
        for divides, part in node.parts:
            degree = _degree(part)
            if degree is None or (divides and degree):
                return None
            total += degree
        return total if total <= 1 else None
    if isinstance(node, Power):
        base, exponent = _degree(node.base), _degree(node.exponent)
        if base == 0 and exponent == 0:
            return 0
        one = isinstance(node.exponent, Number) and node.exponent.value == 1
        return 1 if base == 1 and exponent == 0 and one else None
    if isinstance(node, Call):
        return 0 if all(_degree(a) == 0 for a in node.arguments) else None
    return 0


def _at(node: Node, value: Fraction) -> Node:
    """The tree with every own variable replaced by a number."""
    if isinstance(node, Signal):
        return Number(node.position, value)
    return _map(node, lambda child: _at(child, value))


def _names(node: Node) -> tuple[NameUse, ...]:
    if isinstance(node, Name):
        return (NameUse(node.name, node.position),)
    return tuple(use for child in _children(node) for use in _names(child))


def _expression(node: Node, position: Position) -> Expression:
    return Expression(node, _names(node), position, _signals(node))


def _signals(node: Node) -> tuple[SignalUse, ...]:
    if isinstance(node, Signal):
        return (SignalUse(node.kind, node.target, node.position),)
    return tuple(use for child in _children(node) for use in _signals(child))


def _reciprocal(node: Node) -> Node:
    one = Number(node.position, Fraction(1))
    return Product(node.position, ((False, one), (True, node)))


def linear_parameter(relation: Relation, ratio: tuple[str, str]) -> Expression | None:
    """The parameter k of the linear component (`ratio` (y, x): y = k x; R: e = r f, C:
    q = c e, I: p = i f) when the relation is linear through the origin, else None."""
    tree = relation.expression.tree
    if _degree(tree) != 1:
        return None
    at_one = _at(tree, Fraction(1))
    value = at_one if relation.variable == ratio[0] else _reciprocal(at_one)
    return _expression(value, relation.expression.position)


# Inverses ------------------------------------------------------------------------


def _occurrences(node: Node) -> int:
    if isinstance(node, Signal):
        return 1
    return sum(_occurrences(child) for child in _children(node))


def _affine(node: Node) -> bool:
    """Whether the node is a + b x in its own variable x (x may occur several times)."""
    if isinstance(node, Negative):
        return _affine(node.operand)
    if isinstance(node, Sum):
        return all(_affine(part) for _, part in node.parts)
    if isinstance(node, Product):
        variable = [(d, p) for d, p in node.parts if _occurrences(p)]
        return len(variable) == 1 and not variable[0][0] and _affine(variable[0][1])
    return isinstance(node, Signal) or not _occurrences(node)


def _unsaturated(y: Node, at: Position) -> Node:
    """The inverse of sat(x) = x / sqrt(1 + x^2): y / sqrt(1 - y^2)."""
    one, two = Number(at, Fraction(1)), Number(at, Fraction(2))
    root = Call(at, "sqrt", (Sum(at, ((False, one), (True, Power(at, y, two)))),))
    return Product(at, ((False, y), (True, root)))


def _nonnegative(y: Node, at: Position) -> Node:
    return y


def _within_one(y: Node, at: Position) -> Node:
    """1 - y^2, which is >= 0 where -1 <= y <= 1."""
    square = Power(at, y, Number(at, Fraction(2)))
    return Sum(at, ((False, Number(at, Fraction(1))), (True, square)))


# each function's inverse, applied to the value y, where it holds (in terms of y, and as
# an expression >= 0 there, when there is one)
_UNDO = {
    "sqrt": (lambda y, at: Power(at, y, Number(at, Fraction(2))), "{y} >= 0", _nonnegative),
    "exp": (lambda y, at: Call(at, "log", (y,)), "{y} > 0", _nonnegative),
    "log": (lambda y, at: Call(at, "exp", (y,)), None, None),
    "sin": (lambda y, at: Call(at, "asin", (y,)), "-1 <= {y} <= 1, {x} in [-pi/2, pi/2]",
            _within_one),
    "cos": (lambda y, at: Call(at, "acos", (y,)), "-1 <= {y} <= 1, {x} in [0, pi]", _within_one),
    "tan": (lambda y, at: Call(at, "atan", (y,)), "{x} in (-pi/2, pi/2)", None),
    "tanh": (lambda y, at: Call(at, "atanh", (y,)), "-1 < {y} < 1", _within_one),
    "atan": (lambda y, at: Call(at, "tan", (y,)), "-pi/2 < {y} < pi/2", None),
    "sat": (lambda y, at: _unsaturated(y, at), "-1 < {y} < 1", _within_one),
}  # fmt: skip


class _NoInverse(Exception):
    """The function (or the shape) that has no exact inverse."""


def _peel(node: Node, y: Node, domain: list[str], conditions: list[Node]) -> Node:
    """The own variable x (which occurs once in `node`) from y = node."""
    if isinstance(node, Signal):
        return y
    at = node.position
    if isinstance(node, Negative):
        return _peel(node.operand, Negative(at, y), domain, conditions)
    if isinstance(node, Sum | Product):
        k = next(i for i, (_, part) in enumerate(node.parts) if _occurrences(part))
        inverse, part = node.parts[k]
        others = [(not flag, p) for i, (flag, p) in enumerate(node.parts) if i != k]
        if isinstance(node, Sum):
            rest = Sum(at, ((False, y), *others))
            return _peel(part, Negative(at, rest) if inverse else rest, domain, conditions)
        if inverse:  # y = others / part: part = others / y
            rest = Product(at, ((False, Number(at, Fraction(1))), *[(not f, p) for f, p in others],
                                (True, y)))  # fmt: skip
        else:
            rest = Product(at, ((False, y), *others))
        return _peel(part, rest, domain, conditions)
    if isinstance(node, Power):
        if _occurrences(node.exponent):
            raise _NoInverse("a variable in an exponent")
        root = Power(at, y, _reciprocal(node.exponent))
        domain.append(f"{text(bare(y))} >= 0")
        conditions.append(y)
        return _peel(node.base, root, domain, conditions)
    if isinstance(node, Call) and node.function in _UNDO:
        undo, where, condition = _UNDO[node.function]
        if where:
            domain.append(where.format(y=text(bare(y)), x=text(bare(node.argument))))
        if condition:
            conditions.append(condition(y, at))
        return _peel(node.argument, undo(y, at), domain, conditions)
    name = node.function if isinstance(node, Call) else type(node).__name__
    raise _NoInverse(f"{name} has no inverse")


def inverse(relation: Relation, variable: str) -> Relation | None:
    """The relation solved for its own `variable` (the one its right-hand side uses), exactly,
    or None when there is no exact inverse."""
    tree = relation.expression.tree
    at = relation.expression.position
    target = relation.target
    occurrences = _occurrences(tree)
    if not occurrences or not target:
        return None
    y = Signal(relation.position, relation.variable, target)
    domain: list[str] = []
    conditions: list[Node] = []
    if occurrences == 1:
        try:
            solved = _peel(tree, y, domain, conditions)
        except _NoInverse:
            return None
    elif _affine(tree):  # x = (y - a) / b with a = rhs(0), b = rhs(1) - rhs(0)
        a, b = _at(tree, Fraction(0)), _at(tree, Fraction(1))
        slope = Sum(at, ((False, b), (True, a)))
        solved = Product(at, ((False, Sum(at, ((False, y), (True, a)))), (True, slope)))
        domain.append(f"{text(bare(slope))} != 0")
    else:
        return None
    return Relation(
        variable,
        _expression(solved, at),
        relation.position,
        True,
        tuple(domain),
        tuple(_expression(c, at) for c in conditions),
    )


@dataclass(frozen=True)
class Constitutive:
    """A component's relation as given (one, or two: the second the inverse of the first),
    with the variables the component relates (its type's `relates`)."""

    given: tuple[Relation, ...]
    relates: tuple[str, str]

    @property
    def position(self) -> Position:
        return self.given[0].position

    def text(self) -> str:
        return ", ".join(r.text() for r in self.given)

    def giving(self, variable: str) -> Relation | None:
        """The relation that yields `variable`: as given, or the first relation inverted."""
        for relation in self.given:
            if relation.variable == variable:
                return relation
        (other,) = (v for v in self.relates if v != variable)
        first = next((r for r in self.given if r.variable == other), None)
        return None if first is None else inverse(first, variable)

    def serves(self) -> frozenset[bool]:
        """The causalities (imposes effort or not) it can serve."""
        return frozenset(IMPOSES_EFFORT[v] for v in self.relates if self.giving(v) is not None)
