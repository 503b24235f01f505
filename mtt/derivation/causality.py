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

The work is near-linear in the number of bonds: a junction keeps counts of its bonds
still open and of those that carry its common variable in, so that propagating through
it costs O(1) per bond; choices are undone from a trail, not by copying the assignment;
and backtracking is conflict-directed: every forced bond remembers the bonds that forced
it, so a conflict names the choices it follows from, and the search jumps back to the
latest of those, over every choice that had nothing to do with it (Prosser's conflict-
directed backjumping: the assignment found is the one plain backtracking finds).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from types import MappingProxyType

from mtt.language.bondgraph import BondGraph, Component
from mtt.language.components import CausalKind, PortRule, Role
from mtt.language.diagnostics import ModelError, error

# Backtracking over free causal choices gives up (with the first conflict) after this many
# failed attempts: the search can still be exponential in the worst case.
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

    @property
    def order(self) -> int:
        """The number of storage elements in integral causality: the order of the state
        equations (of G(s), but for cancellations)."""
        graph = self.bondgraph
        storage = [c for c in graph.components if c.type.role is Role.STORAGE]
        return len(storage) - len(self.dependent)


class _Conflict(Exception):
    """Two elements impose one variable; `bonds` are the bonds the clash is made of."""

    def __init__(self, component: Component, message: str, bonds: tuple[int, ...]):
        super().__init__(message)
        self.component = component
        self.bonds = bonds


def _model_error(graph: BondGraph, conflict: _Conflict) -> ModelError:
    return ModelError(
        graph.source, [error("causal_conflict", str(conflict), conflict.component.position)]
    )


class _Assignment:
    """A partial causal assignment, propagated to a fixed point after every choice, with
    the trail of its bonds in the order they were set (and why), to undo choices."""

    def __init__(self, graph: BondGraph, strict: bool = True):
        self.graph = graph
        self.strict = strict  # relations used only the ways they can be (else: any way)
        self.effort_from: dict[int, str] = {}
        self.cause: dict[int, str] = {}  # bond -> the component whose choice set it
        self.level: dict[int, int] = {}  # bond -> the number of choices made when it was set
        self.reasons: dict[int, tuple[int, ...]] = {}  # bond -> the bonds that forced it
        self.trail: list[int] = []
        self.choosing = ""
        self.depth = 0  # choices made
        self.ports = {c.name: tuple(p.bond for p in graph.ports(c.name)) for c in graph.components}
        # for each junction: its bonds not set yet, and those with `imposes == special`
        self.open = {name: len(bonds) for name, bonds in self.ports.items()}
        self.special = dict.fromkeys(self.ports, 0)

    def _special(self, component: str, bond: int) -> bool:
        """Does this bond bring the junction's common variable in (0: effort, 1: flow)?"""
        return (
            self.imposes(component, bond)
            == self.graph.component(component).type.causality.imposes_effort
        )

    def _conflict(self, bonds: list[int], what: str, claimant: str, because=()) -> _Conflict:
        """Name the elements whose choices collide (not just the junction where they meet)."""
        if self.graph.component(claimant).type.ports is not PortRule.ONE:
            claimant = self.choosing
        causes = list(dict.fromkeys([self.cause[b] for b in bonds if b in self.cause] + [claimant]))
        labels = " and ".join(self.graph.component(c).label for c in causes)
        verb = "both impose" if len(causes) > 1 else "imposes"
        message = f"{labels} {verb} {what}"
        return _Conflict(self.graph.component(causes[-1]), message, (*bonds, *because))

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
        self._set(component, bond, imposes_effort, queue, ())
        while queue:
            self._propagate(queue.popleft(), queue)

    def _set(self, component, bond, imposes_effort: bool, queue: deque, because) -> None:
        owner = component if imposes_effort else self._other_end(component, bond)
        current = self.effort_from.get(bond)
        if current is None:
            self.effort_from[bond] = owner
            self.cause[bond] = self.choosing
            self.level[bond] = self.depth
            self.reasons[bond] = because
            self.trail.append(bond)
            ends = (component, self._other_end(component, bond))
            for end in ends:
                self.open[end] -= 1
                self.special[end] += self._special(end, bond)
            queue.extend(ends)
        elif current != owner:
            b = self.graph.bond(bond)
            ends = f"{self.graph.component(b.tail).label} -> {self.graph.component(b.head).label}"
            variable = "effort" if imposes_effort else "flow"
            what = f"the {variable} on bond {bond} ({ends})"
            raise self._conflict([bond], what, component, because)

    def undo(self, mark: int) -> None:
        """Unset every bond set since the trail had `mark` bonds."""
        while len(self.trail) > mark:
            bond = self.trail[-1]
            b = self.graph.bond(bond)
            for end in (b.tail, b.head):
                self.open[end] += 1
                self.special[end] -= self._special(end, bond)
            self.trail.pop()
            for record in (self.effort_from, self.cause, self.level, self.reasons):
                del record[bond]

    def _propagate(self, name: str, queue: deque) -> None:
        component = self.graph.component(name)
        rule = component.causality if self.strict else component.type.causality
        ports = self.ports[name]
        if rule.kind is CausalKind.FIXED:
            self._set(name, ports[0], rule.imposes_effort, queue, ())
        elif rule.kind in (CausalKind.SAME, CausalKind.OPPOSITE):
            known = [b for b in ports if b in self.effort_from]
            if known:
                bond = known[0]
                other = ports[1] if bond == ports[0] else ports[0]
                value = self.imposes(name, bond)
                same = rule.kind is CausalKind.SAME
                self._set(name, other, value if same else not value, queue, (bond,))
        elif rule.kind is CausalKind.EXACTLY_ONE:
            self._junction(name, component, ports, rule.imposes_effort, queue)

    def _junction(self, name, component, ports, special, queue) -> None:
        """Exactly one bond of a junction has `imposes == special` (0: effort in; 1: flow in)."""
        count, open_ = self.special[name], self.open[name]
        if count == 1 and not open_ or count == 0 and open_ > 1:
            return
        variable = "effort" if component.type.name == "0" else "flow"
        if count > 1:
            chosen = [b for b in ports if self.imposes(name, b) == special]
            raise self._conflict(chosen, f"the {variable} of {component.label}", name)
        if count == 1:
            (bond,) = [b for b in ports if self.imposes(name, b) == special]
            for other in [b for b in ports if b not in self.effort_from]:
                self._set(name, other, not special, queue, (bond,))
        elif open_ == 1:
            (bond,) = [b for b in ports if b not in self.effort_from]
            self._set(name, bond, special, queue, tuple(b for b in ports if b != bond))
        else:
            raise self._conflict(
                list(ports),
                f"causality that leaves the {variable} of {component.label} undetermined",
                name,
            )

    def culprits(self, conflict: _Conflict) -> set[int]:
        """The choices (numbered from 1) a conflict follows from: the levels of the choices
        found by following the bonds that forced each of its bonds back to choices."""
        levels, seen, stack = set(), set(), list(conflict.bonds)
        while stack:
            bond = stack.pop()
            if bond in seen or self.level.get(bond, 0) == 0:
                continue
            seen.add(bond)
            reasons = self.reasons[bond]
            if reasons:
                stack.extend(reasons)
            else:  # set by a choice itself
                levels.add(self.level[bond])
        return levels


def assign(graph: BondGraph) -> CausalBondGraph:
    """Sequential causality assignment; raise `ModelError` (causal_conflict) if impossible,
    or (no_inverse) if it is possible only with a relation used the way it cannot be."""
    try:
        return _assign(graph, strict=True)
    except ModelError as found:
        conflict = found
        one_way = [c for c in graph.components if c.causality != c.type.causality]
        if not one_way:
            raise
        try:
            relaxed = _assign(graph, strict=False)
        except ModelError:
            raise conflict from None
    problems = []
    for component in one_way:
        bond = graph.ports(component.name)[0].bond
        imposes = relaxed.imposes_effort(component.name, bond)
        if imposes == component.causality.imposes_effort:
            continue
        needed = component.needs(imposes)
        given = component.relation.given[0]
        message = (
            f"{component.label} gives {given.variable} ({component.relation.text()}), but "
            f"causality makes it give {needed}, and its relation has no exact inverse: write "
            f"it {needed} = ..., or add the inverse after a comma "
            f"({component.type.name}:{component.name}({given.text()}, {needed} = ...))"
        )
        problems.append(error("no_inverse", message, given.position))
    raise ModelError(graph.source, problems) if problems else conflict


def _assign(graph: BondGraph, strict: bool) -> CausalBondGraph:
    state = _Assignment(graph, strict)
    by_role = {role: [c for c in graph.components if c.type.role is role] for role in Role}
    rule = (lambda c: c.causality) if strict else (lambda c: c.type.causality)  # noqa: E731

    # A junction with a single bond fixes that bond's causality as a source does (a
    # 0-junction sets its flow to zero, a 1-junction its effort): it goes first too; so
    # does an R, C or I whose relation can be used one way only.
    ends = [c for c in by_role[Role.JUNCTION] if len(graph.ports(c.name)) == 1]
    fixed = by_role[Role.SOURCE] + by_role[Role.MODULATED] + by_role[Role.DETECTOR]
    one_way = [
        c
        for c in by_role[Role.STORAGE] + by_role[Role.RESISTOR]
        if rule(c).kind is CausalKind.FIXED
    ]
    for component in fixed + ends + one_way:
        port = graph.ports(component.name)[0].bond
        try:
            state.choose(component.name, port, rule(component).imposes_effort)
        except _Conflict as conflict:
            raise _model_error(graph, conflict) from None

    chosen = _complete(state, _decisions(graph, by_role))
    dependent = tuple(
        c.name
        for c in by_role[Role.STORAGE]
        if state.imposes(c.name, graph.ports(c.name)[0].bond) != c.type.causality.imposes_effort
    )
    return CausalBondGraph(
        graph,
        MappingProxyType(dict(sorted(state.effort_from.items()))),
        dependent,
        tuple(c for c in chosen if graph.component(c).type.role is Role.RESISTOR),
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


@dataclass
class _Frame:
    """A choice being made: which decision, the trail before it, the values left to try,
    and the earlier choices (levels) that its failures so far follow from."""

    index: int
    mark: int
    values: list[bool]
    culprits: set[int] = field(default_factory=set)


def _complete(state: _Assignment, decisions: list[tuple[str, int, bool]]) -> list[str]:
    """Make the decisions in order, preferred causality first, backtracking on a conflict;
    return the components whose causality was chosen, in order.

    The sequential procedure alone can paint itself into a corner (a choice that only a
    later conflict shows to be wrong); backtracking finds an assignment whenever one exists
    (within `MAX_TRIALS` failed attempts) and otherwise reports the first conflict met,
    which is the one the sequential procedure reports. A choice whose values both fail is
    blamed on the latest earlier choice its conflicts follow from: the choices in between
    are not tried again, as they would fail in the same way.
    """
    frames: list[_Frame] = []
    first: _Conflict | None = None
    trials, index = 0, 0
    while True:
        while index < len(decisions) and state.imposes(*decisions[index][:2]) is not None:
            index += 1
        if index == len(decisions):
            return [decisions[frame.index][0] for frame in frames]
        preferred = decisions[index][2]
        frames.append(_Frame(index, len(state.trail), [preferred, not preferred]))
        while True:
            frame = frames[-1]
            if not frame.values:  # both values fail: back to the latest culprit
                if not frame.culprits or trials > MAX_TRIALS:
                    raise _model_error(state.graph, first)
                target = max(frame.culprits)
                culprits = frame.culprits - {target}
                del frames[target:]
                frames[-1].culprits |= culprits
                continue
            component, bond, _ = decisions[frame.index]
            state.undo(frame.mark)
            state.depth = len(frames)
            try:
                state.choose(component, bond, frame.values.pop(0))
            except _Conflict as conflict:
                trials += 1
                first = first or conflict
                frame.culprits |= state.culprits(conflict) - {len(frames)}
                continue
            break
        index = frame.index + 1


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
