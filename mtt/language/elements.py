"""The records checking produces, and the rules for reading signals.

A `Parameter` and a `Component` are what one file declares (and, once the files are
assembled, what the whole model has, with dotted names).
"""

from __future__ import annotations

from dataclasses import dataclass

from mtt.language.components import ComponentType, PortRule, Role
from mtt.language.diagnostics import Position
from mtt.language.expressions import SIGNALS, Expression, SignalUse


@dataclass(frozen=True)
class Parameter:
    name: str
    value: Expression | None
    description: str | None
    declared_unknown: bool
    position: Position


@dataclass(frozen=True)
class Component:
    name: str
    type: ComponentType
    argument: Expression | None  # explicit, or the parameter of the same name
    position: Position  # first mention
    description: str | None

    @property
    def label(self) -> str:
        return f"{self.type.name}:{self.name}"


@dataclass(frozen=True)
class LocalBond:
    """A bond of one file, between its components or its subsystems' ports."""

    tail: str  # a component's name, or `sub.port`
    head: str
    position: Position


def signal_readable(kind: str, target: ComponentType) -> bool:
    """e(X) reads a 0-junction's common effort or a one-port's; f(X) a 1-junction's flow."""
    junction = "0" if kind == "e" else "1"
    return target.name == junction or target.ports is PortRule.ONE


def unreadable(use: SignalUse, target: ComponentType) -> str:
    """Why a signal cannot be read from a component of this type."""
    variable = SIGNALS[use.kind]
    if target.role is Role.JUNCTION:
        other = "f" if use.kind == "e" else "e"
        return (
            f"{use.text}: a {target.summary} has no common {variable}; "
            f"read {other}({use.target}) or the {variable} of one of its one-ports"
        )
    return f"{use.text}: a {target.summary} has two {variable}s; read the junction beside it"
