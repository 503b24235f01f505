"""Stage 4: `CausalBondGraph` -> `Equations`, the descriptor state-space form.

Each component's constitutive relation (from the library) is solved for the
variables its causality makes it impose: this gives one explicit, linear equation
per bond variable. Substituting them in dependency order expresses everything in
the input u, the energy variables of storage in integral causality and the
derivatives of the dependent (derivative-causality) ones; the strongly connected
pieces of that dependency graph are the algebraic loops, solved exactly together.
The result is E x' = A x + B u, y = C x + D u with x the energy variables (q of C,
p of I), all exact, with coefficients in the field of rational functions of the
unknown and the kept symbols.
"""

from __future__ import annotations

from collections import ChainMap
from collections.abc import Mapping
from dataclasses import dataclass, replace
from functools import cache

import networkx as nx
import sympy
from sympy.polys.domains.domain import Domain
from sympy.polys.matrices import DomainMatrix

from mtt.derivation.budget import DEFAULT_BUDGET, Budget
from mtt.derivation.causality import CausalBondGraph
from mtt.derivation.constants import Constants, Unsupported
from mtt.derivation.parameters import Parametrisation
from mtt.language.bondgraph import Component
from mtt.language.components import ComponentType, PortVariables, Role
from mtt.language.diagnostics import ModelError, error

INPUT, OUTPUT = "u", "y"

Form = dict  # variable name -> coefficient (a domain element): a linear combination


@dataclass(frozen=True)
class Equations:
    causal: CausalBondGraph
    parametrisation: Parametrisation
    domain: Domain  # the coefficient field: QQ or Q(alpha), or Q(alpha)(unknowns, symbols...)
    relations: tuple[tuple[str, sympy.Expr], ...]  # the causal equations, variable = expression
    states: tuple[str, ...]  # the descriptor variables x
    E: DomainMatrix
    A: DomainMatrix
    B: DomainMatrix
    C: DomainMatrix
    D: DomainMatrix
    budget: Budget = DEFAULT_BUDGET  # how large the transfer stage may let polynomials grow

    def matrices(self) -> dict[str, sympy.Matrix]:
        """E, A, B, C, D as exact sympy matrices."""
        return {name: getattr(self, name).to_Matrix() for name in "EABCD"}


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


def _coefficient_domain(held: Constants, free: tuple[str, ...], graph, values) -> Domain:
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
        drive=INPUT if component.name == graph.input else None,
        measure=OUTPUT if component.name == graph.output else None,
        signals=signals,
    )


def _outputs(causal: CausalBondGraph, component: Component, v: PortVariables) -> list[str]:
    """The variables a component imposes under its causality."""
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


def _times(a, b, K: Domain):
    """a * b, without the general product (and its gcd) when one factor is 1 or -1, or
    both are numbers."""
    if a == K.one:
        return b
    if b == K.one:
        return a
    if a == -K.one:
        return -b
    if b == -K.one:
        return -a
    if (
        K.is_FractionField
        and a.numer.is_ground
        and a.denom.is_ground
        and b.numer.is_ground
        and b.denom.is_ground
    ):
        ground = K.domain
        value = ground.quo(a.numer.LC * b.numer.LC, a.denom.LC * b.denom.LC)
        return K.convert_from(value, ground)
    return a * b


def _solve(
    rows: list[dict], unknowns: list[str], K: Domain
) -> tuple[dict[str, Form], list[str], list[Form]]:
    """Solve linear rows (forms equal to zero) for as many of `unknowns` as they determine.

    Returns the solved unknowns, each in terms of the other variables and of the unknowns
    left free; the unknowns left free (a parameter of zero, say, or a degenerate algebraic
    loop, keeps the rows from determining them); and the rows that remain as constraints.
    This is the reduced row echelon form with the unknowns' columns first (unique, so any
    pivot row will do: one with a coefficient of 1 or -1 spares divisions).
    """
    others = sorted({name for row in rows for name in row} - set(unknowns))
    rows = [{name: c for name, c in row.items() if c != K.zero} for row in rows]
    where: dict[str, set[int]] = {}  # column -> the rows holding it (a junction's are many)
    for i, row in enumerate(rows):
        for name in row:
            where.setdefault(name, set()).add(i)
    free_rows = set(range(len(rows)))
    pivots: list[tuple[int, str]] = []
    for column in unknowns + others:
        candidates = sorted(where.get(column, set()) & free_rows)
        if not candidates:
            continue
        i = next((i for i in candidates if rows[i][column] in (K.one, -K.one)), candidates[0])
        free_rows.remove(i)
        scale = rows[i][column]
        if scale != K.one:
            inverse = -K.one if scale == -K.one else K.one / scale
            rows[i] = {name: _times(c, inverse, K) for name, c in rows[i].items()}
        for j in sorted(where[column] - {i}):
            row = rows[j]
            factor = row[column]
            for name, c in rows[i].items():
                value = row.get(name, K.zero) - _times(factor, c, K)
                if value == K.zero:
                    row.pop(name, None)
                    where[name].discard(j)
                else:
                    row[name] = value
                    where.setdefault(name, set()).add(j)
        pivots.append((i, column))
    solved: dict[str, Form] = {}
    constraints: list[Form] = []
    for i, column in sorted(pivots, key=lambda p: (unknowns + others).index(p[1])):
        form = {name: c for name, c in rows[i].items() if name != column}
        if column in unknowns:
            solved[column] = {name: -c for name, c in form.items()}
        else:
            constraints.append({column: K.one, **form})
    free = [u for u in unknowns if u not in solved]
    return solved, free, constraints


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
    K = _coefficient_domain(held, parametrisation.free, graph, values)
    explicit: dict[str, Form] = {}
    extra: list[str] = []
    constraints: list[Form] = []
    storage = [c for c in graph.components if c.type.role is Role.STORAGE]
    convert = cache(lambda value: held.element(K, value))  # most are 1, -1 and a few values

    @cache
    def solve(kind: ComponentType, v: PortVariables, outputs: tuple[str, ...]):
        rows = [{name: convert(c) for name, c in row.items()} for row in kind.relation(v)]
        return _solve(rows, list(outputs), K)

    for component in graph.components:
        v = _port_variables(causal, component, values.get(component.name), signals[component.name])
        solved, free, left = _solved(component, v, _outputs(causal, component, v), solve)
        explicit.update(solved)
        extra += free
        constraints += left

    resolved, free, left = _eliminate(explicit, K)
    extra += free
    constraints = [_substitute(form, resolved, K) for form in constraints] + left
    relations = tuple((name, _to_expr(form, K)) for name, form in explicit.items())
    relations += tuple(("0", _to_expr(form, K)) for form in constraints)
    equations = _descriptor(
        causal, parametrisation, K, storage, resolved, relations, extra, constraints
    )
    return replace(equations, budget=budget)


def _solved(component: Component, v: PortVariables, outputs: list[str], solve):
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
        return solve(component.type, v, tuple(outputs))
    solved, free, left = solve(
        component.type, template, tuple(placeholder.get(o, o) for o in outputs)
    )
    back = lambda name: named.get(name, name)  # noqa: E731
    rename = lambda form: {back(w): c for w, c in form.items()}  # noqa: E731
    return (
        {back(x): rename(form) for x, form in solved.items()},
        [back(x) for x in free],
        [rename(form) for form in left],
    )


def _substitute(form: Form, resolved: Mapping[str, Form], K: Domain, skip=frozenset()) -> Form:
    """A form in terms of the base variables (those `resolved` does not give)."""
    total: Form = {}
    for w, c in form.items():
        if w in skip:
            continue
        for base, cb in resolved.get(w, {w: K.one}).items():
            term = _times(c, cb, K)
            total[base] = total[base] + term if base in total else term
    return {b: c for b, c in total.items() if c != K.zero}


def _eliminate(explicit: dict[str, Form], K: Domain) -> tuple[dict[str, Form], list, list]:
    """Every variable in terms of the base variables, loops solved jointly.

    Returns the resolved forms, and the loop variables left free with the loop's
    remaining constraints when a loop does not determine them all.
    """
    depends = nx.DiGraph()
    depends.add_nodes_from(explicit)
    for name, form in explicit.items():
        depends.add_edges_from((name, w) for w in form if w in explicit)
    condensed = nx.condensation(depends)
    resolved: dict[str, Form] = {}
    extra: list[str] = []
    constraints: list[Form] = []

    for node in reversed(list(nx.topological_sort(condensed))):
        members = sorted(condensed.nodes[node]["members"])
        if len(members) == 1 and not depends.has_edge(members[0], members[0]):
            resolved[members[0]] = _substitute(explicit[members[0]], resolved, K)
            continue
        if _torn(members, explicit, resolved, K, depends):
            continue
        # a degenerate loop: v - sum(a_vw w, w in loop) = the rest, all rows together
        rows = []
        for v in members:
            row = {w: -c for w, c in explicit[v].items() if w in members}
            row[v] = row.get(v, K.zero) + K.one
            for base, c in _substitute(explicit[v], resolved, K, set(members)).items():
                row[base] = row.get(base, K.zero) - c
            rows.append(row)
        solved, free, left = _solve(rows, members, K)
        resolved.update(solved)
        extra += free
        constraints += left
    return resolved, extra, constraints


def _tears(members: list[str], depends: nx.DiGraph) -> tuple[list[str], nx.DiGraph]:
    """A few loop variables that, taken as known, leave no cycle among the others (a
    feedback vertex set, chosen greedily: in each cycle the variable with the most
    dependencies both ways), and the dependencies left among the others."""
    graph = nx.DiGraph(depends.subgraph(members))
    tears = []
    while True:
        cycles = [
            sorted(c)
            for c in nx.strongly_connected_components(graph)
            if len(c) > 1 or graph.has_edge(next(iter(c)), next(iter(c)))
        ]
        if not cycles:
            return tears, graph
        for cycle in cycles:
            tear = max(cycle, key=lambda v: graph.in_degree(v) * graph.out_degree(v))
            tears.append(tear)
            graph.remove_node(tear)


def _torn(members, explicit, resolved, K, depends) -> bool:
    """Solve an algebraic loop by tearing: every other loop variable in terms of the tear
    variables (in dependency order, one substitution each), then the few tear variables
    from their own equations, jointly. A wide junction makes one loop of hundreds of
    variables with a single tear: the work stays linear in them (a joint solve of all
    would fill in). False, with nothing resolved, when the tear equations are degenerate.
    """
    tears, rest = _tears(members, depends)
    partial: dict[str, Form] = {}
    given = ChainMap(partial, resolved)  # the tear variables stay themselves
    for v in reversed(list(nx.topological_sort(rest))):
        partial[v] = _substitute(explicit[v], given, K)
    rows = []
    for t in tears:
        row = {w: -c for w, c in _substitute(explicit[t], given, K).items()}
        row[t] = row.get(t, K.zero) + K.one
        rows.append({w: c for w, c in row.items() if c != K.zero})
    solved, free, left = _solve(rows, tears, K)
    if free or left:
        return False
    resolved.update(solved)
    for v, form in partial.items():
        resolved[v] = _substitute(form, solved, K)
    return True


def _to_expr(form: Form, K: Domain) -> sympy.Expr:
    return sympy.Add(*(_to_sympy(K, c) * sympy.Symbol(w) for w, c in form.items()))


@cache
def _to_sympy(K: Domain, c) -> sympy.Expr:
    """Coefficients recur (1, -1 and the few values of a model): each converted once."""
    return K.to_sympy(c)


def _descriptor(
    causal, parametrisation, K, storage, resolved, relations, extra, constraints
) -> Equations:
    states = [_energy(c) for c in storage]
    rates = {"d" + x: i for i, x in enumerate(states)}
    output = resolved.get(OUTPUT, {})
    auxiliary = [w for w in rates if w in output]  # y depends on a dependent state's rate
    names = states + auxiliary + extra
    index = {x: i for i, x in enumerate(states)}
    index.update((z, len(states) + len(auxiliary) + j) for j, z in enumerate(extra))
    size = len(names)
    E = [[K.zero] * size for _ in range(size)]
    A = [[K.zero] * size for _ in range(size)]
    B = [[K.zero] for _ in range(size)]

    def place(row: int, form: Form, sign) -> None:
        for w, c in form.items():
            if w == INPUT:
                B[row][0] += sign * c
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
    C = [[K.zero] * size]
    D = [[K.zero]]
    for w, c in output.items():
        if w == INPUT:
            D[0][0] += c
        elif w in index:
            C[0][index[w]] += c
        else:
            C[0][len(states) + auxiliary.index(w)] += c
    matrix = lambda rows, cols: DomainMatrix(rows, (len(rows), cols), K)  # noqa: E731
    return Equations(
        causal=causal,
        parametrisation=parametrisation,
        domain=K,
        relations=relations,
        states=tuple(names),
        E=matrix(E, size),
        A=matrix(A, size),
        B=matrix(B, 1),
        C=matrix(C, size),
        D=matrix(D, 1),
    )
