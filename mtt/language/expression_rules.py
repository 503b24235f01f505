"""The grammar's expression rules: parse tree -> `Expression` trees, within the limits.

Rational numbers are folded exactly (fractions) as they are read; every other node is
measured (`Measure`): its nesting depth and size, bounds on its degree, terms and digits
once expanded, and a float value of constants that are not rational. Untrusted text must
not ask the later stages (sympy, the derivation) for unbounded work, so these limits are
checked here, before sympy ever sees an expression, and reported at their place:

* numbers: at most `MAX_DIGITS` digits in a numerator or denominator (`1e999999999`,
  `10^10^10`), roots and functions of numbers of at most `MAX_ROOT_DIGITS` digits;
* nesting at most `MAX_DEPTH` deep, at most `MAX_SIZE` numbers, names and operators;
* degree in the names and constants at most `MAX_DEGREE` (`k^500`), at most `MAX_TERMS`
  terms once expanded (`(a+b+c+d+e)^100`);
* constants that are not rational (pi, roots, functions) at most `MAX_MAGNITUDE` in size
  (`exp(exp(exp(9)))`), `exp` of at most `MAX_EXP_ARGUMENT` (`exp(1e100)`).

Lark's tree is transformed without recursion (`Transformer_NonRecursive`): a line of ten
thousand minus signs is a located error, not a crash.
"""

from __future__ import annotations

import math
from fractions import Fraction

from lark import Token, Transformer_NonRecursive

from mtt.language.diagnostics import Diagnostic, Position, error
from mtt.language.expressions import (
    CONSTANTS,
    FUNCTIONS,
    SIGNALS,
    Call,
    Constant,
    Expression,
    Measure,
    Name,
    NameUse,
    Negative,
    Number,
    Placeholder,
    Power,
    Product,
    Signal,
    SignalProblem,
    SignalUse,
    Sum,
)

MAX_DIGITS = 4000  # below the 4300 digits CPython converts between int and str by default
MAX_ROOT_DIGITS = 100  # sympy looks for perfect powers and factors of a root's argument
MAX_DEPTH = 100
MAX_SIZE = 1000
MAX_DEGREE = 100
MAX_TERMS = 10_000
MAX_MAGNITUDE = 1e300
MAX_EXP_ARGUMENT = 690  # exp(690) ~ 1e300


class _Problem(Exception):
    """A limit or an undefined value, met while measuring a node: kind, message, place."""

    def __init__(self, kind: str, message: str, position: Position):
        super().__init__(message)
        self.kind, self.position = kind, position


def _number(text: str) -> Fraction:
    mantissa, _, exponent = text.lower().partition("e")
    if len(mantissa) > MAX_DIGITS:
        raise ValueError("number has too many digits")
    sign = -1 if exponent.startswith("-") else 1
    exponent = exponent.lstrip("+-").lstrip("0") or "0"
    if len(exponent) > len(str(MAX_DIGITS)):
        raise ValueError("number out of range")
    return Fraction(mantissa) * Fraction(10) ** (sign * int(exponent))


def _log10(value: int) -> float:
    return math.log10(abs(value)) if value else 0.0


def _exact(value: Fraction) -> Measure:
    return Measure(exact=value, digits=(_log10(value.numerator), _log10(value.denominator)), size=1)


def _digits(value: Fraction) -> float:
    return max(_log10(value.numerator), _log10(value.denominator))


def _float(value: Fraction | None, approx: float | None) -> float | None:
    if value is None:
        return approx
    try:
        return float(value)
    except OverflowError:
        return math.inf if value > 0 else -math.inf


def _root(value: int, order: int) -> int | None:
    """The exact integer `order`-th root of a non-negative integer, if there is one."""
    guess = round(value ** (1 / order)) if value < 1 << 1000 else None
    if guess is None:
        return None
    for candidate in (guess - 1, guess, guess + 1):
        if candidate >= 0 and candidate**order == value:
            return candidate
    return None


def _exact_power(base: Fraction, exponent: Fraction) -> Fraction | None:
    """base^(p/q) when it is rational (a perfect q-th power), else None."""
    p, q = exponent.numerator, exponent.denominator
    num, den = _root(base.numerator, q), _root(base.denominator, q)
    if num is None or den is None:
        return None
    return Fraction(num, den) ** p


def _multisets(terms: int, power: int) -> int:
    """Terms of a sum of `terms` terms raised to `power`, at most, expanded (or just over
    `MAX_TERMS`, when they are more: not computed)."""
    if terms <= 1 or power == 0:
        return 1
    log = math.lgamma(power + terms) - math.lgamma(power + 1) - math.lgamma(terms)
    if log > math.log(MAX_TERMS) + 1:
        return MAX_TERMS + 1
    return math.comb(power + terms - 1, terms - 1)


def _first_problem(*parts: Expression) -> SignalProblem | None:
    return next((p.signal_problem for p in parts if p.signal_problem), None)


def _nonlinear(message: str, *parts: Expression) -> SignalProblem | None:
    """Where `parts` take no signal at all (a function's argument, a power, a denominator):
    the problem is their first signal, or else any problem inside them."""
    signals = [s for p in parts for s in p.signals]
    return SignalProblem(message, signals[0].position) if signals else _first_problem(*parts)


def _sum_problem(a: Expression, b: Expression) -> SignalProblem | None:
    """A sum stays linear unless it adds a (nonzero) constant term to signal terms."""
    first = _first_problem(a, b)
    if first is not None or bool(a.signals) == bool(b.signals):
        return first
    constant = b if a.signals else a
    if constant.exact == 0:
        return None
    return SignalProblem(
        "a constant term: every term must be a coefficient times one signal",
        constant.position,
    )


def _product_problem(a: Expression, b: Expression) -> SignalProblem | None:
    """A product stays linear when at most one factor holds signals."""
    first = _first_problem(a, b)
    if first is None and a.signals and b.signals:
        return SignalProblem("a product of signals", b.signals[0].position)
    return first


def _combined(operator: str, a: Measure, b: Measure, chained: bool) -> Measure:
    """The measure of `a operator b` (+ - * /), not both rational numbers; `chained`: a
    is a chain of the same operators, which b extends (a chain is one node, not nested)."""
    (an, ad), (bn, bd) = a.degree, b.degree
    (tan, tad), (tbn, tbd) = a.terms, b.terms
    (dan, dad), (dbn, dbd) = a.digits, b.digits
    if operator in "+-":  # (an bd + bn ad) / (ad bd)
        degree = (max(an + bd, bn + ad), ad + bd)
        terms = (tan * tbd + tbn * tad, tad * tbd)
        digits = (max(dan + dbd, dbn + dad) + math.log10(2), dad + dbd)
    elif operator == "*":
        degree = (an + bn, ad + bd)
        terms = (tan * tbn, tad * tbd)
        digits = (dan + dbn + math.log10(min(tan, tbn)), dad + dbd + math.log10(min(tad, tbd)))
    else:  # (an bd) / (ad bn)
        degree = (an + bd, ad + bn)
        terms = (tan * tbd, tad * tbn)
        digits = (dan + dbd + math.log10(min(tan, tbd)), dad + dbn + math.log10(min(tad, tbn)))
    approx = None
    x, y = _float(a.exact, a.approx), _float(b.exact, b.approx)
    if x is not None and y is not None:
        try:
            approx = {"+": x + y, "-": x - y, "*": x * y}[operator] if operator != "/" else x / y
        except ZeroDivisionError:
            approx = None  # decided exactly later (an irrational may be zero after all)
    return Measure(
        approx=approx,
        degree=degree,
        terms=terms,
        digits=digits,
        depth=max(a.depth if chained else a.depth + 1, b.depth + 1),
        size=a.size + b.size + 1,
    )


def _power_measure(base: Measure, exponent: Measure) -> Measure:
    """The measure of base^exponent, not both rational numbers."""
    n = exponent.exact
    depth, size = max(base.depth, exponent.depth) + 1, base.size + exponent.size + 1
    approx = None
    x, y = _float(base.exact, base.approx), _float(exponent.exact, exponent.approx)
    if x is not None and y is not None and (x > 0 or (n is not None and n.denominator == 1)):
        try:
            approx = x**y
        except OverflowError:
            approx = math.inf
        except ZeroDivisionError:
            approx = None
    if n is not None and n.denominator == 1 and abs(n) <= MAX_DIGITS:
        power = abs(int(n))
        (bn, bd), (tn, td), (dn, dd) = base.degree, base.terms, base.digits
        if n < 0:
            bn, bd, tn, td, dn, dd = bd, bn, td, tn, dd, dn
        return Measure(
            approx=approx,
            degree=(power * bn, power * bd),
            terms=(_multisets(tn, power), _multisets(td, power)),
            digits=(power * (dn + math.log10(tn)), power * (dd + math.log10(td))),
            depth=depth,
            size=size,
        )
    if n is not None and abs(n) > MAX_DIGITS:  # a huge power of anything but 0, 1 and -1
        degree = MAX_DEGREE + 1
    elif n is not None:  # a root: a new atom, of the degree of its integer part at most
        degree = math.ceil(abs(n)) * max(sum(base.degree), 1)
    else:
        degree = 1
    return Measure(approx=approx, degree=(degree, 0), depth=depth, size=size)


class ExpressionRules(Transformer_NonRecursive):
    """The expression rules of the grammar; `problems` collects positioned errors.

    `line` is the line the text being transformed starts on (the parser reads one line
    at a time).
    """

    def __init__(self, problems: list[Diagnostic], line: int = 1):
        super().__init__()
        self.problems = problems
        self.first_line = line

    def at(self, token: Token) -> Position:
        return Position(token.line + self.first_line - 1, token.column)

    def _report(self, kind: str, message: str, position: Position, *parts: Expression):
        """A problem at `position`: a placeholder stands for the expression from now on."""
        self.problems.append(error(kind, message, position))
        return self._placeholder(position, *parts)

    @staticmethod
    def _placeholder(position: Position, *parts: Expression) -> Expression:
        names = tuple(u for p in parts for u in p.names)
        signals = tuple(u for p in parts for u in p.signals)
        return Expression(Placeholder(position), names, position, signals, _first_problem(*parts))

    @staticmethod
    def _broken(*parts: Expression) -> bool:
        return any(isinstance(p.tree, Placeholder) for p in parts)

    def _checked(self, node, measure: Measure, parts, problem, where=None):
        """The expression of `node`, unless its measure is beyond a limit (then reported
        at `where`, by default at the node)."""
        names = tuple(u for p in parts for u in p.names)
        signals = tuple(u for p in parts for u in p.signals)
        expression = Expression(node, names, node.position, signals, problem, measure)
        try:
            self._limits(measure, where or node.position)
        except _Problem as problem_:
            return self._report(problem_.kind, str(problem_), problem_.position, *parts)
        return expression

    @staticmethod
    def _limits(m: Measure, position: Position) -> None:
        if m.depth > MAX_DEPTH:
            raise _Problem(
                "syntax", f"expression nested more than {MAX_DEPTH} deep (a limit)", position
            )
        if m.size > MAX_SIZE:
            raise _Problem(
                "syntax",
                f"expression of more than {MAX_SIZE} numbers, names and operators (a limit)",
                position,
            )
        if max(m.degree) > MAX_DEGREE:
            raise _Problem(
                "syntax",
                f"out of range: degree above {MAX_DEGREE} in the parameters and constants",
                position,
            )
        if max(m.terms) > MAX_TERMS:
            raise _Problem(
                "syntax",
                f"expression out of range: more than {MAX_TERMS} terms once expanded",
                position,
            )
        if max(m.digits) > MAX_DIGITS:
            raise _Problem("syntax", "number out of range", position)
        if m.approx is not None and not abs(m.approx) <= MAX_MAGNITUDE and not math.isnan(m.approx):
            raise _Problem(
                "syntax", f"value out of range (beyond {MAX_MAGNITUDE:g} in size)", position
            )

    def _fold(self, value: Fraction, position: Position, *parts: Expression) -> Expression:
        if _digits(value) > MAX_DIGITS:
            return self._report("syntax", "number out of range", position, *parts)
        problem = _first_problem(*parts)
        signals = tuple(u for p in parts for u in p.signals)
        return Expression(Number(position, value), (), position, signals, problem, _exact(value))

    # leaves

    def number(self, children):
        (token,) = children
        try:
            value = _number(str(token))
        except ValueError as problem:
            return self._report("syntax", str(problem), self.at(token))
        return self._fold(value, self.at(token))

    def name(self, children):
        (token,) = children
        where = self.at(token)
        if str(token) in CONSTANTS:
            return Expression(
                Constant(where, str(token)),
                (),
                where,
                measure=Measure(approx=math.pi, degree=(1, 0)),
            )
        return Expression(Name(where, str(token)), (NameUse(str(token), where),), where)

    def _signal(self, token: Token, target: str | None, where: Position) -> Expression:
        if target is None:
            problem = SignalProblem(
                f"{token}(...) reads a signal: its argument is a component's name", where
            )
            return Expression(Placeholder(self.at(token)), (), self.at(token), (), problem)
        use = SignalUse(str(token), target, self.at(token))
        return Expression(Signal(use.position, use.kind, target), (), use.position, (use,))

    # functions

    def call(self, children):
        token, argument = children
        where = self.at(token)
        if str(token) in SIGNALS:
            bare = isinstance(argument.tree, Name) and not argument.signals
            return self._signal(token, argument.tree.name if bare else None, argument.position)
        if str(token) not in FUNCTIONS:
            known = " ".join(FUNCTIONS)
            self.problems.append(
                error("syntax", f"unknown function {str(token)!r} (known: {known})", where)
            )
            return argument
        if self._broken(argument):
            return self._placeholder(where, argument)
        problem = _nonlinear("a signal inside a function", argument)
        function = str(token)
        try:
            folded = self._function_value(function, argument.measure, where)
        except _Problem as problem_:
            return self._report(problem_.kind, str(problem_), problem_.position, argument)
        if folded is not None:
            return self._fold(folded, where, argument)
        try:
            approx = self._function_approx(function, argument.measure, where)
        except _Problem as problem_:
            return self._report(problem_.kind, str(problem_), problem_.position, argument)
        measure = Measure(
            approx=approx,
            degree=(1, 0),
            depth=argument.measure.depth + 1,
            size=argument.measure.size + 1,
        )
        return self._checked(Call(where, function, argument.tree), measure, [argument], problem)

    @staticmethod
    def _function_value(function: str, m: Measure, where: Position) -> Fraction | None:
        """The rational value of a function of a rational number, when there is one; raise
        `_Problem` for an argument out of range or outside the function's domain."""
        value = m.exact
        if value is None:
            return None
        if _digits(value) > MAX_ROOT_DIGITS:
            raise _Problem("syntax", f"argument of {function} out of range", where)
        if function == "sqrt":
            if value < 0:
                raise _Problem(
                    "bad_value", f"sqrt({value}) is not a real number (a negative argument)", where
                )
            return _exact_power(value, Fraction(1, 2))
        if function == "log":
            if value == 0:
                raise _Problem("syntax", "the value is undefined or infinite (log(0))", where)
            if value < 0:
                raise _Problem(
                    "bad_value", f"log({value}) is not a real number (a negative argument)", where
                )
            return Fraction(0) if value == 1 else None
        if function == "exp" and abs(value) > MAX_EXP_ARGUMENT:
            raise _Problem(
                "syntax",
                f"argument of exp out of range (at most {MAX_EXP_ARGUMENT} in size)",
                where,
            )
        if value == 0:
            return Fraction(0) if function == "sin" else Fraction(1)
        return None

    @staticmethod
    def _function_approx(function: str, m: Measure, where: Position) -> float | None:
        x = _float(m.exact, m.approx)
        if x is None:
            return None
        if function == "exp" and abs(x) > MAX_EXP_ARGUMENT:
            raise _Problem(
                "syntax",
                f"argument of exp out of range (at most {MAX_EXP_ARGUMENT} in size)",
                where,
            )
        if function in ("sqrt", "log") and x <= 0:
            return None  # an irrational argument's sign is decided exactly, later
        if function in ("sin", "cos") and abs(x) > MAX_MAGNITUDE:
            return None
        return getattr(math, function)(x)

    def signal_path(self, children):
        """`e(a.b)`: a signal of a subsystem's component; other calls take no dotted name."""
        token, path = children
        if str(token) in SIGNALS:
            return self._signal(token, str(path), self.at(path))
        return self._report(
            "syntax",
            f"{path}: a dotted name only names a signal, in e(...) or f(...)",
            self.at(path),
        )

    # operators

    def _binary(self, operator: str, a: Expression, b: Expression, problem) -> Expression:
        if self._broken(a, b):
            return self._placeholder(a.position, a, b)
        if a.exact is not None and b.exact is not None:
            x, y = a.exact, b.exact  # y is not 0 in a division: see `div`
            value = {"+": x + y, "-": x - y, "*": x * y}[operator] if operator != "/" else x / y
            return self._fold(value, a.position, a, b)
        kind = Sum if operator in "+-" else Product
        inverse = operator in "-/"
        chained = isinstance(a.tree, kind)
        parts = (
            a.tree.terms
            if kind is Sum and chained
            else (a.tree.factors if chained else ((False, a.tree),))
        )
        node = kind(a.position, (*parts, (inverse, b.tree)))
        measure = _combined(operator, a.measure, b.measure, chained)
        return self._checked(node, measure, [a, b], problem)

    def add(self, children):
        a, b = children
        return self._binary("+", a, b, _sum_problem(a, b))

    def sub(self, children):
        a, b = children
        return self._binary("-", a, b, _sum_problem(a, b))

    def mul(self, children):
        a, b = children
        return self._binary("*", a, b, _product_problem(a, b))

    def div(self, children):
        a, b = children
        if b.exact == 0:
            self.problems.append(error("syntax", "division by zero", b.position))
            return a
        problem = _first_problem(a) or _nonlinear("a signal in a denominator", b)
        return self._binary("/", a, b, problem)

    def neg(self, children):
        (a,) = children
        if a.exact is not None:
            return self._fold(-a.exact, a.position, a)
        if self._broken(a):
            return a
        m = a.measure
        measure = Measure(
            approx=None if m.approx is None else -m.approx,
            degree=m.degree,
            terms=m.terms,
            digits=m.digits,
            depth=m.depth + 1,
            size=m.size + 1,
        )
        return self._checked(Negative(a.position, a.tree), measure, [a], a.signal_problem)

    def pow(self, children):
        base, operator, exponent = children
        where = self.at(operator)
        if self._broken(base, exponent):
            return self._placeholder(base.position, base, exponent)
        problem = _nonlinear("a signal in a power", base, exponent)
        b, x = base.exact, exponent.exact
        if b is not None and x is not None:
            try:
                value = self._rational_power(b, x, where)
            except _Problem as problem_:
                return self._report(problem_.kind, str(problem_), problem_.position, base, exponent)
            if value is not None:
                return self._fold(value, base.position, base, exponent)
        node = Power(base.position, base.tree, exponent.tree)
        measure = _power_measure(base.measure, exponent.measure)
        return self._checked(node, measure, [base, exponent], problem, where)

    @staticmethod
    def _rational_power(b: Fraction, x: Fraction, where: Position) -> Fraction | None:
        """b^x for rational b and x: its rational value, or None for an irrational root;
        raise `_Problem` when it is out of range, undefined or not real."""
        out_of_range = _Problem("syntax", "power out of range", where)
        if b == 0 and x < 0:
            raise _Problem("syntax", "power out of range: 0 to a negative power", where)
        if b in (0, 1) or (b == -1 and x.denominator == 1):
            return b ** int(x) if x.denominator == 1 else b
        if abs(x) > MAX_DIGITS / _digits(b):  # b is not 0, 1 or -1: it has digits
            raise out_of_range
        if x.denominator == 1:
            return b ** int(x)
        if b < 0:
            raise _Problem(
                "bad_value",
                f"({b})^({x}) is not a real number (a negative number to a fractional power)",
                where,
            )
        if _digits(b) > MAX_ROOT_DIGITS or x.denominator > MAX_DEGREE:
            raise out_of_range
        return _exact_power(b, x)

    def expression(self, children):
        (partial,) = children
        return partial
