"""Linear forms over the coefficient field: each component's relation solved for the
variables it imposes, and every variable in terms of the base ones, algebraic loops solved
by tearing.

A form is a dict variable name -> coefficient (an element of the coefficient field K), the
linear combination it stands for. A wide junction makes one algebraic loop of hundreds of
variables: a few tear variables, taken as known, leave no cycle among the others, which are
then substituted once each in dependency order, and only the tear variables are solved for
jointly (solving all the loop's variables jointly would fill in). With many symbols the
coefficients are rational functions that can grow exponentially through a loop: the
arithmetic is paid for on a `Meter`, and a loop whose tearing outgrows `TEARING_SHARE` of
the budget is left to the descriptor form as it stands (its variables and rows kept), for
the transfer stage's fraction-free elimination, which needs no gcd at every step.
"""

from __future__ import annotations

from collections import ChainMap
from collections.abc import Mapping

import networkx as nx
from sympy.polys.domains.domain import Domain

from mtt.derivation import deadline
from mtt.derivation.budget import Budget, Meter, TooLarge

Form = dict  # variable name -> coefficient (a domain element): a linear combination
# the part of the derivation's budget an algebraic loop's tearing may use before the loop
# is left to the transfer stage
TEARING_SHARE = 100


def _terms(x) -> int:
    """The terms of a coefficient: numerator and denominator of a rational function."""
    return len(x.numer) + len(x.denom) if hasattr(x, "numer") else 1


def _paid(meter: Meter | None, a, b) -> None:
    """The products of terms that a * b or a + b over the fractions does (cross products,
    then the gcd that cancels them, about as much again), paid for before it is done."""
    if meter is not None:
        meter.spend(2 * _terms(a) * _terms(b))


def _held(meter: Meter | None, x):
    if meter is not None:
        meter.hold(_terms(x))
    return x


def plus(a, b, K: Domain, meter: Meter | None = None):
    """a + b, paid for."""
    if a == K.zero or b == K.zero:
        return a + b
    _paid(meter, a, b)
    return _held(meter, a + b)


def times(a, b, K: Domain, meter: Meter | None = None):
    """a * b, without the general product (and its gcd) when one factor is 1 or -1, or
    both are numbers; paid for on `meter` otherwise."""
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
    _paid(meter, a, b)
    return _held(meter, a * b)


def solve(
    rows: list[dict], unknowns: list[str], K: Domain, meter: Meter | None = None
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
        deadline.check()
        candidates = sorted(where.get(column, set()) & free_rows)
        if not candidates:
            continue
        i = next((i for i in candidates if rows[i][column] in (K.one, -K.one)), candidates[0])
        free_rows.remove(i)
        scale = rows[i][column]
        if scale != K.one:
            inverse = -K.one if scale == -K.one else K.one / scale
            rows[i] = {name: times(c, inverse, K, meter) for name, c in rows[i].items()}
        for j in sorted(where[column] - {i}):
            row = rows[j]
            factor = row[column]
            for name, c in rows[i].items():
                value = plus(row.get(name, K.zero), -times(factor, c, K, meter), K, meter)
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


def substitute(
    form: Form, resolved: Mapping[str, Form], K: Domain, skip=frozenset(), meter=None
) -> Form:
    """A form in terms of the base variables (those `resolved` does not give)."""
    total: Form = {}
    for w, c in form.items():
        if w in skip:
            continue
        for base, cb in resolved.get(w, {w: K.one}).items():
            term = times(c, cb, K, meter)
            total[base] = plus(total[base], term, K, meter) if base in total else term
    return {b: c for b, c in total.items() if c != K.zero}


def eliminate(
    explicit: dict[str, Form], K: Domain, meter: Meter
) -> tuple[dict[str, Form], list, list]:
    """Every variable in terms of the base variables, loops solved jointly (`TooLarge` when
    that outgrows the budget of `meter`).

    Returns the resolved forms, and the loop variables left free with the loop's
    remaining constraints when a loop does not determine them all (or when solving it
    would take more than its share of the budget).
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
        deadline.check()
        members = sorted(condensed.nodes[node]["members"])
        if len(members) == 1 and not depends.has_edge(members[0], members[0]):
            resolved[members[0]] = substitute(explicit[members[0]], resolved, K, meter=meter)
            continue
        share = Meter(Budget(max(1, meter.budget.max_terms // TEARING_SHARE)), meter.stage)
        try:
            if _torn(members, explicit, resolved, K, depends, share):
                meter.spend(share.work)
                continue
            big = False
        except TooLarge:
            big = True
        meter.spend(share.work)
        # v - sum(a_vw w, w in loop) = the rest, all rows together: solved jointly for a
        # degenerate loop, left to the descriptor form for one too large to solve here
        rows = []
        for v in members:
            row = {w: -c for w, c in explicit[v].items() if w in members}
            row[v] = row.get(v, K.zero) + K.one
            for base, c in substitute(explicit[v], resolved, K, set(members), meter).items():
                row[base] = plus(row.get(base, K.zero), -c, K, meter)
            rows.append({w: c for w, c in row.items() if c != K.zero})
        if big:
            extra += members
            constraints += rows
            continue
        solved, free, left = solve(rows, members, K, meter)
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


def _torn(members, explicit, resolved, K, depends, meter: Meter) -> bool:
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
        partial[v] = substitute(explicit[v], given, K, meter=meter)
    rows = []
    for t in tears:
        row = {w: -c for w, c in substitute(explicit[t], given, K, meter=meter).items()}
        row[t] = plus(row.get(t, K.zero), K.one, K, meter)
        rows.append({w: c for w, c in row.items() if c != K.zero})
    solved, free, left = solve(rows, tears, K, meter)
    if free or left:
        return False
    done = {v: substitute(form, solved, K, meter=meter) for v, form in partial.items()}
    resolved.update(solved)
    resolved.update(done)
    return True
