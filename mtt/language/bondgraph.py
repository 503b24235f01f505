"""Stage 2: `ParsedModel` -> `BondGraph`, a validated bond graph.

The model's file and the files of its subsystems are read (`subsystems`), checked each in
its own scope (`checks`) and assembled into one flat bond graph with dotted names
(`flatten`); what concerns the whole model is checked here: the unknowns, the input and
the output. Its components and bonds (tail -> head is the direction of positive power,
numbered in model order) are kept as plain records, and each component's ports in
order; `graph` gives the same as a networkx multigraph, built when asked for (networkx
takes longer to import than `mtt check` takes to run). Validation reports every problem
it can find in one pass, each with its kind, file and place.
"""

from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass, field
from functools import cached_property
from types import MappingProxyType
from typing import TYPE_CHECKING

from mtt.language.checks import FileCheck
from mtt.language.components import LIBRARY, PortRule, Role
from mtt.language.diagnostics import (
    Diagnostic,
    ModelError,
    Position,
    Severity,
    Source,
    error,
)
from mtt.language.elements import Component, Parameter
from mtt.language.expressions import Expression
from mtt.language.flatten import Assembly, Bond, assemble
from mtt.language.model_values import check_values
from mtt.language.parse import ParsedModel, PortDecl
from mtt.language.subsystems import Instance, load_tree

if TYPE_CHECKING:
    import networkx as nx

__all__ = ["Bond", "BondGraph", "Component", "Parameter", "Port", "Selection", "build"]


@dataclass(frozen=True)
class Port:
    """A bond as one of its components sees it."""

    bond: int
    inward: bool


Chosen = str | tuple[str, ...] | None  # TYPE:NAME, several as a tuple or "Se:v,Se:tl"


def chosen_names(chosen: Chosen) -> tuple[str, ...]:
    """The TYPE:NAMEs of an --input or --output choice, in order."""
    if chosen is None:
        return ()
    names = chosen.split(",") if isinstance(chosen, str) else chosen
    return tuple(name.strip() for name in names if name.strip())


@dataclass(frozen=True)
class Selection:
    """What the command line chooses over the file: the unknowns (in order), the input and
    the output (TYPE:NAME; several sources for several inputs, several detectors for several
    outputs), and the directories subsystem files may also come from."""

    unknowns: tuple[str, ...] | None = None  # None: the `unknown` declarations, in order
    input: Chosen = None
    output: Chosen = None
    include: tuple[str, ...] = ()  # --include DIR: beyond the model's tree and shipped parts


@dataclass(frozen=True)
class Subsystem:
    """A subsystem of the model, for reports: `mtt show` draws their tree."""

    name: str  # dotted: motor, motor.brush
    file: str  # the file read, as reported
    bindings: tuple[tuple[str, Expression], ...]  # the parameters its parent sets
    description: str | None


@dataclass(frozen=True)
class BondGraph:
    source: Source
    name: str
    description: str | None
    named: MappingProxyType  # name -> Component, in model order
    bonds: tuple[Bond, ...]  # by number
    parameters: MappingProxyType  # name -> Parameter, in model order
    input: str | None  # the (first) input; None only in a part (see `open_ports`)
    output: str | None  # the (first) output
    unknowns: tuple[str, ...]  # the parameters to identify, in order
    warnings: tuple[Diagnostic, ...]
    subsystems: tuple[Subsystem, ...] = ()  # depth first, in file order
    port_bonds: MappingProxyType = field(default_factory=lambda: MappingProxyType({}))
    # each SS port -> the bond it joined
    name_position: Position | None = None  # the model's name in its `model` statement
    inputs: tuple[str, ...] = ()  # every input, in the order chosen (input first)
    outputs: tuple[str, ...] = ()  # every output, in the order chosen (output first)

    def __post_init__(self) -> None:
        for one, several in (("input", "inputs"), ("output", "outputs")):
            if not getattr(self, several) and getattr(self, one) is not None:
                object.__setattr__(self, several, (getattr(self, one),))

    @property
    def several(self) -> bool:
        """Several inputs or several outputs: a transfer matrix, not a transfer function."""
        return len(self.inputs) > 1 or len(self.outputs) > 1

    def component(self, name: str) -> Component:
        return self.named[name]

    @property
    def components(self) -> tuple[Component, ...]:
        return tuple(self.named.values())

    @property
    def files(self) -> tuple[str, ...]:
        """The files the model was read from: its own and its subsystems' (as named)."""
        return (self.source.name, *dict.fromkeys(s.file for s in self.subsystems))

    @property
    def open_ports(self) -> tuple[str, ...]:
        """A part's own SS ports, bonded on one side only (none in a model)."""
        return tuple(c.name for c in self.named.values() if c.type.role is Role.PORT)

    @cached_property
    def graph(self) -> nx.MultiDiGraph:
        """The bond graph as a networkx multigraph: a node per component (its `component`
        attribute), an edge tail -> head per bond keyed by its number (`bond` attribute)."""
        import networkx as nx

        graph = nx.MultiDiGraph()
        for name, component in self.named.items():
            graph.add_node(name, component=component)
        for bond in self.bonds:
            graph.add_edge(bond.tail, bond.head, key=bond.number, bond=bond)
        return graph

    @cached_property
    def _by_number(self) -> dict[int, Bond]:
        return {b.number: b for b in self.bonds}

    @cached_property
    def _ports(self) -> dict[str, tuple[Port, ...]]:
        """Each component's bonds in port order: by bond number, a two-port's inward bond
        first."""
        inward: dict[str, list[Port]] = {name: [] for name in self.named}
        outward: dict[str, list[Port]] = {name: [] for name in self.named}
        for bond in self.bonds:
            outward[bond.tail].append(Port(bond.number, False))
            inward[bond.head].append(Port(bond.number, True))
        ports = {}
        for name, component in self.named.items():
            both = inward[name] + outward[name]
            two = component.type.ports is PortRule.TWO
            ports[name] = tuple(both if two else sorted(both, key=lambda p: p.bond))
        return ports

    def ports(self, name: str) -> tuple[Port, ...]:
        """A component's bonds in port order: by bond number, a two-port's inward bond first."""
        return self._ports[name]

    def bond(self, number: int) -> Bond:
        return self._by_number[number]

    def reading(self, target: str) -> int:
        """The bond whose variable a signal of `target` reads (a junction's first: all its
        bonds share it; an SS port's: the bond it joined)."""
        if target in self.port_bonds:
            return self.port_bonds[target]
        return self.ports(target)[0].bond


class _Whole:
    """The rules about the whole model: its unknowns, its input and its output."""

    def __init__(self, root: Instance, assembly: Assembly, selection: Selection, part: bool):
        self.part = part  # a part needs no input or output
        self.parsed = root.parsed
        self.assembly = assembly
        self.selection = selection
        self.problems: list[Diagnostic] = []
        # with a subsystem that could not be read (reported), sources and detectors may be
        # missing: the input and output are then not looked for
        self.complete = all(
            {d.name for d in i.parsed.subsystems} == set(i.children) for i in root.walk()
        )

    def report(self, kind: str, message: str, position=None) -> None:
        self.problems.append(error(kind, message, position))

    def unknowns(self) -> tuple[str, ...]:
        parameters = self.assembly.parameters
        chosen = self.selection.unknowns
        if chosen is None:
            return tuple(p.name for p in parameters.values() if p.declared_unknown)
        for name in chosen:
            if name not in parameters:
                self.report(
                    "undeclared_parameter",
                    f"the unknown {name!r} chosen on the command line is not a parameter "
                    "of the model",
                )
        for name in sorted({n for n in chosen if chosen.count(n) > 1}):
            self.report("duplicate_name", f"the unknown {name!r} is chosen twice")
        return tuple(dict.fromkeys(n for n in chosen if n in parameters))

    def choose_port(self, role: Role) -> tuple[str, ...]:
        """The inputs (or outputs): the command line's choice, the model file's statement,
        or the only candidate (in any file: subsystems' sources and detectors count)."""
        kind, word = ("no_input", "input") if role is Role.SOURCE else ("no_output", "output")
        components = self.assembly.components
        candidates = [c for c in components.values() if c.type.role is role]
        statements = [p for p in self.parsed.ports if p.role == word]
        for extra in statements[1:]:
            self.report("syntax", f"a second {word!r} statement", extra.position)
        override = chosen_names(getattr(self.selection, word))
        if not self.complete:
            return ()
        if override:
            how = f" (chosen with --{word})"
            chosen = [PortDecl(word, *name.partition(":")[::2], None) for name in override]
            for name in sorted({n for n in override if override.count(n) > 1}):
                self.report("duplicate_name", f"the {word} {name} is chosen twice")
        elif statements:
            chosen, how = statements[:1], ""
        elif len(candidates) == 1:
            return (candidates[0].name,)
        elif self.part:
            return ()
        else:
            what = "sources" if role is Role.SOURCE else "detectors"
            if not candidates:
                self.report(kind, f"the model has no {role.value} (an {word} is needed)")
            else:
                names = ", ".join(c.label for c in candidates)
                self.report(
                    kind,
                    f"several {what} ({names}): say which is the {word} with an "
                    f"'{word} TYPE:NAME' statement or --{word} TYPE:NAME (several: "
                    f"--{word} TYPE:NAME,TYPE:NAME)",
                )
            return ()
        found = [self._port(declaration, role, kind, how) for declaration in chosen]
        if None in found:
            return ()
        return tuple(dict.fromkeys(found))

    def _port(self, chosen: PortDecl, role: Role, kind: str, how: str) -> str | None:
        """The component a statement or an option names, if it is a source (detector)."""
        component = self.assembly.components.get(chosen.name)
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


def values_problems(parameters: dict, components, symbolic, overrides=None) -> list[Diagnostic]:
    """The limits (see `measures`) of every parameter's value with the values it names put
    in, and of every component's argument with those of the parameters not kept `symbolic`
    (nor without a value) put in; `overrides`: measures of values given on the command line."""
    values = {name: p.value for name, p in parameters.items()}
    values.update(overrides or {})
    arguments = [c.argument for c in components if c.argument is not None]
    arguments += [
        r.expression for c in components if c.nonlinear_relation for r in c.relation.given
    ]
    return check_values(values, (), ()) + check_values(values, symbolic, arguments)


def _check_files(root: Instance, part: bool) -> dict[str, FileCheck]:
    """Each instance checked in its own scope, its subsystems first."""
    checks: dict[str, FileCheck] = {}
    for instance in reversed(list(root.walk())):
        children = {name: checks[child.name] for name, child in instance.children.items()}
        checks[instance.name] = FileCheck(instance, children, part and instance is root)
    return checks


def _once(diagnostics: list[Diagnostic]) -> list[Diagnostic]:
    """Each problem once (a file used as several subsystems reports its own once), in model
    order, errors before warnings at one place."""
    order = lambda d: (d.key, d.severity is not Severity.ERROR)  # noqa: E731
    unique = {(d.file, d.position, d.kind, d.message): d for d in sorted(diagnostics, key=order)}
    return list(unique.values())


def build(parsed: ParsedModel, selection: Selection | None = None, part: bool = False) -> BondGraph:
    """Validate a parsed model (and its subsystems) and build its bond graph; raise
    `ModelError` listing every error.

    `selection` overrides the model's `unknown` declarations and its `input` and `output`
    statements (the command line's --unknown, --input and --output). With `part`, a file
    with SS ports of its own is a part, checked (and drawn) alone: its ports stay open
    ends, and it needs no input or output (its sources and detectors are its parent's).
    """
    if parsed.header is None or not parsed.bonds:
        what = "no statement" if parsed.header is None else "no bond"
        raise ModelError(parsed.source, [error("empty_model", f"the model has {what}")])
    selection = selection or Selection()
    root, problems = load_tree(parsed, selection.include)
    checks = _check_files(root, part)
    assembly = assemble(root, checks)
    part = part and any(c.type.role is Role.PORT for c in checks[root.name].components.values())
    whole = _Whole(root, assembly, selection, part)
    unknowns = whole.unknowns()
    inputs = whole.choose_port(Role.SOURCE)
    outputs = whole.choose_port(Role.DETECTOR)
    for check in checks.values():
        problems += check.problems
    problems += assembly.problems + whole.problems
    if not problems:  # every name known, no cycle: the values can be put in
        problems += values_problems(assembly.parameters, assembly.components.values(), unknowns)
    warnings = [w for check in checks.values() for w in check.warnings]
    if problems:
        raise ModelError(parsed.source, _once(problems + warnings))
    return BondGraph(
        source=parsed.source,
        name=parsed.header.name,
        description=parsed.header.description,
        name_position=parsed.header.position,
        named=MappingProxyType(dict(assembly.components)),
        bonds=tuple(sorted(assembly.bonds, key=lambda b: b.number)),
        parameters=MappingProxyType(assembly.parameters),
        input=inputs[0] if inputs else None,
        output=outputs[0] if outputs else None,
        inputs=inputs,
        outputs=outputs,
        unknowns=unknowns,
        warnings=tuple(_once(warnings)),
        subsystems=tuple(
            Subsystem(
                instance.name,
                instance.origin.source.name,
                tuple(
                    (b.name, assembly.parameters[f"{instance.name}.{b.name}"].value)
                    for b in instance.declaration.bindings
                ),
                instance.declaration.description,
            )
            for instance in root.walk()
            if instance.declaration is not None
        ),
        port_bonds=MappingProxyType(assembly.port_bonds),
    )


def summary_counts(bondgraph: BondGraph) -> dict[str, int]:
    """How many components of each type, in library order."""
    counts = defaultdict(int)
    for component in bondgraph.components:
        counts[component.type.name] += 1
    return {name: counts[name] for name in LIBRARY if counts[name]}
