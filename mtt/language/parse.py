"""Stage 1: text -> parse tree -> `ParsedModel`.

The grammar in `grammars/bg.lark` is run by lark, one line at a time (no statement
spans lines: each line's errors are found on their own, and the work is linear in the
file's length); a transformer turns each line's tree into frozen dataclasses with
source positions. Expressions become small trees of their own (`expressions`), exact
and measured against the limits of the implementation; no text from a model ever
reaches eval, exec, sympify or parse_expr, and this stage does not import sympy.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import cache
from typing import TYPE_CHECKING

import lark
from lark import Token

from mtt.language.diagnostics import Diagnostic, ModelError, Position, Source, error
from mtt.language.expression_rules import MAX_DIGITS, ExpressionRules
from mtt.language.expressions import LAPLACE, RESERVED, Expression, NameUse, SignalUse
from mtt.language.relations import Relation, written
from mtt.language.syntax_messages import syntax_message
from mtt.resources import resource_dir

if TYPE_CHECKING:
    import sympy

__all__ = ["LAPLACE", "MAX_DIGITS", "RESERVED", "Expression", "NameUse", "SignalUse"]

MAX_SYNTAX_ERRORS = 50
MAX_LINE = 10_000  # characters: lark reads some 100000 a second
MAX_BONDS = 5_000  # in a model, subsystems included: the derivation's work grows with them
# lines of statements in a file: lark takes about 0.1 ms a line, so that a file of a megabyte
# (some 80000 short lines) took 10 to 100 s; blank lines and comments do not count
MAX_STATEMENTS = 2 * MAX_BONDS
_BLANK = re.compile(r"[ \t\f\r\ufeff]*(?:#.*)?")  # what the grammar ignores: no statement


@dataclass(frozen=True)
class ComponentUse:
    """One mention of `TYPE:NAME [(EXPR)]` or `TYPE:NAME (VAR = EXPR[, ...])`, anywhere."""

    type: str
    name: str
    argument: Expression | None
    position: Position
    relations: tuple[Relation, ...] = ()  # a constitutive relation (and its inverse)

    @property
    def label(self) -> str:
        return f"{self.type}:{self.name}"


@dataclass(frozen=True)
class ModelHeader:
    name: str
    description: str | None
    position: Position


@dataclass(frozen=True)
class ParameterDecl:
    name: str
    value: Expression | None
    description: str | None
    unknown: bool
    position: Position


@dataclass(frozen=True)
class ComponentDecl:
    use: ComponentUse
    description: str | None


@dataclass(frozen=True)
class PortUse:
    """`NAME.PORT` as a bond's end: the port PORT (an `SS:PORT`) of the subsystem NAME."""

    subsystem: str
    port: str
    position: Position

    @property
    def name(self) -> str:
        return f"{self.subsystem}.{self.port}"

    label = name


@dataclass(frozen=True)
class BondText:
    """`tail -> head`: positive power flows from tail to head."""

    tail: ComponentUse | PortUse
    head: ComponentUse | PortUse
    position: Position


@dataclass(frozen=True)
class Binding:
    """`p = EXPR` in a subsystem statement: the child's parameter p, set in the parent."""

    name: str
    value: Expression
    position: Position


@dataclass(frozen=True)
class SubsystemDecl:
    """`subsystem NAME = "FILE.bg" [(p = EXPR, ...)] ["description"]`."""

    name: str
    file: str  # as written, relative to the including file's directory
    bindings: tuple[Binding, ...]
    description: str | None
    position: Position  # of the name


@dataclass(frozen=True)
class PortDecl:
    """An `input` or `output` statement."""

    role: str
    type: str
    name: str  # dotted for a subsystem's component
    position: Position | None  # None for a choice made on the command line


@dataclass(frozen=True)
class ParsedModel:
    source: Source
    header: ModelHeader | None
    parameters: tuple[ParameterDecl, ...]
    declarations: tuple[ComponentDecl, ...]
    bonds: tuple[BondText, ...]
    ports: tuple[PortDecl, ...]
    subsystems: tuple[SubsystemDecl, ...] = ()

    @property
    def mentions(self) -> tuple[ComponentUse, ...]:
        """Every component mention (not the subsystems' ports), in file order."""
        uses = [d.use for d in self.declarations]
        for bond in self.bonds:
            uses += [end for end in (bond.tail, bond.head) if isinstance(end, ComponentUse)]
        return tuple(sorted(set(uses), key=lambda u: u.position))


@cache
def _parser() -> lark.Lark:
    grammar = (resource_dir("grammars") / "bg.lark").read_text(encoding="utf-8")
    return lark.Lark(grammar, start=["line", "expression"], parser="lalr")


class _ToModel(ExpressionRules):
    """Bottom-up: tokens and subtrees to expressions and statement records."""

    # statements
    @staticmethod
    def _text(token: Token | None) -> str | None:
        return None if token is None else str(token)[1:-1]

    def model_stmt(self, children):
        name, description = children
        return ModelHeader(str(name), self._text(description), self.at(name))

    def _parameter(self, children, unknown: bool):
        name, value, description = children
        return ParameterDecl(str(name), value, self._text(description), unknown, self.at(name))

    def param_stmt(self, children):
        return self._parameter(children, unknown=False)

    def unknown_stmt(self, children):
        return self._parameter(children, unknown=True)

    def relation(self, children):
        variable, value = children
        return str(variable), self.at(variable), value

    def relations(self, children):
        return [child for child in children if child is not None]

    def component(self, children):
        token, *given = children  # an argument, relations, or nothing
        argument = given[0] if given else None
        type_, _, name = str(token).partition(":")
        if isinstance(argument, list):  # (variable, its place, the expression), in order
            return ComponentUse(type_, name, None, self.at(token), written(argument, name))
        if "." in name:
            self.problems.append(
                error(
                    "syntax",
                    f"{token}: a subsystem's component is reached only through its ports "
                    "(NAME.PORT); dotted names are for input, output and signals",
                    self.at(token),
                )
            )
        return ComponentUse(type_, name, argument, self.at(token))

    def port_use(self, children):
        (token,) = children
        subsystem, _, port = str(token).partition(".")
        if "." in port:
            self.problems.append(
                error(
                    "syntax",
                    f"{token}: a bond reaches a subsystem through one of its own ports, NAME.PORT",
                    self.at(token),
                )
            )
        return PortUse(subsystem, port, self.at(token))

    def binding(self, children):
        name, value = children
        return Binding(str(name), value, self.at(name))

    def bindings(self, children):
        return tuple(children)

    def subsystem_stmt(self, children):
        name, file, bindings, description = children
        return SubsystemDecl(
            str(name), self._text(file), bindings or (), self._text(description), self.at(name)
        )

    def declaration(self, children):
        use, description = children
        return ComponentDecl(use, self._text(description))

    def bonds(self, children):
        uses = children[::2]
        arrows = children[1::2]
        return [
            BondText(tail, head, self.at(arrow))
            for tail, head, arrow in zip(uses, uses[1:], arrows, strict=False)
        ]

    def _port(self, children, role: str):
        (token,) = children
        type_, _, name = str(token).partition(":")
        return PortDecl(role, type_, name, self.at(token))

    def input_stmt(self, children):
        return self._port(children, "input")

    def output_stmt(self, children):
        return self._port(children, "output")


_BRACKETED_PORT = re.compile(r"\bSS\s*:\s*\[\s*([A-Za-z_][A-Za-z0-9_]*)\s*\]")


def _statements(source: Source) -> tuple[list, list[Diagnostic]]:
    """Every statement of the file, each line parsed on its own, and every syntax error
    (up to `MAX_SYNTAX_ERRORS`)."""
    parser = _parser()
    statements: list = []
    problems: list[Diagnostic] = []
    bonds = lines = 0
    for number, line in enumerate(source.lines, start=1):
        if len(problems) >= MAX_SYNTAX_ERRORS:
            break
        if _BLANK.fullmatch(line):  # blank or a comment: the parser would find nothing
            continue
        lines += 1
        if lines > MAX_STATEMENTS:
            message = (
                f"more than {MAX_STATEMENTS} lines of statements (a limit): the rest is not read"
            )
            problems.append(error("too_large", message, Position(number, 1)))
            break
        if len(line) > MAX_LINE:
            problems.append(
                error(
                    "syntax",
                    f"a line longer than {MAX_LINE} characters (a limit)",
                    Position(number, MAX_LINE + 1),
                )
            )
            continue
        try:
            tree = parser.parse(line + "\n", start="line")
        except lark.exceptions.UnexpectedInput as exc:
            column = exc.column if exc.line > 0 else len(line) + 1
            message = syntax_message(exc, parser)
            bracketed = _BRACKETED_PORT.search(line)
            if bracketed:  # MTT's own syntax for a port
                column = bracketed.start() + 1
                message = (
                    f"{bracketed.group(0)} is MTT's bracketed port: here a subsystem's port is "
                    f"written SS:{bracketed.group(1)} (see the language guide, subsystems)"
                )
            problems.append(error("syntax", message, Position(number, column)))
            continue
        for item in _ToModel(problems, number).transform(tree).children:
            statements.extend(item if isinstance(item, list) else [item])
            bonds += len(item) if isinstance(item, list) else 0  # a chain of bonds
        if bonds > MAX_BONDS:
            message = f"more than {MAX_BONDS} bonds (a limit): the rest is not read"
            problems.append(error("too_large", message, Position(number, 1)))
            break
    return statements, problems


def parse(source: Source) -> ParsedModel:
    """Read a model's text; raise `ModelError` with every syntax error found."""
    statements, problems = _statements(source)
    header = None
    for index, statement in enumerate(statements):
        if isinstance(statement, ModelHeader):
            if header is not None:
                problems.append(error("syntax", "a second 'model' line", statement.position))
            elif index > 0:
                problems.append(
                    error(
                        "syntax", "the 'model' line must be the first statement", statement.position
                    )
                )
            header = statement
    if statements and header is None:
        first = statements[0]
        where = first.use.position if isinstance(first, ComponentDecl) else _first_position(first)
        problems.append(error("syntax", "the file must begin with a 'model NAME' line", where))
    if problems:
        raise ModelError(source, sorted(problems, key=_order))
    return ParsedModel(
        source=source,
        header=header,
        parameters=tuple(s for s in statements if isinstance(s, ParameterDecl)),
        declarations=tuple(s for s in statements if isinstance(s, ComponentDecl)),
        bonds=tuple(s for s in statements if isinstance(s, BondText)),
        ports=tuple(s for s in statements if isinstance(s, PortDecl)),
        subsystems=tuple(s for s in statements if isinstance(s, SubsystemDecl)),
    )


def begins_as_model(source: Source) -> bool:
    """Whether the first statement of the text (blank lines and comments aside) is a
    `model NAME` line: what a file must at least be to be reported as a model."""
    first = next((line for line in source.lines if not _BLANK.fullmatch(line)), None)
    if first is None or len(first) > MAX_LINE:
        return False
    try:
        tree = _parser().parse(first + "\n", start="line")
    except lark.exceptions.UnexpectedInput:
        return False
    items = _ToModel([], 1).transform(tree).children
    return bool(items) and isinstance(items[0], ModelHeader)


def _first_position(statement) -> Position:
    return statement.tail.position if isinstance(statement, BondText) else statement.position


def _order(diagnostic: Diagnostic):
    return diagnostic.key


def parse_expression(text: str, variables: frozenset[str] = frozenset({LAPLACE})) -> sympy.Expr:
    """A lone expression (a filter polynomial on the command line, say) in the named variables.

    Raises `ModelError` (reported against `<expression>`) for syntax errors and unknown names.
    """
    source = Source("<expression>", text)
    problems: list[Diagnostic] = []
    parser = _parser()
    if len(text) > MAX_LINE:
        too_long = f"an expression longer than {MAX_LINE} characters (a limit)"
        raise ModelError(source, [error("syntax", too_long, Position(1, MAX_LINE + 1))])
    try:
        tree = parser.parse(text, start="expression")
    except lark.exceptions.UnexpectedInput as exc:
        position = Position(exc.line, exc.column) if exc.line > 0 else None
        raise ModelError(source, [error("syntax", syntax_message(exc, parser), position)]) from None
    partial = _ToModel(problems).transform(tree)
    for use in partial.names:
        if use.name not in variables:
            allowed = ", ".join(sorted(variables))
            hint = (
                f"use {allowed}"
                if variables
                else "a value here is a number or an expression of numbers"
            )
            problems.append(
                error("undeclared_parameter", f"unknown name {use.name!r} ({hint})", use.position)
            )
    if problems:
        raise ModelError(source, problems)
    return partial.value
