"""Errors and warnings about a model, reported the way a compiler reports them.

Every stage reports problems in the user's model as `Diagnostic` records; a stage
that cannot go on raises `ModelError` carrying all of them, so the CLI can print
every problem found in one pass and API users get the same records.

A model may span several files (subsystems): every diagnostic knows the file its line
and column belong to (its `Origin`), and, for a line in a subsystem's file, the chain of
`subsystem` statements that brought the file in, printed as notes.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from enum import Enum
from functools import cached_property


class Severity(Enum):
    ERROR = "error"
    WARNING = "warning"


@dataclass(frozen=True)
class Source:
    """The text of a model file under the name it is reported by."""

    name: str
    text: str = field(repr=False)

    @cached_property
    def lines(self) -> list[str]:
        """The text's lines, split once (a diagnostic per line of a long file would
        otherwise split the whole text each time). Lines end at "\\n" only, as the parser
        counts them (splitlines would also split at form feeds and Unicode line separators
        inside descriptions)."""
        return self.text.split("\n")

    def line(self, number: int) -> str:
        lines = self.lines
        return lines[number - 1].removesuffix("\r") if 0 < number <= len(lines) else ""

    def render(self, diagnostic: Diagnostic) -> str:
        """The diagnostic as the compiler prints it; this file unless it names its own."""
        return diagnostic.render(self)


QUOTE_WIDTH = 100  # characters of the offending line a diagnostic quotes, at most


def quoted(line: str, column: int) -> tuple[str, int]:
    """The part of `line` a diagnostic quotes, at most `QUOTE_WIDTH` characters around
    `column` ("..." where it is cut), and the column within it: a diagnostic shows the
    place, never a whole long line of the file."""
    text = line.expandtabs(1)
    if len(text) <= QUOTE_WIDTH:
        return text, column
    start = max(0, min(column - 1 - QUOTE_WIDTH // 2, len(text) - QUOTE_WIDTH))
    before = "..." if start else ""
    after = "..." if start + QUOTE_WIDTH < len(text) else ""
    return before + text[start : start + QUOTE_WIDTH] + after, column - start + len(before)


@dataclass(frozen=True)
class Inclusion:
    """A `subsystem` statement that brought a file into the model."""

    subsystem: str  # the subsystem's full (dotted) name
    file: str  # the including file, as reported
    line: int
    column: int

    @property
    def note(self) -> str:
        return f"in subsystem {self.subsystem} ({self.file}:{self.line})"


@dataclass(frozen=True)
class Origin:
    """The file a line and column belong to, and how that file entered the model."""

    source: Source
    within: tuple[Inclusion, ...] = ()  # the innermost subsystem statement first


def _outer(origin: Origin | None) -> tuple[tuple[int, int], ...]:
    """The places of the subsystem statements around a file, the outermost first."""
    return tuple((i.line, i.column) for i in reversed(origin.within)) if origin else ()


@dataclass(frozen=True, order=True)
class Position:
    """A 1-based line and column in a source file; `origin` says which file, when the
    model spans several (positions compare by line and column only)."""

    line: int
    column: int
    origin: Origin | None = field(default=None, compare=False)

    @property
    def key(self) -> tuple:
        """Model order: a line of a subsystem's file sorts at its subsystem statement."""
        return (*_outer(self.origin), (self.line, self.column))


@dataclass(frozen=True)
class Diagnostic:
    kind: str
    message: str
    position: Position | None = None
    severity: Severity = Severity.ERROR
    origin: Origin | None = None  # the file, when known (always, once in a ModelError)

    @property
    def file(self) -> str | None:
        return self.origin.source.name if self.origin else None

    @property
    def notes(self) -> tuple[str, ...]:
        return tuple(i.note for i in self.origin.within) if self.origin else ()

    @property
    def key(self) -> tuple:
        """Model order, the diagnostics without a place first."""
        if self.position is not None:
            return self.position.key
        return (*_outer(self.origin), (0, 0))

    def to_json(self) -> dict:
        return {
            "file": self.file,
            "kind": self.kind,
            "line": self.position.line if self.position else None,
            "column": self.position.column if self.position else None,
            "message": self.message,
            "notes": list(self.notes),
        }

    def render(self, default: Source | None = None) -> str:
        """`FILE:LINE:COL: error[KIND]: message`, the source line, a caret, then the notes."""
        source = self.origin.source if self.origin else default
        where = source.name if source else "<model>"
        if self.position:
            where += f":{self.position.line}:{self.position.column}"
        lines = [f"{where}: {self.severity.value}[{self.kind}]: {self.message}"]
        if self.position and source:
            number = str(self.position.line)
            text, column = quoted(source.line(self.position.line), self.position.column)
            pad = " " * len(number)
            caret = " " * (column - 1) + "^"
            lines += [f" {number} | {text}", f" {pad} | {caret}"]
        lines += [f"note: {note}" for note in self.notes]
        return "\n".join(lines)


class MttError(Exception):
    """Every error a user of mtt can cause, with where it is (public as `mtt.MttError`).

    `kind` names the problem (`syntax`, `causal_conflict`, `missing_value`...); `file`,
    `line` and `column` locate it when it is in a model file (1-based, or None).
    """

    def __init__(
        self,
        message: str,
        *,
        kind: str,
        file: str | None = None,
        line: int | None = None,
        column: int | None = None,
    ):
        super().__init__(message)
        self.kind, self.file, self.line, self.column = kind, file, line, column

    def render(self) -> str:
        """`FILE:LINE:COL: error[KIND]: message`, as much of the place as is known."""
        place = (self.file, self.line, self.column)
        where = ":".join(str(part) for part in place if part is not None)
        return f"{where + ': ' if where else ''}error[{self.kind}]: {self}"

    def to_json(self) -> dict:
        """The `--json` record of a command that failed: `ok` false and the errors."""
        error = {"file": self.file, "kind": self.kind, "line": self.line,
                 "column": self.column, "message": str(self), "notes": []}  # fmt: skip
        return {"ok": False, "errors": [error]}


class ModelError(MttError):
    """A model that cannot be processed; `diagnostics` holds every problem found.

    Diagnostics that do not name their file are taken to be about `source`. As an
    `MttError` it reports its first error: `kind`, `file`, `line`, `column`.
    """

    def __init__(self, source: Source, diagnostics: list[Diagnostic] | tuple[Diagnostic, ...]):
        self.source = source
        default = Origin(source)
        self.diagnostics = tuple(
            d if d.origin is not None else replace(d, origin=default) for d in diagnostics
        )
        first = (self.errors or self.diagnostics or (Diagnostic("model", "", origin=default),))[0]
        where = first.position
        super().__init__(
            self.render(),
            kind=first.kind,
            file=first.file,
            line=where.line if where else None,
            column=where.column if where else None,
        )

    @property
    def errors(self) -> tuple[Diagnostic, ...]:
        return tuple(d for d in self.diagnostics if d.severity is Severity.ERROR)

    @property
    def warnings(self) -> tuple[Diagnostic, ...]:
        return tuple(d for d in self.diagnostics if d.severity is Severity.WARNING)

    def render(self) -> str:
        return "\n".join(d.render() for d in self.diagnostics)

    def to_json(self) -> dict:
        return {"ok": False, "errors": [d.to_json() for d in self.errors]}

    def kinds(self) -> list[str]:
        return [d.kind for d in self.errors]


def _diagnostic(kind, message, position, severity, origin) -> Diagnostic:
    if origin is None and position is not None:
        origin = position.origin
    return Diagnostic(kind, message, position, severity, origin)


def error(
    kind: str, message: str, position: Position | None = None, origin: Origin | None = None
) -> Diagnostic:
    return _diagnostic(kind, message, position, Severity.ERROR, origin)


def warning(
    kind: str, message: str, position: Position | None = None, origin: Origin | None = None
) -> Diagnostic:
    return _diagnostic(kind, message, position, Severity.WARNING, origin)
