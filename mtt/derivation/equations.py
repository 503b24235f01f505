"""Stage 4: `CausalBondGraph` -> `Equations`, the descriptor state-space form.

Each component's constitutive relation (from the library) is solved for the
variables its causality makes it impose: this gives one explicit, linear equation
per bond variable. Substituting them in dependency order expresses everything in
the input u, the energy variables of storage in integral causality and the
derivatives of the dependent (derivative-causality) ones; the strongly connected
pieces of that dependency graph are the algebraic loops, solved exactly together.
The result is E x' = A x + B u, y = C x + D u with x the energy variables (q of C,
p of I), all exact, with coefficients in the field of rational functions of the
unknown and the kept symbols. With several inputs u1, u2, ... (sources) and outputs y1,
y2, ... (detectors), B and D have a column per input, C and D a row per output; one input
and one output are u and y.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cache, cached_property

import sympy
from sympy.polys.domains.domain import Domain
from sympy.polys.matrices import DomainMatrix

from mtt.derivation import deadline
from mtt.derivation.budget import DEFAULT_BUDGET, Budget, Meter, TooLarge, refusal
from mtt.derivation.causality import CausalBondGraph
from mtt.derivation.constants import Constants, Unsupported
from mtt.derivation.forms import Form, eliminate, solve, substitute
from mtt.derivation.parameters import Parametrisation
from mtt.language.bondgraph import Component
from mtt.language.components import ComponentType, PortVariables, Role
from mtt.language.diagnostics import Diagnostic, ModelError, error

INPUT, OUTPUT = "u", "y"  # the letters of the inputs' and outputs' variables


@dataclass(frozen=True)
class Equations:
    causal: CausalBondGraph
    parametrisation: Parametrisation
    domain: Domain  # the coefficient field: QQ or Q(alpha), or Q(alpha)(unknowns, symbols...)
    # the causal equations, variable = form (the relations as sympy expressions are made
    # when asked for: for a thousand parts that took as long as the rest of the stage)
    forms: tuple[tuple[str, Form], ...]
    states: tuple[str, ...]  # the descriptor variables x
    E: DomainMatrix
    A: DomainMatrix
    B: DomainMatrix
    C: DomainMatrix
    D: DomainMatrix
    budget: Budget = DEFAULT_BUDGET  # how large the transfer stage may let polynomials grow
    notes: tuple[Diagnostic, ...] = ()  # warnings about how they were made (linearisation)
    inputs: tuple[str, ...] = ()  # the sources driven, one per column of B and D
    outputs: tuple[str, ...] = ()  # the detectors read, one per row of C and D

    def __post_init__(self) -> None:
        graph = self.causal.bondgraph
        if not self.inputs:
            object.__setattr__(self, "inputs", graph.inputs)
        if not self.outputs:
            object.__setattr__(self, "outputs", graph.outputs)

    @property
    def several(self) -> bool:
        """Several inputs or outputs: a transfer matrix (see `channel`)."""
        return len(self.inputs) > 1 or len(self.outputs) > 1

    def channel(self, output: int, input: int) -> Equations:
        """The same equations from one input to one output (the other inputs at zero)."""
        return replace(
            self,
            B=self.B[:, input : input + 1],
            C=self.C[output : output + 1, :],
            D=self.D[output : output + 1, input : input + 1],
            inputs=(self.inputs[input],),
            outputs=(self.outputs[output],),
        )

    @cached_property
    def relations(self) -> tuple[tuple[str, sympy.Expr], ...]:
        """The causal equations, variable = expression ("0" = expression: a constraint)."""
        return tuple((name, _to_expr(form, self.domain)) for name, form in self.forms)

    def matrices(self) -> dict[str, sympy.Matrix]:
        """E, A, B, C, D as exact sympy matrices."""
        return {name: getattr(self, name).to_Matrix() for name in "EABCD"}


def signal_names(names: tuple[str, ...], letter: str) -> dict[str, str]:
    """Each input's (output's) variable: u (y) for one, u1, u2, ... (y1, ...) for several."""
    if len(names) == 1:
        return {names[0]: letter}
    return {name: f"{letter}{i}" for i, name in enumerate(names, 1)}


def _energy(component: Component) -> str:
    return f"{component.type.energy_prefix}_{component.name}"


def _parameter_values(causal: CausalBondGraph, parametrisation: Parametrisation):
    """Each component's exact parameter value, checked to be real, finite and rational in
    every unknown, with its constants written for the coefficient field (see `constants`);
    and what the values hold besides rational numbers."""
    graph = causal.bondgraph
    problems, values, held = [], {}, Constants()
    unknowns = [sympy.Symbol(name) for name in parametrisation.unknowns]
    for component in graph.components:
        if component.argument is None:
            continue
        value = parametrisation.apply(component.argument.value)
        where = component.argument.position
        irrational = [k for k in unknowns if not value.is_rational_function(k)]
        label = f"the parameter of {component.label}"
        if value.has(sympy.zoo, sympy.oo, sympy.nan):
            message = f"{label} is infinite ({component.argument.value} = {value})"
            problems.append(error("singular_model", message, where))
            continue
        if irrational:
            message = f"{label} is {value}, not a rational function of the unknown {irrational[0]}"
            problems.append(error("non_rational_unknown", message, where))
            continue
        try:
            values[component.name] = held.scan(value)
        except Unsupported as problem:
            problems.append(error(problem.kind, f"{label} is {value}: {problem}", where))
    if problems:
        raise ModelError(graph.source, problems)
    return values, held


def coefficient_domain(held: Constants, free: tuple[str, ...], graph, values) -> Domain:
    """The field of rational functions in the free parameters and the constants' variables,
    over QQ or the algebraic number field of the model's roots (a field too large is
    reported at the first component whose value holds one of them)."""
    try:
        ground = held.ground()
    except Unsupported as problem:
        where = next(
            (
                c.argument.position
                for c in graph.components
                if c.name in values and values[c.name].atoms(sympy.Pow) & held.algebraic
            ),
            None,
        )
        raise ModelError(graph.source, [error(problem.kind, str(problem), where)]) from None
    gens = [sympy.Symbol(name) for name in free]
    gens += [g for g in held.variables() if g not in gens]
    return ground.frac_field(*gens) if gens else ground


def _signals(graph, component: Component, value) -> tuple[tuple[str, sympy.Expr], ...]:
    """A modulated source's signals as (bond variable, coefficient): e(X) and f(X) read the
    variable of X's bond (of its first bond, for a junction, where all are equal)."""
    if not component.type.modulated:
        return ()
    uses = {use.symbol: use for use in component.argument.signals}
    return tuple(
        (f"{use.kind}{graph.reading(use.target)}", value.diff(symbol))
        for symbol, use in uses.items()
    )


def _port_variables(
    causal: CausalBondGraph, component: Component, value, signals: tuple
) -> PortVariables:
    graph = causal.bondgraph
    ports = graph.ports(component.name)
    storage = component.type.role is Role.STORAGE
    return PortVariables(
        efforts=tuple(f"e{p.bond}" for p in ports),
        flows=tuple(f"f{p.bond}" for p in ports),
        inward=tuple(p.inward for p in ports),
        parameter=value,
        energy=_energy(component) if storage else None,
        rate="d" + _energy(component) if storage else None,
        drive=signal_names(graph.inputs, INPUT).get(component.name),
        measure=signal_names(graph.outputs, OUTPUT).get(component.name),
        signals=signals,
    )


def imposed(causal: CausalBondGraph, component: Component, v: PortVariables) -> list[str]:
    """The variables a component imposes under its causality (its state's rate, or its
    energy variable in derivative causality, and the output included)."""
    ports = causal.bondgraph.ports(component.name)
    names = [
        e if causal.imposes_effort(component.name, p.bond) else f
        for p, e, f in zip(ports, v.efforts, v.flows, strict=True)
    ]
    if v.energy:
        names.append(v.rate if causal.integral(component.name) else v.energy)
    if v.measure:
        names.append(v.measure)
    return names


@deadline.timed("the equations", lambda causal: causal.bondgraph)
def derive(
    causal: CausalBondGraph, parametrisation: Parametrisation, budget: Budget = DEFAULT_BUDGET
) -> Equations:
    """The causal equations and the descriptor form.

    Variables that the causal equations cannot give explicitly (a parameter of zero, a
    degenerate algebraic loop) stay unknowns of the descriptor form, with the rows that
    were to determine them as algebraic constraints: whether the whole system has a
    unique solution is then decided by the pencil sE - A (see `transfer`).
    """
    graph = causal.bondgraph
    values, held = _parameter_values(causal, parametrisation)
    signals = {c.name: _signals(graph, c, values.get(c.name)) for c in graph.components}
    K = coefficient_domain(held, parametrisation.free, graph, values)
    explicit: dict[str, Form] = {}
    extra: list[str] = []
    constraints: list[Form] = []
    storage = [c for c in graph.components if c.type.role is Role.STORAGE]
    convert = cache(lambda value: held.element(K, value))  # most are 1, -1 and a few values

    @cache
    def relation(kind: ComponentType, v: PortVariables, outputs: tuple[str, ...]):
        rows = [{name: convert(c) for name, c in row.items()} for row in kind.relation(v)]
        return solve(rows, list(outputs), K)

    for component in graph.components:
        deadline.check()
        v = _port_variables(causal, component, values.get(component.name), signals[component.name])
        solved, free, left = _solved(component, v, imposed(causal, component, v), relation)
        explicit.update(solved)
        extra += free
        constraints += left

    meter = Meter(budget, "algebraic loops")
    try:
        resolved, free, left = eliminate(explicit, K, meter)
        extra += free
        constraints = [substitute(form, resolved, K, meter=meter) for form in constraints] + left
    except TooLarge as stop:
        raise refusal(graph, parametrisation.free, stop) from None
    forms = (*explicit.items(), *(("0", form) for form in constraints))
    equations = _descriptor(
        causal, parametrisation, K, storage, resolved, forms, extra, constraints
    )
    return replace(equations, budget=budget)


def _solved(component: Component, v: PortVariables, outputs: list[str], relation):
    """A component's relation solved for the variables it imposes: written in placeholder
    names and solved once for all the components alike (a thousand equal resistors on a
    junction are solved once), then renamed."""
    named = {}
    template = replace(
        v,
        efforts=tuple(named.setdefault(f"e#{i}", e) and f"e#{i}" for i, e in enumerate(v.efforts)),
        flows=tuple(named.setdefault(f"f#{i}", f) and f"f#{i}" for i, f in enumerate(v.flows)),
        energy=v.energy and named.setdefault("x#", v.energy) and "x#",
        rate=v.rate and named.setdefault("dx#", v.rate) and "dx#",
        signals=tuple(
            (named.setdefault(f"s#{i}", name) and f"s#{i}", c)
            for i, (name, c) in enumerate(v.signals)
        ),
    )
    placeholder = {name: key for key, name in named.items()}
    if len(placeholder) < len(named):  # a variable in two roles (a signal of its own bond)
        return relation(component.type, v, tuple(outputs))
    solved, free, left = relation(
        component.type, template, tuple(placeholder.get(o, o) for o in outputs)
    )
    back = lambda name: named.get(name, name)  # noqa: E731
    rename = lambda form: {back(w): c for w, c in form.items()}  # noqa: E731
    return (
        {back(x): rename(form) for x, form in solved.items()},
        [back(x) for x in free],
        [rename(form) for form in left],
    )


def _to_expr(form: Form, K: Domain) -> sympy.Expr:
    return sympy.Add(*(_to_sympy(K, c) * sympy.Symbol(w) for w, c in form.items()))


@cache
def _to_sympy(K: Domain, c) -> sympy.Expr:
    """Coefficients recur (1, -1 and the few values of a model): each converted once."""
    return K.to_sympy(c)


def _descriptor(
    causal, parametrisation, K, storage, resolved, forms, extra, constraints
) -> Equations:
    graph = causal.bondgraph
    inputs = {u: j for j, u in enumerate(signal_names(graph.inputs, INPUT).values())}
    outputs = list(signal_names(graph.outputs, OUTPUT).values())
    states = [_energy(c) for c in storage]
    rates = {"d" + x: i for i, x in enumerate(states)}
    read = [resolved.get(y, {}) for y in outputs]
    auxiliary = [w for w in rates if any(w in form for form in read)]  # a dependent rate
    names = states + auxiliary + extra
    index = {x: i for i, x in enumerate(states)}
    index.update((z, len(states) + len(auxiliary) + j) for j, z in enumerate(extra))
    size = len(names)
    E = [[K.zero] * size for _ in range(size)]
    A = [[K.zero] * size for _ in range(size)]
    B = [[K.zero] * len(inputs) for _ in range(size)]

    def place(row: int, form: Form, sign) -> None:
        for w, c in form.items():
            if w in inputs:
                B[row][inputs[w]] += sign * c
            elif w in index:
                A[row][index[w]] += sign * c
            elif w in rates:
                E[row][rates[w]] -= sign * c

    for row, component in enumerate(storage):
        x = states[row]
        if causal.integral(component.name):  # x' = form
            E[row][row] += K.one
            place(row, resolved.get("d" + x, {"d" + x: K.one}), K.one)
        else:  # 0 = -x + form
            A[row][row] -= K.one
            place(row, resolved.get(x, {x: K.one}), K.one)
    for j, w in enumerate(auxiliary):  # x_j' = z_j
        row = len(states) + j
        E[row][rates[w]] += K.one
        A[row][row] += K.one
    for j, form in enumerate(constraints):  # 0 = form
        place(len(states) + len(auxiliary) + j, form, K.one)
    C = [[K.zero] * size for _ in outputs]
    D = [[K.zero] * len(inputs) for _ in outputs]
    for i, form in enumerate(read):
        for w, c in form.items():
            if w in inputs:
                D[i][inputs[w]] += c
            elif w in index:
                C[i][index[w]] += c
            else:
                C[i][len(states) + auxiliary.index(w)] += c
    matrix = lambda rows, cols: DomainMatrix(rows, (len(rows), cols), K)  # noqa: E731
    return Equations(
        causal=causal,
        parametrisation=parametrisation,
        domain=K,
        forms=forms,
        states=tuple(names),
        E=matrix(E, size),
        A=matrix(A, size),
        B=matrix(B, len(inputs)),
        C=matrix(C, size),
        D=matrix(D, len(inputs)),
        inputs=graph.inputs,
        outputs=graph.outputs,
    )
