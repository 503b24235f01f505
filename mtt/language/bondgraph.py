"""Stage 2: `ParsedModel` -> `BondGraph`, a validated networkx multigraph.

One node per component and one edge per bond (tail -> head is the direction of
positive power, keyed by the bond's number in file order). Validation reports every
problem it can find in one pass, each with its kind and place.
"""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass
from types import MappingProxyType

import networkx as nx
import sympy

from mtt.language.components import LIBRARY, ComponentType, PortRule, Role
from mtt.language.diagnostics import (
    Diagnostic,
    ModelError,
    Origin,
    Position,
    Severity,
    Source,
    error,
    warning,
)
from mtt.language.expressions import SIGNALS, SignalUse
from mtt.language.parse import (
    RESERVED,
    ComponentUse,
    Expression,
    NameUse,
    ParsedModel,
    PortDecl,
)


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
class Bond:
    number: int
    tail: str
    head: str
    position: Position


@dataclass(frozen=True)
class Port:
    """A bond as one of its components sees it."""

    bond: int
    inward: bool


@dataclass(frozen=True)
class Selection:
    """What the command line chooses over the file: the unknowns (in order), the input and
    the output (TYPE:NAME)."""

    unknowns: tuple[str, ...] | None = None  # None: the `unknown` declarations, in order
    input: str | None = None
    output: str | None = None


@dataclass(frozen=True)
class BondGraph:
    source: Source
    name: str
    description: str | None
    graph: nx.MultiDiGraph
    parameters: MappingProxyType  # name -> Parameter, in file order
    input: str
    output: str
    unknowns: tuple[str, ...]  # the parameters to identify, in order
    warnings: tuple[Diagnostic, ...]

    def component(self, name: str) -> Component:
        return self.graph.nodes[name]["component"]

    @property
    def components(self) -> tuple[Component, ...]:
        return tuple(data["component"] for _, data in self.graph.nodes(data=True))

    @property
    def bonds(self) -> tuple[Bond, ...]:
        edges = self.graph.edges(keys=True, data=True)
        return tuple(sorted((data["bond"] for *_, data in edges), key=lambda b: b.number))

    def ports(self, name: str) -> tuple[Port, ...]:
        """A component's bonds in port order: by bond number, a two-port's inward bond first."""
        inward = [Port(k, True) for _, _, k in self.graph.in_edges(name, keys=True)]
        outward = [Port(k, False) for _, _, k in self.graph.out_edges(name, keys=True)]
        if self.component(name).type.ports is PortRule.TWO:
            return tuple(inward + outward)
        return tuple(sorted(inward + outward, key=lambda p: p.bond))

    def bond(self, number: int) -> Bond:
        return next(b for b in self.bonds if b.number == number)


def signal_readable(kind: str, target: ComponentType) -> bool:
    """e(X) reads a 0-junction's common effort or a one-port's; f(X) a 1-junction's flow."""
    junction = "0" if kind == "e" else "1"
    return target.name == junction or target.ports is PortRule.ONE


def _unreadable(use: SignalUse, target: ComponentType) -> str:
    variable = SIGNALS[use.kind]
    if target.role is Role.JUNCTION:
        other = "f" if use.kind == "e" else "e"
        return (
            f"{use.text}: a {target.summary} has no common {variable}; "
            f"read {other}({use.target}) or the {variable} of one of its one-ports"
        )
    return f"{use.text}: a {target.summary} has two {variable}s; read the junction beside it"


def _article(noun: str) -> str:
    return "an" if noun[0] in "aeiou" else "a"


def _implied_argument(use: ComponentUse) -> Expression:
    """`R:ra` means `R:ra(ra)`."""
    return Expression(sympy.Symbol(use.name), (NameUse(use.name, use.position),), use.position)


class _Checker:
    """Collects the problems of one model; each method checks one rule of the language."""

    def __init__(self, parsed: ParsedModel, selection: Selection):
        self.parsed = parsed
        self.selection = selection
        self.origin = Origin(parsed.source)
        self.problems: list[Diagnostic] = []
        self.components: dict[str, Component] = {}
        self.parameters: dict[str, Parameter] = {}

    def report(self, kind: str, message: str, position: Position | None = None) -> None:
        self.problems.append(error(kind, message, position, self.origin))

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
            if use.argument is not None:
                self._check_argument(use, kind, argument_at)
            if seen is None:
                self.components[use.name] = Component(
                    use.name, kind, use.argument, use.position, descriptions.get(use.name)
                )
            elif use.argument is not None and seen.argument is None:
                self.components[use.name] = Component(
                    seen.name, kind, use.argument, seen.position, seen.description
                )
        for name, component in self.components.items():
            if component.type.modulated and component.argument is None:
                self.report(
                    "bad_argument",
                    f"{component.label} needs an argument: the signals that modulate it, "
                    f"such as {component.type.name}:{name}(2*e(x))",
                    component.position,
                )
            elif component.type.takes_argument and component.argument is None:
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
                use.argument.position,
            )
        elif use.name in seen:
            self.report(
                "duplicate_argument",
                f"the argument of {use.label} is already given on line {seen[use.name].line}",
                use.argument.position,
            )
        else:
            seen[use.name] = use.argument.position

    def check_names(self) -> None:
        expressions = [p.value for p in self.parameters.values() if p.value is not None]
        expressions += [c.argument for c in self.components.values() if c.argument is not None]
        for expression in expressions:
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
        """Signal terms only in modulated sources' arguments, each a linear combination of
        signals of components that have them."""
        expressions = [p.value for p in self.parameters.values() if p.value is not None]
        for component in self.components.values():
            if not component.type.modulated:
                expressions.append(component.argument)
            elif component.argument is not None:
                self._check_modulation(component.argument)
        for expression in expressions:
            if expression is None:
                continue
            if expression.signals:
                self.report(
                    "bad_signal",
                    f"{expression.signals[0].text} is a signal: signals are read only in the "
                    "argument of an MSe or MSf",
                    expression.signals[0].position,
                )
            elif expression.signal_problem:
                problem = expression.signal_problem
                self.report("bad_signal", problem.message, problem.position)

    def _check_modulation(self, argument: Expression) -> None:
        if argument.signal_problem:
            problem = argument.signal_problem
            self.report("bad_signal", problem.message, problem.position)
        elif not argument.signals:
            self.report(
                "bad_signal",
                "no signal term: a modulated source's argument is a combination of signals "
                "e(X) and f(X) with coefficients",
                argument.position,
            )
        for use in argument.signals:
            target = self.components.get(use.target)
            if target is None:
                self.report(
                    "undeclared_component",
                    f"{use.text} reads component {use.target!r}, which is not declared",
                    use.position,
                )
            elif not signal_readable(use.kind, target.type):
                self.report("bad_signal", _unreadable(use, target.type), use.position)

    def check_cycles(self) -> None:
        depends = nx.DiGraph()
        for p in self.parameters.values():
            depends.add_node(p.name)
            for use in p.value.names if p.value else ():
                if use.name in self.parameters:
                    depends.add_edge(p.name, use.name)
        for group in nx.strongly_connected_components(depends):
            first = min(group, key=lambda n: self.parameters[n].position)
            if len(group) > 1 or depends.has_edge(first, first):
                names = ", ".join(sorted(group))
                self.report(
                    "cyclic_definition",
                    f"the values of {names} depend on each other in a cycle",
                    self.parameters[first].position,
                )

    def check_unknowns(self) -> tuple[str, ...]:
        chosen = self.selection.unknowns
        if chosen is None:
            return tuple(p.name for p in self.parameters.values() if p.declared_unknown)
        for name in chosen:
            if name not in self.parameters:
                self.report(
                    "undeclared_parameter",
                    f"the unknown {name!r} chosen on the command line is not a parameter "
                    "of the model",
                )
        for name in sorted({n for n in chosen if chosen.count(n) > 1}):
            self.report("duplicate_name", f"the unknown {name!r} is chosen twice")
        return tuple(dict.fromkeys(n for n in chosen if n in self.parameters))

    def check_bonds(self, graph: nx.MultiDiGraph) -> None:
        for bond in self.parsed.bonds:
            if bond.tail.name == bond.head.name:
                self.report("self_bond", f"a bond from {bond.tail.label} to itself", bond.position)
        for name, component in self.components.items():
            inward, outward = graph.in_degree(name), graph.out_degree(name)
            rule = component.type.ports
            if inward + outward == 0:
                self.report(
                    "unconnected_component",
                    f"{component.label} is not connected to any bond",
                    component.position,
                )
            elif rule is PortRule.ONE and inward + outward != 1:
                self.report(
                    "bad_arity",
                    f"{component.label} is a one-port but has {inward + outward} bonds",
                    component.position,
                )
            elif rule is PortRule.TWO and (inward, outward) != (1, 1):
                self.report(
                    "bad_two_port",
                    f"{component.label} needs one inward and one "
                    f"outward bond, not {inward} inward and {outward} outward",
                    component.position,
                )

    def check_direction(self, graph: nx.MultiDiGraph) -> list[Diagnostic]:
        notes = []
        for name, component in self.components.items():
            usual = component.type.conventional_inward
            if usual is None or graph.degree(name) != 1:
                continue
            if (graph.in_degree(name) == 1) != usual:
                way = "out of" if usual else "into"
                notes.append(
                    warning(
                        "bond_direction",
                        f"the bond of {component.label} points "
                        f"{way} it, which makes it an active element",
                        component.position,
                        self.origin,
                    )
                )
        return notes

    def choose_port(self, role: Role) -> str | None:
        """The input (or output): the command line's choice, the file's statement, or the
        only candidate."""
        kind, word = ("no_input", "input") if role is Role.SOURCE else ("no_output", "output")
        candidates = [c for c in self.components.values() if c.type.role is role]
        statements = [p for p in self.parsed.ports if p.role == word]
        for extra in statements[1:]:
            self.report("syntax", f"a second {word!r} statement", extra.position)
        override = getattr(self.selection, word)
        if override is not None:
            type_, _, name = override.partition(":")
            chosen = PortDecl(word, type_, name, None)
            how = f" (chosen with --{word})"
        elif statements:
            chosen, how = statements[0], ""
        elif len(candidates) == 1:
            return candidates[0].name
        else:
            what = "sources" if role is Role.SOURCE else "detectors"
            if not candidates:
                self.report(kind, f"the model has no {role.value} (an {word} is needed)")
            else:
                names = ", ".join(c.label for c in candidates)
                self.report(
                    kind,
                    f"several {what} ({names}): say which is the {word} with an "
                    f"'{word} TYPE:NAME' statement or --{word} TYPE:NAME",
                )
            return None
        component = self.components.get(chosen.name)
        if component is None or component.type.name != chosen.type:
            actual = f" (it is {component.label})" if component else ""
            self.report(
                "undeclared_component",
                f"{chosen.type}:{chosen.name}{how} does not exist{actual}",
                chosen.position,
            )
            return None
        if component.type.role is not role:
            what = f"a {role.value}"
            if component.type.role is Role.MODULATED:
                what += " (a modulated source is never the input: its value is a signal)"
            self.report(kind, f"{component.label}{how} is not {what}", chosen.position)
            return None
        return chosen.name


def build(parsed: ParsedModel, selection: Selection | None = None) -> BondGraph:
    """Validate a parsed model and build its bond graph; raise `ModelError` listing every error.

    `selection` overrides the model's `unknown` declarations and its `input` and `output`
    statements (the command line's --unknown, --input and --output).
    """
    if parsed.header is None or not parsed.bonds:
        what = "no statement" if parsed.header is None else "no bond"
        raise ModelError(parsed.source, [error("empty_model", f"the model has {what}")])
    checker = _Checker(parsed, selection or Selection())
    checker.check_parameters()
    checker.check_components()
    checker.check_names()
    checker.check_signals()
    checker.check_cycles()
    unknowns = checker.check_unknowns()

    graph = nx.MultiDiGraph()
    for name, component in checker.components.items():
        graph.add_node(
            name,
            component=component,
            type=component.type.name,
            argument=component.argument,
            position=component.position,
        )

    def valid(use: ComponentUse) -> bool:
        """A mention of a component that exists with this type (else it was reported)."""
        component = checker.components.get(use.name)
        return component is not None and component.type.name == use.type

    for number, bond in enumerate(parsed.bonds, start=1):
        if valid(bond.tail) and valid(bond.head):
            graph.add_edge(
                bond.tail.name,
                bond.head.name,
                key=number,
                bond=Bond(number, bond.tail.name, bond.head.name, bond.position),
            )
    checker.check_bonds(graph)
    input_name = checker.choose_port(Role.SOURCE)
    output_name = checker.choose_port(Role.DETECTOR)
    notes = checker.check_direction(graph)
    errors = list(dict.fromkeys(checker.problems))
    if errors:
        raise ModelError(parsed.source, sorted(errors + notes, key=_order))
    return BondGraph(
        source=parsed.source,
        name=parsed.header.name,
        description=parsed.header.description,
        graph=graph,
        parameters=MappingProxyType(dict(checker.parameters)),
        input=input_name,
        output=output_name,
        unknowns=unknowns,
        warnings=tuple(notes),
    )


def _order(diagnostic: Diagnostic):
    severity = 0 if diagnostic.severity is Severity.ERROR else 1
    return (diagnostic.key, severity)


def summary_counts(bondgraph: BondGraph) -> dict[str, int]:
    """How many components of each type, in library order."""
    counts = defaultdict(int)
    for component in bondgraph.components:
        counts[component.type.name] += 1
    return {name: counts[name] for name in LIBRARY if counts[name]}
