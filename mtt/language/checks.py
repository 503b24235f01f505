"""The rules of the language that one file obeys on its own, checked file by file.

A model file and each subsystem file are checked in their own scope, with their own
names: parameters, components (SS ports only in a part: a subsystem's file, or a file
checked or drawn alone as a part), arguments, names in
expressions, signals, cycles, bonds and arities, and each subsystem statement against
the file it reads (its bindings, its ports, their use and direction). What concerns the
whole model (the unknowns, the input and output, signals read across subsystems) is
checked once the files are assembled (see `bondgraph`).
"""

from __future__ import annotations

from collections import Counter
from graphlib import CycleError, TopologicalSorter

from mtt.language.components import LIBRARY, ComponentType, PortRule, Role
from mtt.language.diagnostics import Diagnostic, Origin, Position, error, warning
from mtt.language.elements import Component, LocalBond, Parameter, signal_readable, unreadable
from mtt.language.expressions import RESERVED, Expression, name_expression
from mtt.language.parse import ComponentUse, ParsedModel, PortUse
from mtt.language.ports import SubsystemRules
from mtt.language.relation_rules import relation_problems
from mtt.language.relations import Constitutive, linear_parameter
from mtt.language.subsystems import Instance


def _article(noun: str) -> str:
    return "an" if noun[0] in "aeiou" else "a"


def _given(use: ComponentUse) -> Position | None:
    """Where a mention's argument or relation is, if it has one."""
    if use.relations:
        return use.relations[0].position
    return None if use.argument is None else use.argument.position


def _reads_signals(component: Component) -> bool:
    return component.type.modulated or component.type.modulable


def _implied_argument(use: ComponentUse) -> Expression:
    """`R:ra` means `R:ra(ra)`."""
    return name_expression(use.name, use.position)


class FileCheck(SubsystemRules):
    """Checks one instance of a file; each method checks one rule of the language.

    `children` are its subsystems' checks (those that could be read), for the rules that
    relate a subsystem statement to the file it reads.
    """

    def __init__(self, instance: Instance, children: dict[str, FileCheck], part: bool = False):
        self.parsed: ParsedModel = instance.parsed
        self.origin: Origin = instance.origin
        self.ports_allowed = instance.declaration is not None or part  # a part's own ports
        self.children = children
        self.problems: list[Diagnostic] = []
        self.warnings: list[Diagnostic] = []
        self.components: dict[str, Component] = {}
        self.parameters: dict[str, Parameter] = {}
        self.bonds: list[LocalBond] = []
        self.check()

    def report(self, kind: str, message: str, position: Position | None = None) -> None:
        self.problems.append(error(kind, message, position, self.origin))

    def check(self) -> None:
        if self.parsed.header is None or not self.parsed.bonds:
            what = "no statement" if self.parsed.header is None else "no bond"
            self.report("empty_model", f"the model has {what}")
            return
        self.check_parameters()
        self.check_components()
        self.check_subsystems()
        self.check_names()
        self.check_signals()
        self.check_cycles()
        self.check_bonds()
        self.check_ports()
        self.check_direction()

    def check_parameters(self) -> None:
        for decl in self.parsed.parameters:
            if decl.name in RESERVED:
                self.report(
                    "bad_argument",
                    f"{decl.name!r} is reserved and cannot name a parameter",
                    decl.position,
                )
            elif decl.name in self.parameters:
                first = self.parameters[decl.name].position
                self.report(
                    "duplicate_name",
                    f"parameter {decl.name!r} is already declared on line {first.line}",
                    decl.position,
                )
            else:
                self.parameters[decl.name] = Parameter(
                    decl.name, decl.value, decl.description, decl.unknown, decl.position
                )

    def check_components(self) -> None:
        declared: dict[str, Position] = {}
        repeated: set[Position] = set()
        for decl in self.parsed.declarations:
            name = decl.use.name
            if name in declared:
                repeated.add(decl.use.position)
                self.report(
                    "duplicate_name",
                    f"component {name!r} is already declared on line {declared[name].line}",
                    decl.use.position,
                )
            declared.setdefault(name, decl.use.position)
        descriptions = {d.use.name: d.description for d in self.parsed.declarations}
        argument_at: dict[str, Position] = {}
        for use in self.parsed.mentions:
            kind = LIBRARY.get(use.type)
            if kind is None:
                known = " ".join(LIBRARY)
                self.report(
                    "unknown_component_type",
                    f"unknown component type {use.type!r} (known: {known})",
                    use.position,
                )
                continue
            seen = self.components.get(use.name)
            if seen is not None and seen.type is not kind:
                if use.position not in repeated:  # not reported twice
                    self.report(
                        "duplicate_name",
                        f"{use.label} names the component {seen.label} "
                        f"of line {seen.position.line} with another type",
                        use.position,
                    )
                continue
            if _given(use) is not None:
                self._check_argument(use, kind, argument_at)
            if seen is None:
                argument, relation = self._relation(use, kind)
                self.components[use.name] = Component(
                    use.name, kind, argument, use.position, descriptions.get(use.name), relation
                )
            elif _given(use) is not None and seen.argument is None and seen.relation is None:
                argument, relation = self._relation(use, kind)
                self.components[use.name] = Component(
                    seen.name, kind, argument, seen.position, seen.description, relation
                )
        related = {use.name for use in self.parsed.mentions if use.relations}
        for name, component in self.components.items():
            if component.type.role is Role.PORT and not self.ports_allowed:
                self.report(
                    "bad_port",
                    f"{component.label}: SS ports belong to a part, a file used as a "
                    "subsystem (mtt check and mtt draw take a part alone), not to a model",
                    component.position,
                )
            elif component.type.modulated and component.argument is None:
                self.report(
                    "bad_argument",
                    f"{component.label} needs an argument: the signals that modulate it, "
                    f"such as {component.type.name}:{name}(2*e(x))",
                    component.position,
                )
            elif (
                component.type.takes_argument and component.argument is None and name not in related
            ):
                use = ComponentUse(component.type.name, name, None, component.position)
                self.components[name] = Component(
                    name,
                    component.type,
                    _implied_argument(use),
                    component.position,
                    component.description,
                )

    def _check_argument(self, use: ComponentUse, kind: ComponentType, seen: dict) -> None:
        if not kind.takes_argument:
            self.report(
                "bad_argument",
                f"{use.label} takes no argument: it is {_article(kind.summary)} {kind.summary}",
                _given(use),
            )
        elif use.name in seen:
            self.report(
                "duplicate_argument",
                f"the argument of {use.label} is already given on line {seen[use.name].line}",
                _given(use),
            )
        else:
            seen[use.name] = _given(use)

    def _relation(
        self, use: ComponentUse, kind: ComponentType
    ) -> tuple[Expression | None, Constitutive | None]:
        """The argument and the constitutive relation of a mention: a relation that is
        linear through the origin gives the argument (its parameter) too. A relation
        that breaks a rule is reported (`bad_relation`) and the component has none."""
        if not use.relations:
            return use.argument, None
        if not kind.takes_argument:
            return None, None  # reported as an argument it does not take
        if kind.relates is None:
            self.report(
                "bad_relation",
                f"{use.label} takes a value, not a relation: only R, C and I have "
                "constitutive relations written VAR = EXPR",
                use.relations[0].position,
            )
            return None, None
        problems = relation_problems(use.label, use.name, kind, use.relations)
        for message, position in problems:
            self.report("bad_relation", message, position)
        if problems:
            return None, None
        relation = Constitutive(use.relations, kind.relates)
        return linear_parameter(use.relations[0], kind.relates), relation

    def _expressions(self) -> list[Expression]:
        """Every expression in this file's scope that reads no signal: all but the
        arguments of modulated sources and two-ports, and relations."""
        expressions = [p.value for p in self.parameters.values() if p.value is not None]
        expressions += [
            c.argument
            for c in self.components.values()
            if c.argument is not None and not _reads_signals(c)
        ]
        expressions += [b.value for d in self.parsed.subsystems for b in d.bindings]
        return expressions

    def _reading(self) -> list[Expression]:
        """The expressions that may read signals: modulated arguments and relations."""
        read = [c.argument for c in self.components.values() if _reads_signals(c)]
        for c in self.components.values():
            if c.relation is not None:
                read += [r.expression for r in c.relation.given]
        # a relation that broke a rule still has its parameters checked
        read += [
            r.expression
            for use in self.parsed.mentions
            for r in use.relations
            if self.components.get(use.name) is None or self.components[use.name].relation is None
        ]
        return [m for m in read if m is not None]

    def check_names(self) -> None:
        for expression in self._expressions() + self._reading():
            for use in expression.names:
                if use.name in self.parameters:
                    continue
                hint = (
                    " (s, the Laplace variable, cannot appear in a parameter)"
                    if use.name == "s"
                    else ""
                )
                self.report(
                    "undeclared_parameter",
                    f"parameter {use.name!r} is not declared{hint}",
                    use.position,
                )

    def check_signals(self) -> None:
        """Signals only in the arguments of modulated sources and two-ports (any function of
        them) and in relations, each of a component that has it (a subsystem's, dotted,
        are checked later)."""
        for component in self.components.values():
            if _reads_signals(component) and component.argument is not None:
                self._check_modulation(component.argument)
        for expression in self._expressions():
            if expression.signals:
                self.report(
                    "bad_signal",
                    f"{expression.signals[0].text} is a signal: signals are read only in the "
                    "argument of an MSe, MSf, TF or GY (and an R, C or I relates its own "
                    "variables in a relation, VAR = EXPR)",
                    expression.signals[0].position,
                )
            elif expression.signal_problem:
                problem = expression.signal_problem
                self.report("bad_signal", problem.message, problem.position)

    def _check_modulation(self, argument: Expression) -> None:
        if argument.signal_problem and argument.signal_problem.malformed:
            problem = argument.signal_problem
            self.report("bad_signal", problem.message, problem.position)
        for use in argument.signals:
            if "." in use.target:
                continue
            target = self.components.get(use.target)
            if target is None:
                self.report(
                    "undeclared_component",
                    f"{use.text} reads component {use.target!r}, which is not declared",
                    use.position,
                )
            elif not signal_readable(use.kind, target.type):
                self.report("bad_signal", unreadable(use, target.type), use.position)

    def check_cycles(self) -> None:
        """Parameter values that depend on each other in a cycle: found by the standard
        library's topological sort; networkx, which takes time to import, names each group
        of them only when there is one."""
        depends = {
            p.name: {u.name for u in p.value.names if u.name in self.parameters}
            if p.value
            else set()
            for p in self.parameters.values()
        }
        try:
            TopologicalSorter(depends).prepare()
            return
        except CycleError:
            import networkx as nx
        graph = nx.DiGraph([(a, b) for a, targets in depends.items() for b in targets])
        for group in nx.strongly_connected_components(graph):
            first = min(group, key=lambda n: self.parameters[n].position)
            if len(group) > 1 or graph.has_edge(first, first):
                names = ", ".join(sorted(group))
                self.report(
                    "cyclic_definition",
                    f"the values of {names} depend on each other in a cycle",
                    self.parameters[first].position,
                )

    def _valid(self, end: ComponentUse | PortUse, counted: bool = False) -> bool:
        """A mention of a component that exists with this type, or of a subsystem's port
        (else it is reported). Any port counts in its neighbour's number of bonds: a wrong
        one is reported once, as itself."""
        if isinstance(end, PortUse):
            return counted or end.port in self._ports(end.subsystem)
        component = self.components.get(end.name)
        return component is not None and component.type.name == end.type

    def check_bonds(self) -> None:
        inward, outward = Counter(), Counter()
        for bond in self.parsed.bonds:
            if bond.tail.name == bond.head.name:
                self.report("self_bond", f"a bond from {bond.tail.label} to itself", bond.position)
            if self._valid(bond.tail) and self._valid(bond.head):
                self.bonds.append(LocalBond(bond.tail.name, bond.head.name, bond.position))
            if self._valid(bond.tail, counted=True) and self._valid(bond.head, counted=True):
                outward[bond.tail.name] += 1
                inward[bond.head.name] += 1
        for name, component in self.components.items():
            ins, outs = inward[name], outward[name]
            rule = component.type.ports
            if ins + outs == 0:
                self.report(
                    "unconnected_component",
                    f"{component.label} is not connected to any bond",
                    component.position,
                )
            elif rule is PortRule.ONE and ins + outs != 1:
                self.report(
                    "bad_arity",
                    f"{component.label} is a one-port but has {ins + outs} bonds",
                    component.position,
                )
            elif rule is PortRule.TWO and (ins, outs) != (1, 1):
                self.report(
                    "bad_two_port",
                    f"{component.label} needs one inward and one "
                    f"outward bond, not {ins} inward and {outs} outward",
                    component.position,
                )

    def check_direction(self) -> None:
        degree = Counter(end for b in self.bonds for end in (b.tail, b.head))
        heads = Counter(b.head for b in self.bonds)
        for name, component in self.components.items():
            usual = component.type.conventional_inward
            if usual is None or degree[name] != 1:
                continue
            if (heads[name] == 1) != usual:
                way = "out of" if usual else "into"
                effect = (
                    "which makes it an active element"
                    if component.type.role in (Role.STORAGE, Role.RESISTOR)
                    else "which reverses the sign its variable enters the junctions with (the "
                    "transfer function changes sign)"
                )
                self.warnings.append(
                    warning(
                        "bond_direction",
                        f"the bond of {component.label} points {way} it, {effect}",
                        component.position,
                        self.origin,
                    )
                )
