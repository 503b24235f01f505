"""The rules that relate a file's subsystem statements to the files they read.

A subsystem's name is unique among the file's components and subsystems; its bindings
set parameters its file declares, once each; each of its SS ports is bonded exactly once,
in the direction the subsystem's own bond at that SS agrees with. Mixed into `FileCheck`.
"""

from __future__ import annotations

from functools import cached_property

from mtt.language.components import Role
from mtt.language.diagnostics import Position
from mtt.language.parse import ComponentUse, PortUse


class SubsystemRules:
    """The checks of a file's subsystem statements (`children`: their files' checks)."""

    def check_subsystems(self) -> None:
        """Subsystem names (in the components' name space), and each binding."""
        seen: dict[str, Position] = {}
        for decl in self.parsed.subsystems:
            other = seen.get(decl.name)
            component = self.components.get(decl.name)
            if other is None and component is not None:
                if component.position < decl.position:
                    other = component.position
                else:
                    self.report(
                        "duplicate_name",
                        f"{component.label}: the name is already used on line "
                        f"{decl.position.line} by a subsystem",
                        component.position,
                    )
            if other is not None:
                self.report(
                    "duplicate_name",
                    f"subsystem {decl.name!r}: the name is already used on line {other.line}",
                    decl.position,
                )
                continue
            seen[decl.name] = decl.position
            child = self.children.get(decl.name)
            bound: dict[str, Position] = {}
            for binding in decl.bindings:
                if binding.name in bound:
                    self.report(
                        "duplicate_argument",
                        f"subsystem {decl.name}: {binding.name} is already set on line "
                        f"{bound[binding.name].line}",
                        binding.position,
                    )
                elif child is not None and binding.name not in child.parameters:
                    self.report(
                        "undeclared_parameter",
                        f"subsystem {decl.name}: its file {decl.file} declares no parameter "
                        f"{binding.name!r}",
                        binding.position,
                    )
                bound.setdefault(binding.name, binding.position)

    def _ports(self, subsystem: str) -> dict[str, bool]:
        child = self.children.get(subsystem)
        return child.inward if child is not None else {}

    def check_ports(self) -> None:
        """Each subsystem port bonded exactly once, in the direction its own bond agrees with."""
        declared = {d.name: d for d in self.parsed.subsystems}
        uses: dict[str, list] = {}
        for bond in self.parsed.bonds:
            for end, into_port in ((bond.head, True), (bond.tail, False)):
                if not isinstance(end, PortUse):
                    continue
                decl = declared.get(end.subsystem)
                if decl is None:
                    self.report(
                        "undeclared_component",
                        f"{end.name}: there is no subsystem {end.subsystem!r}",
                        end.position,
                    )
                    continue
                if end.subsystem not in self.children:  # not read: reported there
                    continue
                ports = self._ports(end.subsystem)
                if end.port not in ports:
                    names = ", ".join(sorted(ports)) or "none"
                    self.report(
                        "bad_port",
                        f"{end.name}: {decl.file} has no port SS:{end.port} (its ports: {names})",
                        end.position,
                    )
                    continue
                uses.setdefault(end.name, []).append(end)
                if ports[end.port] == into_port:
                    way, must = ("into", "out of") if into_port else ("out of", "into")
                    self.report(
                        "port_direction",
                        f"{end.name}: the subsystem's own bond points {way} SS:{end.port}, so "
                        f"this bond must point {must} the port",
                        bond.position,
                    )
        for name, child in self.children.items():
            for port in sorted(child.inward):
                mentions = uses.get(f"{name}.{port}", [])
                if not mentions:
                    self.report(
                        "unconnected_component",
                        f"port {name}.{port} of subsystem {name} is not connected to any bond",
                        declared[name].position,
                    )
                elif len(mentions) > 1:
                    self.report(
                        "bad_arity",
                        f"port {name}.{port} is bonded {len(mentions)} times; a port joins "
                        "exactly one bond",
                        mentions[0].position,
                    )

    @cached_property
    def inward(self) -> dict[str, bool]:
        """This file's SS ports: does its own bond point into the SS? (Known even when the
        bond's other end is wrong: that is reported here, not at each use of the port.)"""
        ports = {n for n, c in self.components.items() if c.type.role is Role.PORT}
        into = {}
        for bond in self.parsed.bonds:
            for end, towards in ((bond.head, True), (bond.tail, False)):
                if isinstance(end, ComponentUse) and end.type == "SS" and end.name in ports:
                    into[end.name] = towards
        return into
