"""Assembling the checked files of a model into one flat bond graph.

Every name of a subsystem NAME becomes `NAME.X` (its parameters, components and signals,
in its expressions too), its positions are placed in its own file with the chain of
subsystem statements that brought it in, and a parameter its parent sets takes the
parent's expression. Each SS port then joins its two bonds, the subsystem's own and the
parent's, into one bond between their other ends (the parent's bond gives the place).
"""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass, replace
from itertools import count

from mtt.language.checks import FileCheck
from mtt.language.components import Role
from mtt.language.diagnostics import Diagnostic, Origin, Position, error
from mtt.language.elements import Component, Parameter, signal_readable, unreadable
from mtt.language.expressions import Expression, SignalUse, renamed
from mtt.language.relations import Constitutive
from mtt.language.subsystems import Instance, relocate


@dataclass(frozen=True)
class Bond:
    number: int
    tail: str
    head: str
    position: Position


@dataclass
class Assembly:
    components: dict[str, Component]  # by full name, in model order (no SS ports)
    parameters: dict[str, Parameter]  # by full name, in model order
    bonds: list[Bond]  # numbered in model order
    port_bonds: dict[str, int]  # each SS port (full name) -> the bond it became part of
    problems: list[Diagnostic]


class _Renamer:
    """One instance's names and places as the whole model sees them."""

    def __init__(self, instance: Instance, check: FileCheck):
        self.prefix = instance.prefix
        self.origin: Origin | None = instance.origin if instance.prefix else None
        self.parameters = check.parameters

    def position(self, position: Position | None) -> Position | None:
        return position if self.origin is None else relocate(position, self.origin)

    def expression(self, expression: Expression | None) -> Expression | None:
        if expression is None or not self.prefix:
            return expression
        return renamed(expression, self.prefix, self.parameters, self.position)

    def relation(self, relation: Constitutive | None) -> Constitutive | None:
        if relation is None or not self.prefix:
            return relation
        given = tuple(
            replace(r, expression=self.expression(r.expression), position=self.position(r.position))
            for r in relation.given
        )
        return replace(relation, given=given)


class _Assembler:
    def __init__(self, checks: dict[str, FileCheck]):
        self.checks = checks
        self.components: dict[str, Component] = {}
        self.parameters: dict[str, Parameter] = {}
        self.bonds: list[list] = []  # [tail, head, position, depth]
        self.signals: list[tuple[str, SignalUse]] = []  # dotted: (full target, as written)
        self.problems: list[Diagnostic] = []

    def visit(self, instance: Instance, bound: dict[str, Expression], depth: int) -> None:
        check = self.checks[instance.name]
        rename = _Renamer(instance, check)
        prefix = instance.prefix
        for name, p in check.parameters.items():
            value = bound[name] if name in bound else rename.expression(p.value)
            self.parameters[prefix + name] = Parameter(
                prefix + name,
                value,
                p.description,
                p.declared_unknown and name not in bound,
                rename.position(p.position),
            )
        for name, c in check.components.items():
            argument = rename.expression(c.argument)
            self.components[prefix + name] = Component(
                prefix + name,
                c.type,
                argument,
                rename.position(c.position),
                c.description,
                rename.relation(c.relation),
            )
            if (c.type.modulated or c.type.modulable) and c.argument is not None:
                self.signals += [
                    (prefix + u.target, SignalUse(u.kind, u.target, rename.position(u.position)))
                    for u in c.argument.signals
                    if "." in u.target and u.target.partition(".")[0] in instance.children
                ]
        for b in check.bonds:
            self.bonds.append(
                [prefix + b.tail, prefix + b.head, rename.position(b.position), depth]
            )
        for child in instance.children.values():
            known = self.checks[child.name].parameters
            values = {
                b.name: rename.expression(b.value)
                for b in child.declaration.bindings
                if b.name in known
            }
            self.visit(child, values, depth + 1)

    def check_signals(self) -> None:
        """Signals read across subsystems, `e(motor.x)`: now that every name is known."""
        for target, use in self.signals:
            component = self.components.get(target)
            if component is None:
                self.problems.append(
                    error(
                        "undeclared_component",
                        f"{use.text} reads component {use.target!r}, which is not declared",
                        use.position,
                    )
                )
            elif not signal_readable(use.kind, component.type):
                self.problems.append(
                    error("bad_signal", unreadable(use, component.type), use.position)
                )

    def join_ports(self) -> dict[str, int]:
        """Join each port's two bonds into one (the shallower bond, the parent's, gives the
        place), and number the bonds; each port's bond number."""
        bonds = dict(enumerate(self.bonds))
        touching: dict[str, set[int]] = defaultdict(set)
        for key, (tail, head, _, _) in bonds.items():
            touching[tail].add(key)
            touching[head].add(key)
        became: dict[str, int] = {}
        forward: dict[int, int] = {}
        fresh = count(len(bonds))
        ports = [n for n, c in self.components.items() if c.type.role is Role.PORT]
        for port in ports:
            into = [k for k in touching[port] if bonds[k][1] == port]
            out = [k for k in touching[port] if bonds[k][0] == port]
            if len(into) != 1 or len(out) != 1:  # unused, used twice, or against: reported
                continue
            a, b = bonds.pop(into[0]), bonds.pop(out[0])
            outer = a if a[3] <= b[3] else b
            key = next(fresh)
            bonds[key] = [a[0], b[1], outer[2], outer[3]]
            forward[into[0]] = forward[out[0]] = key
            for end in (a[0], b[1]):
                touching[end] -= {into[0], out[0]}
                touching[end].add(key)
            became[port] = key
            del self.components[port]
            if a[0] == b[1]:
                label = self.components[a[0]].label if a[0] in self.components else a[0]
                self.problems.append(
                    error(
                        "self_bond",
                        f"a bond from {label} to itself, through the port {port}",
                        outer[2],
                    )
                )
        ordered = sorted(bonds.items(), key=lambda item: item[1][2].key)
        number = {key: i for i, (key, _) in enumerate(ordered, start=1)}
        self.bonds = [Bond(number[k], t, h, p) for k, (t, h, p, _) in ordered]

        def final(key: int) -> int:
            while key in forward:
                key = forward[key]
            return number[key]

        return {port: final(key) for port, key in became.items()}


def assemble(root: Instance, checks: dict[str, FileCheck]) -> Assembly:
    """The whole model's components, parameters and bonds, with full names."""
    assembler = _Assembler(checks)
    assembler.visit(root, {}, 0)
    assembler.check_signals()
    port_bonds = assembler.join_ports()
    order = lambda item: item[1].position.key  # noqa: E731
    return Assembly(
        components=dict(sorted(assembler.components.items(), key=order)),
        parameters=dict(sorted(assembler.parameters.items(), key=order)),
        bonds=assembler.bonds,
        port_bonds=port_bonds,
        problems=assembler.problems,
    )
