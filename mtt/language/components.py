"""The component library, as data.

Each bond graph component type declares, in one `ComponentType` entry, its ports,
whether it takes an argument, its causality constraint and its linear constitutive
relation. Every later stage reads these entries and nothing else about a type, so
a new type is one entry here.

A constitutive relation is a list of rows, each row a linear form {variable:
coefficient} that equals zero. Its variables are the efforts and flows of the
component's ports, and for a storage element its energy variable (q for C, p for I)
and that variable's time derivative; sources add the input u, detectors the output y.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from enum import Enum
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # the relations are written only by the derivation, which imports sympy
    import sympy


class Role(Enum):
    SOURCE = "source"
    MODULATED = "modulated source"
    DETECTOR = "detector"
    RESISTOR = "resistor"
    STORAGE = "storage"
    TWO_PORT = "two-port"
    JUNCTION = "junction"
    PORT = "port"  # a subsystem's external port: joined to its parent's bond, it disappears


class PortRule(Enum):
    ONE = "exactly one bond"
    TWO = "one inward and one outward bond"
    ANY = "at least one bond"


class CausalKind(Enum):
    FIXED = "fixed"  # the component always imposes (or never imposes) effort
    PREFERRED = "preferred"  # integral causality if at all possible
    FREE = "free"  # either way; a choice here closes an algebraic loop
    SAME = "same"  # both ports impose effort, or neither (GY)
    OPPOSITE = "opposite"  # exactly one port imposes effort (TF)
    EXACTLY_ONE = "exactly one"  # exactly one port has `imposes_effort` (junctions)


@dataclass(frozen=True)
class CausalRule:
    """The causal strokes a component allows, in terms of which ports it imposes effort on.

    For FIXED and PREFERRED, `imposes_effort` is the (preferred) causality of the one
    port; for EXACTLY_ONE it is the value that exactly one port takes.
    """

    kind: CausalKind
    imposes_effort: bool | None = None


@dataclass(frozen=True)
class PortVariables:
    """The names a relation is written in, for one component of one bond graph."""

    efforts: tuple[str, ...]
    flows: tuple[str, ...]
    inward: tuple[bool, ...]
    parameter: sympy.Expr | None = None
    energy: str | None = None
    rate: str | None = None
    drive: str | None = None  # the input u, or None for a source set to zero
    measure: str | None = None  # the output y, or None for an unused detector
    signals: tuple[tuple[str, sympy.Expr], ...] = ()  # a modulated source's (variable, coefficient)

    def sign(self, port: int) -> int:
        return 1 if self.inward[port] else -1


Row = dict[str, "sympy.Expr"]
Relation = Callable[[PortVariables], list[Row]]


@dataclass(frozen=True)
class ComponentType:
    name: str
    summary: str
    role: Role
    ports: PortRule
    takes_argument: bool
    causality: CausalRule
    relation: Relation | None  # None for SS, which is never in an assembled bond graph
    energy_prefix: str | None = None  # the letter of a storage element's energy variable
    conventional_inward: bool | None = None  # for one-ports: the usual bond direction
    modulated: bool = False  # its argument, required, is a function of signals
    # the variables its constitutive relation relates, (y, x) with y = k x for its linear
    # parameter k (R: e = r f; C: q = c e; I: p = i f); None: it takes no relation
    relates: tuple[str, str] | None = None
    modulable: bool = False  # its argument may read signals (TF, GY): a modulated two-port


def _integer(value: int) -> sympy.Integer:
    import sympy

    return sympy.Integer(value)


def _source(on_effort: bool) -> Relation:
    def relation(v: PortVariables) -> list[Row]:
        variable = v.efforts[0] if on_effort else v.flows[0]
        row = {variable: _integer(1)}
        if v.drive:
            row[v.drive] = _integer(-1)
        return [row]

    return relation


def _modulated(on_effort: bool) -> Relation:
    """e (or f) = sum of coefficient * signal: the signals are other bonds' variables."""

    def relation(v: PortVariables) -> list[Row]:
        row = {v.efforts[0] if on_effort else v.flows[0]: _integer(1)}
        for variable, coefficient in v.signals:
            row[variable] = row.get(variable, _integer(0)) - coefficient
        return [row]

    return relation


def _detector(reads_effort: bool) -> Relation:
    def relation(v: PortVariables) -> list[Row]:
        read, zero = (v.efforts[0], v.flows[0]) if reads_effort else (v.flows[0], v.efforts[0])
        rows = [{zero: _integer(1)}]
        if v.measure:
            rows.append({v.measure: _integer(1), read: _integer(-1)})
        return rows

    return relation


def _resistor(v: PortVariables) -> list[Row]:
    return [{v.efforts[0]: _integer(1), v.flows[0]: -v.parameter}]


def _storage(stored_by_effort: bool) -> Relation:
    """C: q = c e, dq/dt = f.  I: p = i f, dp/dt = e."""

    def relation(v: PortVariables) -> list[Row]:
        stored, rate = (
            (v.efforts[0], v.flows[0]) if stored_by_effort else (v.flows[0], v.efforts[0])
        )
        return [
            {v.energy: _integer(1), stored: -v.parameter},
            {v.rate: _integer(1), rate: _integer(-1)},
        ]

    return relation


def _transformer(v: PortVariables) -> list[Row]:
    """e1 = n e2, f2 = n f1 (port 0 is the inward bond)."""
    one = _integer(1)
    return [
        {v.efforts[0]: one, v.efforts[1]: -v.parameter},
        {v.flows[1]: one, v.flows[0]: -v.parameter},
    ]


def _gyrator(v: PortVariables) -> list[Row]:
    """e1 = r f2, e2 = r f1 (port 0 is the inward bond)."""
    one = _integer(1)
    return [
        {v.efforts[0]: one, v.flows[1]: -v.parameter},
        {v.efforts[1]: one, v.flows[0]: -v.parameter},
    ]


def _junction(common_effort: bool) -> Relation:
    """0: efforts equal, flows balance.  1: flows equal, efforts balance (inward positive)."""

    def relation(v: PortVariables) -> list[Row]:
        common, summed = (v.efforts, v.flows) if common_effort else (v.flows, v.efforts)
        one = _integer(1)
        rows = [{name: one, common[0]: -one} for name in common[1:]]
        rows.append({name: _integer(v.sign(i)) for i, name in enumerate(summed)})
        return rows

    return relation


_FIXED_EFFORT = CausalRule(CausalKind.FIXED, imposes_effort=True)
_FIXED_FLOW = CausalRule(CausalKind.FIXED, imposes_effort=False)

LIBRARY: dict[str, ComponentType] = {
    t.name: t
    for t in (
        ComponentType("Se", "effort source", Role.SOURCE, PortRule.ONE, False,
                      _FIXED_EFFORT, _source(on_effort=True), conventional_inward=False),
        ComponentType("Sf", "flow source", Role.SOURCE, PortRule.ONE, False,
                      _FIXED_FLOW, _source(on_effort=False), conventional_inward=False),
        # Modulated sources are as often sinks (an outflow) as sources: no usual direction.
        ComponentType("MSe", "modulated effort source", Role.MODULATED, PortRule.ONE, True,
                      _FIXED_EFFORT, _modulated(on_effort=True), modulated=True),
        ComponentType("MSf", "modulated flow source", Role.MODULATED, PortRule.ONE, True,
                      _FIXED_FLOW, _modulated(on_effort=False), modulated=True),
        ComponentType("De", "effort detector", Role.DETECTOR, PortRule.ONE, False,
                      _FIXED_FLOW, _detector(reads_effort=True), conventional_inward=True),
        ComponentType("Df", "flow detector", Role.DETECTOR, PortRule.ONE, False,
                      _FIXED_EFFORT, _detector(reads_effort=False), conventional_inward=True),
        ComponentType("R", "resistor", Role.RESISTOR, PortRule.ONE, True,
                      CausalRule(CausalKind.FREE), _resistor, conventional_inward=True,
                      relates=("e", "f")),
        ComponentType("C", "capacitor (compliance)", Role.STORAGE, PortRule.ONE, True,
                      CausalRule(CausalKind.PREFERRED, imposes_effort=True),
                      _storage(stored_by_effort=True), energy_prefix="q",
                      conventional_inward=True, relates=("q", "e")),
        ComponentType("I", "inertia (inductance)", Role.STORAGE, PortRule.ONE, True,
                      CausalRule(CausalKind.PREFERRED, imposes_effort=False),
                      _storage(stored_by_effort=False), energy_prefix="p",
                      conventional_inward=True, relates=("p", "f")),
        ComponentType("TF", "transformer", Role.TWO_PORT, PortRule.TWO, True,
                      CausalRule(CausalKind.OPPOSITE), _transformer, modulable=True),
        ComponentType("GY", "gyrator", Role.TWO_PORT, PortRule.TWO, True,
                      CausalRule(CausalKind.SAME), _gyrator, modulable=True),
        ComponentType("0", "0-junction (common effort)", Role.JUNCTION, PortRule.ANY, False,
                      CausalRule(CausalKind.EXACTLY_ONE, imposes_effort=False),
                      _junction(common_effort=True)),
        ComponentType("1", "1-junction (common flow)", Role.JUNCTION, PortRule.ANY, False,
                      CausalRule(CausalKind.EXACTLY_ONE, imposes_effort=True),
                      _junction(common_effort=False)),
        ComponentType("SS", "subsystem port", Role.PORT, PortRule.ONE, False,
                      CausalRule(CausalKind.FREE), None),
    )
}  # fmt: skip
