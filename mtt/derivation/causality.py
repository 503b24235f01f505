"""Stage 3: `BondGraph` -> `CausalBondGraph`, by the sequential causality assignment procedure.

Causality says, for every bond, which end imposes the effort (the other end imposes
the flow); the causal stroke is drawn at the end that receives the effort. The
procedure (Karnopp and Rosenberg) assigns the fixed causality of sources and
detectors, then preferred (integral) causality of C and I one at a time, then an
arbitrary causality for any resistor still free, propagating the consequences
through junctions, TF and GY after each choice. A storage element forced into
derivative causality is a dependent state; each arbitrary resistor choice marks an
algebraic loop. When a choice leads to a conflict later, the procedure backtracks to try
the other causality, so a causal assignment is found whenever one exists. Two elements
imposing the same variable (no assignment at all) is a `causal_conflict`.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from types import MappingProxyType

from mtt.language.bondgraph import BondGraph, Component
from mtt.language.components import CausalKind, PortRule, Role
from mtt.language.diagnostics import ModelError, error

# Backtracking over free causal choices gives up (with the first conflict) after this many
# failed attempts: the search is exponential in the worst case.
MAX_TRIALS = 10_000


@dataclass(frozen=True)
class CausalBondGraph:
    bondgraph: BondGraph
    effort_from: MappingProxyType  # bond number -> name of the component imposing its effort
    dependent: tuple[str, ...]  # storage elements in derivative causality
    loops: tuple[str, ...]  # resistors given an arbitrary causality (algebraic loops)

    def imposes_effort(self, component: str, bond: int) -> bool:
        return self.effort_from[bond] == component

    def stroke_at(self, bond: int) -> str:
        """The component at the end of the bond that receives the effort."""
        b = self.bondgraph.bond(bond)
        return b.head if self.effort_from[bond] == b.tail else b.tail

    def integral(self, component: str) -> bool:
        return component not in self.dependent


class _Conflict(Exception):
    def __init__(self, component: Component, message: str):
        super().__init__(message)
        self.component = component


def _model_error(graph: BondGraph, conflict: _Conflict) -> ModelError:
    return ModelError(
        graph.source, [error("causal_conflict", str(conflict), conflict.component.position)]
    )


class _Assignment:
    """A partial causal assignment, propagated to a fixed point after every choice."""

    def __init__(self, graph: BondGraph):
        self.graph = graph
        self.effort_from: dict[int, str] = {}
        self.cause: dict[int, str] = {}  # bond -> the component whose choice set it
        self.choosing = ""
        self.chosen: tuple[str, ...] = ()  # components whose causality was a free choice

    def copy(self) -> _Assignment:
        other = _Assignment(self.graph)
        other.effort_from, other.cause = dict(self.effort_from), dict(self.cause)
        other.chosen = self.chosen
        return other

    def _conflict(self, bonds: list[int], what: str, claimant: str) -> _Conflict:
        """Name the elements whose choices collide (not just the junction where they meet)."""
        if self.graph.component(claimant).type.ports is not PortRule.ONE:
            claimant = self.choosing
        causes = list(dict.fromkeys([self.cause[b] for b in bonds if b in self.cause] + [claimant]))
        labels = " and ".join(self.graph.component(c).label for c in causes)
        verb = "both impose" if len(causes) > 1 else "imposes"
        return _Conflict(self.graph.component(causes[-1]), f"{labels} {verb} {what}")

    def imposes(self, component: str, bond: int) -> bool | None:
        owner = self.effort_from.get(bond)
        return None if owner is None else owner == component

    def _other_end(self, component: str, bond: int) -> str:
        b = self.graph.bond(bond)
        return b.head if b.tail == component else b.tail

    def choose(self, component: str, bond: int, imposes_effort: bool) -> None:
        """Set one bond's causality and propagate; raise `_Conflict` if that is impossible."""
        queue = deque()
        self.choosing = component
        self._set(component, bond, imposes_effort, queue)
        while queue:
            self._propagate(queue.popleft(), queue)

    def _set(self, component: str, bond: int, imposes_effort: bool, queue: deque) -> None:
        owner = component if imposes_effort else self._other_end(component, bond)
        current = self.effort_from.get(bond)
        if current is None:
            self.effort_from[bond] = owner
            self.cause[bond] = self.choosing
            queue.extend((component, self._other_end(component, bond)))
        elif current != owner:
            b = self.graph.bond(bond)
            ends = f"{self.graph.component(b.tail).label} -> {self.graph.component(b.head).label}"
            variable = "effort" if imposes_effort else "flow"
            raise self._conflict([bond], f"the {variable} on bond {bond} ({ends})", component)

    def _propagate(self, name: str, queue: deque) -> None:
        component = self.graph.component(name)
        rule = component.type.causality
        ports = [p.bond for p in self.graph.ports(name)]
        states = [self.imposes(name, b) for b in ports]
        if rule.kind is CausalKind.FIXED:
            self._set(name, ports[0], rule.imposes_effort, queue)
        elif rule.kind in (CausalKind.SAME, CausalKind.OPPOSITE):
            known = [(b, v) for b, v in zip(ports, states, strict=True) if v is not None]
            if known:
                bond, value = known[0]
                other = ports[1] if bond == ports[0] else ports[0]
                self._set(name, other, value if rule.kind is CausalKind.SAME else not value, queue)
        elif rule.kind is CausalKind.EXACTLY_ONE:
            self._junction(name, component, ports, states, rule.imposes_effort, queue)

    def _junction(self, name, component, ports, states, special, queue) -> None:
        """Exactly one bond of a junction has `imposes == special` (0: effort in; 1: flow in)."""
        chosen = [b for b, v in zip(ports, states, strict=True) if v == special]
        free = [b for b, v in zip(ports, states, strict=True) if v is None]
        variable = "effort" if component.type.name == "0" else "flow"
        if len(chosen) > 1:
            raise self._conflict(chosen, f"the {variable} of {component.label}", name)
        if chosen:
            for bond in free:
                self._set(name, bond, not special, queue)
        elif len(free) == 1:
            self._set(name, free[0], special, queue)
        elif not free:
            raise self._conflict(
                ports,
                f"causality that leaves the {variable} of {component.label} undetermined",
                name,
            )


def assign(graph: BondGraph) -> CausalBondGraph:
    """Sequential causality assignment; raise `ModelError` (causal_conflict) if impossible."""
    state = _Assignment(graph)
    by_role = {role: [c for c in graph.components if c.type.role is role] for role in Role}

    # A junction with a single bond fixes that bond's causality as a source does (a
    # 0-junction sets its flow to zero, a 1-junction its effort): it goes first too.
    ends = [c for c in by_role[Role.JUNCTION] if len(graph.ports(c.name)) == 1]
    fixed = by_role[Role.SOURCE] + by_role[Role.MODULATED] + by_role[Role.DETECTOR]
    for component in fixed + ends:
        port = graph.ports(component.name)[0].bond
        try:
            state.choose(component.name, port, component.type.causality.imposes_effort)
        except _Conflict as conflict:
            raise _model_error(graph, conflict) from None

    state = _complete(state, _decisions(graph, by_role))
    dependent = tuple(
        c.name
        for c in by_role[Role.STORAGE]
        if state.imposes(c.name, graph.ports(c.name)[0].bond) != c.type.causality.imposes_effort
    )
    return CausalBondGraph(
        graph,
        MappingProxyType(dict(sorted(state.effort_from.items()))),
        dependent,
        tuple(c for c in state.chosen if graph.component(c).type.role is Role.RESISTOR),
    )


def _decisions(graph: BondGraph, by_role: dict) -> list[tuple[str, int, bool]]:
    """The free choices, in the order of the procedure: (component, bond, preferred causality).

    Storage prefers integral causality; a resistor has no preference (imposing its effort,
    e = r f, is tried first, as it also suits r = 0); then any bond left between junctions
    and two-ports.
    """
    choices = [
        (c.name, graph.ports(c.name)[0].bond, c.type.causality.imposes_effort is not False)
        for c in by_role[Role.STORAGE] + by_role[Role.RESISTOR]
    ]
    return choices + [(b.tail, b.number, True) for b in graph.bonds]


def _complete(state: _Assignment, decisions: list[tuple[str, int, bool]]) -> _Assignment:
    """Make the decisions in order, preferred causality first, backtracking on a conflict.

    The sequential procedure alone can paint itself into a corner (a choice that only a
    later conflict shows to be wrong); backtracking finds an assignment whenever one exists
    (within `MAX_TRIALS` attempts) and otherwise reports the first conflict met, which is
    the one the sequential procedure reports.
    """
    graph = state.graph
    conflicts: list[_Conflict] = []
    # one frame per decision taken: the state before it, its index, the values left to try
    frames: list[tuple[_Assignment, int, list[bool]]] = []
    index = 0
    while True:
        while index < len(decisions) and state.imposes(*decisions[index][:2]) is not None:
            index += 1
        if index == len(decisions):
            return state
        frames.append((state, index, [decisions[index][2], not decisions[index][2]]))
        state = None
        while frames and state is None and len(conflicts) <= MAX_TRIALS:
            before, at, values = frames[-1]
            if not values:
                frames.pop()
                continue
            component, bond, _ = decisions[at]
            trial = before.copy()
            try:
                trial.choose(component, bond, values.pop(0))
            except _Conflict as conflict:
                conflicts.append(conflict)
                continue
            trial.chosen = before.chosen + (component,)
            state, index = trial, at + 1
        if state is None:
            raise _model_error(graph, conflicts[0])


def describe(causal: CausalBondGraph) -> str:
    """The bonds with their causal strokes, then dependent storage and algebraic loops."""
    graph = causal.bondgraph
    lines = [f"causality of {graph.name} (| marks the end of a bond that receives the effort)"]
    for bond in graph.bonds:
        tail, head = graph.component(bond.tail).label, graph.component(bond.head).label
        arrow = "->|" if causal.stroke_at(bond.number) == bond.head else "|->"
        lines.append(f"  {bond.number:>3}  {tail} {arrow} {head}")
    dependent = ", ".join(graph.component(n).label for n in causal.dependent) or "none"
    loops = ", ".join(graph.component(n).label for n in causal.loops) or "none"
    lines.append(f"dependent storage (derivative causality): {dependent}")
    lines.append(f"algebraic loops (resistors with an arbitrary causality): {loops}")
    return "\n".join(lines)
