"""The records checking produces, and the rules for reading signals.

A `Parameter` and a `Component` are what one file declares (and, once the files are
assembled, what the whole model has, with dotted names).
"""

from __future__ import annotations

from dataclasses import dataclass

from mtt.language.components import CausalKind, CausalRule, ComponentType, PortRule, Role
from mtt.language.diagnostics import Position
from mtt.language.expressions import SIGNALS, Expression, SignalUse
from mtt.language.relations import IMPOSES_EFFORT, Constitutive


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
    # a relation in its own variables (R, C, I); with `argument` too when it is linear
    # through the origin (the argument is then its parameter), alone when it is nonlinear
    relation: Constitutive | None = None

    @property
    def label(self) -> str:
        return f"{self.type.name}:{self.name}"

    @property
    def nonlinear_relation(self) -> bool:
        return self.relation is not None and self.argument is None

    @property
    def causality(self) -> CausalRule:
        """The type's causal rule, unless a nonlinear relation can be used one way only:
        then that way is fixed."""
        rule = self.type.causality
        if not self.nonlinear_relation:
            return rule
        served = self.relation.serves()
        if len(served) == 2:
            return rule
        return CausalRule(CausalKind.FIXED, imposes_effort=next(iter(served)))

    def needs(self, imposes_effort: bool) -> str:
        """The variable its relation must give under this causality."""
        return next(v for v in self.relation.relates if IMPOSES_EFFORT[v] == imposes_effort)


@dataclass(frozen=True)
class LocalBond:
    """A bond of one file, between its components or its subsystems' ports."""

    tail: str  # a component's name, or `sub.port`
    head: str
    position: Position


def signal_readable(kind: str, target: ComponentType) -> bool:
    """e(X) (and p(X), its integral) reads a 0-junction's common effort or a one-port's;
    f(X) (and q(X)) a 1-junction's flow or a one-port's."""
    junction = "0" if kind in ("e", "p") else "1"
    return target.name == junction or target.ports is PortRule.ONE


def unreadable(use: SignalUse, target: ComponentType) -> str:
    """Why a signal cannot be read from a component of this type."""
    variable = SIGNALS[use.kind]
    if target.role is Role.JUNCTION:
        other = {"e": "f", "f": "e", "q": "p", "p": "q"}[use.kind]
        return (
            f"{use.text}: a {target.summary} has no common {variable}; "
            f"read {other}({use.target}) or the {variable} of one of its one-ports"
        )
    return f"{use.text}: a {target.summary} has two {variable}s; read the junction beside it"
