"""Structural problems of a causal bond graph, found before any algebra.

Causality orders the equations: every variable a component imposes is computed from the
variables it receives (and, for storage, from its state). Following those arrows from the
input u gives every variable the input can influence, whatever the parameter values; if
the output y is not among them, the transfer function is zero (`unreachable_output`). A
component whose variables lie on no path from u to y cannot change the transfer
function: an unknown that enters only such components drops out of it (`no_dependence`).
Both are structural: they hold for every value of the parameters.
"""

from __future__ import annotations

from collections import defaultdict, deque

from mtt.derivation.causality import CausalBondGraph, assign
from mtt.language.bondgraph import BondGraph, Component
from mtt.language.components import Role
from mtt.language.diagnostics import Diagnostic, ModelError, error


def _u(name: str) -> tuple:
    """The input variable a source imposes."""
    return ("u", name)


def _y(name: str) -> tuple:
    """The output variable a detector reads."""
    return ("y", name)


def _received(causal: CausalBondGraph, name: str) -> list[tuple]:
    return [
        ("f" if causal.imposes_effort(name, p.bond) else "e", p.bond)
        for p in causal.bondgraph.ports(name)
    ]


def _imposed(causal: CausalBondGraph, name: str) -> list[tuple]:
    return [
        ("e" if causal.imposes_effort(name, p.bond) else "f", p.bond)
        for p in causal.bondgraph.ports(name)
    ]


def _arrows(causal: CausalBondGraph, component: Component) -> list[tuple[tuple, tuple]]:
    """What a component's imposed variables (and its output y, its state) are computed
    from, as arrows (from, to). Junctions and transformers relate efforts to efforts and
    flows to flows; gyrators efforts to flows; a source's variable comes from the input
    (or its signals, or nothing: a source set to zero), a detector's from nothing."""
    graph, name, role = causal.bondgraph, component.name, component.type.role
    imposed, received = _imposed(causal, name), _received(causal, name)
    read = _read(graph, component)
    if role is Role.SOURCE:
        sources = [_u(name)] if name in graph.inputs else []
    elif role is Role.MODULATED:
        sources = read
    elif role is Role.DETECTOR:  # imposes a zero; the output reads the other variable
        return [(v, _y(name)) for v in received] if name in graph.outputs else []
    elif role is Role.STORAGE:  # the state and its rate, both ways (integral or derivative)
        state = [("x", name), ("dx", name)]
        return [(a, b) for a in received + state for b in imposed + state if a != b]
    elif role is Role.JUNCTION or component.type.name == "TF":  # efforts to efforts
        same = [(a, b) for kind in "ef" for a in received if a[0] == kind
                for b in imposed if b[0] == kind]  # fmt: skip
        return same + [(a, b) for a in read for b in imposed]  # a modulated TF's signals
    elif component.type.name == "GY":
        return [(a, b) for a in received for b in imposed if a[0] != b[0]] + [
            (a, b) for a in read for b in imposed
        ]
    else:  # a resistor: its effort and flow
        sources = received
    return [(a, b) for a in sources for b in imposed]


def _read(graph: BondGraph, component: Component) -> list[tuple]:
    """The bond variables the signals in a component's argument read: q(X) and p(X), the
    integrals of f(X) and e(X), are computed from them."""
    if component.argument is None or not component.argument.signals:
        return []
    integral = {"q": "f", "p": "e"}
    return [
        (integral.get(use.kind, use.kind), graph.reading(use.target))
        for use in component.argument.signals
    ]


Flow = dict[tuple, set[tuple]]  # variable -> the variables computed from it


def signal_flow(causal: CausalBondGraph) -> tuple[Flow, Flow]:
    """The arrows from each variable to those computed from it, and back."""
    forward: Flow = defaultdict(set)
    backward: Flow = defaultdict(set)
    for component in causal.bondgraph.components:
        for a, b in _arrows(causal, component):
            forward[a].add(b)
            backward[b].add(a)
    return forward, backward


def _reached(arrows: Flow, start: tuple) -> set[tuple]:
    """Every variable a chain of arrows leads to from `start` (breadth first)."""
    seen, queue = set(), deque([start])
    while queue:
        for target in arrows.get(queue.popleft(), ()):
            if target not in seen:
                seen.add(target)
                queue.append(target)
    return seen


def _unknowns_in(graph: BondGraph) -> dict[str, set[str]]:
    """The unknowns each parameter's value brings in, through the parameters it names
    (an unknown's own value is its true value: it brings in itself only)."""
    unknowns = set(graph.unknowns)
    found: dict[str, set[str]] = {}

    def of(name: str, seen: frozenset = frozenset()) -> set[str]:
        if name in unknowns:
            return {name}
        if name not in found:
            value = graph.parameters[name].value
            names = {u.name for u in value.names} if value is not None else set()
            found[name] = {
                u for n in names if n in graph.parameters and n not in seen
                for u in of(n, seen | {name})
            }  # fmt: skip
        return found[name]

    return {name: of(name) for name in graph.parameters}


def _entering(graph: BondGraph, component: Component, brought: dict) -> set[str]:
    if component.argument is not None:
        names = {use.name for use in component.argument.names}
    elif component.relation is not None:
        names = {use.name for r in component.relation.given for use in r.expression.names}
    else:
        return set()
    return {u for name in names if name in brought for u in brought[name]}


ZERO = {
    "Se": "a zero effort (a source other than the input is set to zero)",
    "Sf": "a zero flow (a source other than the input is set to zero)",
    "De": "a zero flow (a detector draws no power)",
    "Df": "a zero effort (a detector draws no power)",
}


def _unreachable(graph: BondGraph, source: Component, output: Component) -> str:
    """Why the output does not depend on the input: no chain of bonds between them, or
    one that causality cuts (a source other than the input, set to zero, or a detector
    other than the output imposes a zero the junctions between pass on)."""
    whole = f"the output {output.label} does not depend on the input {source.label}"
    zero = " (the transfer function is zero)"
    neighbours = defaultdict(set)
    for bond in graph.bonds:
        neighbours[bond.tail].add(bond.head)
        neighbours[bond.head].add(bond.tail)
    joined, queue = {source.name}, deque([source.name])
    while queue:
        for name in neighbours[queue.popleft()] - joined:
            joined.add(name)
            queue.append(name)
    if output.name not in joined:
        return (
            f"{whole}: no chain of bonds and signals leads from one to the other, whatever "
            f"the parameters{zero}"
        )
    zeros = [
        f"{c.label} imposes {ZERO[c.type.name]}"
        for c in graph.components
        if c.name in joined and c.name not in (source.name, output.name) and c.type.name in ZERO
    ]
    if not zeros:
        return f"{whole}: a chain of bonds joins them, but its causal equations carry nothing{zero}"
    return (
        f"{whole}: a chain of bonds joins them, but causality cuts it: "
        f"{'; '.join(zeros)}, and the junctions between pass it on{zero}"
    )


def structure_problems(causal: CausalBondGraph) -> list[Diagnostic]:
    """An output the inputs cannot reach (an input that reaches no output), and unknowns
    that cannot reach an output."""
    graph = causal.bondgraph
    forward, backward = signal_flow(causal)
    reached = {u: _reached(forward, _u(u)) for u in graph.inputs}
    back = {y: _reached(backward, _y(y)) | {_y(y)} for y in graph.outputs}
    problems = _unreached(graph, reached)
    if problems:
        return problems
    on_path = set().union(*reached.values()) & set().union(*back.values())
    brought = _unknowns_in(graph)
    entering: set[str] = set()
    for component in graph.components:
        if on_path & {target for _, target in _arrows(causal, component)}:
            entering |= _entering(graph, component, brought)
    return [
        error(
            "no_dependence",
            f"the unknown {name} does not enter the transfer {_between(graph)}: no component "
            "between them depends on it, so the data cannot tell its value",
            graph.parameters[name].position,
        )
        for name in graph.unknowns
        if name not in entering
    ]


def _labels(graph: BondGraph, names: tuple[str, ...]) -> str:
    return ", ".join(graph.component(name).label for name in names)


def _between(graph: BondGraph) -> str:
    """`function from Se:v to Df:w`, or `matrix from Se:v, Se:tl to Df:w, Df:i`."""
    what = "matrix" if graph.several else "function"
    return f"{what} from {_labels(graph, graph.inputs)} to {_labels(graph, graph.outputs)}"


def _unreached(graph: BondGraph, reached: dict[str, set[tuple]]) -> list[Diagnostic]:
    """Each output no input reaches; with several inputs, each input that reaches no output
    (a row, or a column, of the transfer matrix zero whatever the parameters)."""
    problems = []
    for y in graph.outputs:
        if any(_y(y) in found for found in reached.values()):
            continue
        output = graph.component(y)
        if graph.several:
            message = (
                f"the output {output.label} depends on none of the inputs "
                f"({_labels(graph, graph.inputs)}): no chain of bonds and signals leads from "
                "one to it, whatever the parameters (its row of the transfer matrix is zero)"
            )
        else:
            message = _unreachable(graph, graph.component(graph.inputs[0]), output)
        problems.append(error("unreachable_output", message, output.position))
    for u in graph.inputs if len(graph.inputs) > 1 else ():
        if not any(_y(y) in reached[u] for y in graph.outputs):
            source = graph.component(u)
            message = (
                f"the input {source.label} reaches none of the outputs "
                f"({_labels(graph, graph.outputs)}): no chain of bonds and signals leads from "
                "it to one, whatever the parameters (its column of the transfer matrix is zero)"
            )
            problems.append(error("unreachable_output", message, source.position))
    return problems


def causal_for(graph: BondGraph, identify: bool = False) -> CausalBondGraph:
    """Bond graph -> causal bond graph, free of structural problems: an output the input
    does not reach; when the unknowns are to be identified (`identify`), an unknown that
    cannot reach the output either."""
    causal = assign(graph)
    problems = [p for p in structure_problems(causal) if identify or p.kind == "unreachable_output"]
    if problems:
        raise ModelError(graph.source, problems)
    return causal
