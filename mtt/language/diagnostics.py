"""Errors and warnings about a model, reported the way a compiler reports them.

Every stage reports problems in the user's model as `Diagnostic` records; a stage
that cannot go on raises `ModelError` carrying all of them, so the CLI can print
every problem found in one pass and API users get the same records.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum


class Severity(Enum):
    ERROR = "error"
    WARNING = "warning"


@dataclass(frozen=True, order=True)
class Position:
    """A 1-based line and column in a source file."""

    line: int
    column: int


@dataclass(frozen=True)
class Diagnostic:
    kind: str
    message: str
    position: Position | None = None
    severity: Severity = Severity.ERROR

    def to_json(self) -> dict:
        return {
            "kind": self.kind,
            "line": self.position.line if self.position else None,
            "column": self.position.column if self.position else None,
            "message": self.message,
        }


@dataclass(frozen=True)
class Source:
    """The text of a model file under the name it is reported by."""

    name: str
    text: str = field(repr=False)

    def line(self, number: int) -> str:
        # Lines end at "\n" only, as the parser counts them (splitlines would also
        # split at form feeds and Unicode line separators inside descriptions).
        lines = self.text.split("\n")
        return lines[number - 1].removesuffix("\r") if 0 < number <= len(lines) else ""

    def render(self, diagnostic: Diagnostic) -> str:
        """`FILE:LINE:COL: error[KIND]: message`, the source line and a caret."""
        where = self.name
        if diagnostic.position:
            where += f":{diagnostic.position.line}:{diagnostic.position.column}"
        head = f"{where}: {diagnostic.severity.value}[{diagnostic.kind}]: {diagnostic.message}"
        if not diagnostic.position:
            return head
        number = str(diagnostic.position.line)
        text = self.line(diagnostic.position.line).expandtabs(1)
        pad = " " * len(number)
        caret = " " * (diagnostic.position.column - 1) + "^"
        return f"{head}\n {number} | {text}\n {pad} | {caret}"


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


class ModelError(MttError):
    """A model that cannot be processed; `diagnostics` holds every problem found.

    As an `MttError` it reports its first error: `kind`, `file`, `line`, `column`.
    """

    def __init__(self, source: Source, diagnostics: list[Diagnostic] | tuple[Diagnostic, ...]):
        self.source = source
        self.diagnostics = tuple(diagnostics)
        first = (self.errors or self.diagnostics or (Diagnostic("model", ""),))[0]
        where = first.position
        super().__init__(
            self.render(),
            kind=first.kind,
            file=source.name,
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
        return "\n".join(self.source.render(d) for d in self.diagnostics)

    def kinds(self) -> list[str]:
        return [d.kind for d in self.errors]


def error(kind: str, message: str, position: Position | None = None) -> Diagnostic:
    return Diagnostic(kind, message, position, Severity.ERROR)


def warning(kind: str, message: str, position: Position | None = None) -> Diagnostic:
    return Diagnostic(kind, message, position, Severity.WARNING)
