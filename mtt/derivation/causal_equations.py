"""Stage 4 for nonlinear models: `CausalBondGraph` -> the state equations, exact.

Causality orders every constitutive relation as an assignment: each component's imposed
variables as expressions of what it receives (a nonlinear relation used the way it was
written or inverted exactly, a linear component's rows solved for them, a modulated
source's or two-port's argument with its signals as the variables they read). These are
put into each other in dependency order; the strongly connected pieces are algebraic
loops, solved together (exactly when linear in their variables, by sympy within a budget
when not); a storage element in derivative causality takes its rate from the chain rule.
What is left is x' = f(x, u), y = g(x, u) in the states (integral storage, then the
integrals q(X) and p(X) read), the input and the parameters.
"""

from __future__ import annotations

import sympy
from sympy.solvers.solveset import NonlinearError

from mtt.derivation import bounded
from mtt.derivation.causality import CausalBondGraph
from mtt.derivation.equations import imposed
from mtt.derivation.parameters import Parametrisation
from mtt.language.components import PortVariables, Role
from mtt.language.diagnostics import Diagnostic, ModelError, error
from mtt.language.elements import Component
from mtt.language.expressions import SignalUse

INPUT, OUTPUT = sympy.Symbol("u"), sympy.Symbol("y")


def _bond(kind: str, number: int) -> sympy.Symbol:
    return sympy.Symbol(f"{kind}{number}")


def _rate(state: sympy.Symbol) -> sympy.Symbol:
    return sympy.Symbol(f"d{state.name}")


class _Derivation:
    """The causal equations of one model, each imposed variable as an expression of the
    variables its component receives (and of states, the input and parameters), then
    eliminated down to the states and the input."""

    def __init__(self, causal: CausalBondGraph, parametrisation: Parametrisation):
        self.causal = causal
        self.graph = causal.bondgraph
        self.parametrisation = parametrisation
        self.problems: list[Diagnostic] = []
        self.states: list[sympy.Symbol] = []  # integral storage first, then integrators
        self.explicit: dict[sympy.Symbol, sympy.Expr] = {}
        self.where: dict[sympy.Symbol, Component] = {}  # which component imposes a variable
        self.dependent: dict[sympy.Symbol, sympy.Symbol] = {}  # rate -> its energy variable
        self.integrators: dict[sympy.Symbol, sympy.Symbol] = {}  # state -> its rate's source
        self.conditions: list[sympy.Expr] = []  # >= 0 where the derived inverses hold
        for component in self.graph.components:
            if component.type.role is Role.STORAGE and causal.integral(component.name):
                self.states.append(self._energy(component))

    # names

    def _energy(self, component: Component) -> sympy.Symbol:
        return sympy.Symbol(f"{component.type.energy_prefix}_{component.name}")

    def _signal(self, use: SignalUse) -> sympy.Symbol:
        """The variable a signal reads: a bond's effort or flow, or their integral (a C's
        or I's own energy variable, or a state integrating the bond's variable)."""
        bond = self.graph.reading(use.target)
        if use.kind in ("e", "f"):
            return _bond(use.kind, bond)
        target = self.graph.component(use.target)
        energy = sympy.Symbol(f"{use.kind}_{use.target}")
        if target.type.energy_prefix == use.kind:
            return energy  # a C's q, an I's p: its own state (or dependent energy)
        if energy not in self.integrators:
            self.integrators[energy] = _bond("f" if use.kind == "q" else "e", bond)
        return energy

    def _value(self, expression, component: Component) -> sympy.Expr:
        """An expression with the parameters' values put in and its signals as variables."""
        value = self.parametrisation.apply(expression.value)
        signals = {use.symbol: self._signal(use) for use in expression.signals}
        value = value.xreplace(signals)
        if value.has(sympy.zoo, sympy.oo, sympy.nan):
            message = f"{component.label}: {expression} is infinite or undefined here ({value})"
            self.problems.append(error("singular_model", message, expression.position))
            return sympy.Integer(0)
        return value

    # the equations of each component

    def _impose(self, variable: sympy.Symbol, value: sympy.Expr, component: Component) -> None:
        self.explicit[variable] = value
        self.where[variable] = component

    def component(self, component: Component) -> None:
        graph = self.graph
        ports = graph.ports(component.name)
        role = component.type.role
        if role is Role.MODULATED and component.argument is not None:
            on_effort = component.type.causality.imposes_effort
            variable = _bond("e" if on_effort else "f", ports[0].bond)
            self._impose(variable, self._value(component.argument, component), component)
            return
        if component.nonlinear_relation:
            self._relation(component, ports[0].bond)
            return
        parameter = None
        if component.argument is not None:
            parameter = self._value(component.argument, component)
        v = PortVariables(
            efforts=tuple(f"e{p.bond}" for p in ports),
            flows=tuple(f"f{p.bond}" for p in ports),
            inward=tuple(p.inward for p in ports),
            parameter=parameter,
            energy=str(self._energy(component)) if role is Role.STORAGE else None,
            rate="d" + str(self._energy(component)) if role is Role.STORAGE else None,
            drive="u" if component.name == graph.input else None,
            measure="y" if component.name == graph.output else None,
        )
        outputs = imposed(self.causal, component, v)
        rows = component.type.relation(v)
        self._solve_rows(rows, outputs, component)

    def _solve_rows(self, rows: list[dict], outputs: list[str], component: Component) -> None:
        """The component's linear rows solved for the variables it imposes (its parameter
        and any signals in it are coefficients)."""
        solution = _gauss_jordan(rows, outputs)
        if solution is None:
            message = (
                f"{component.label}: its relation does not determine what causality makes it impose"
            )
            where = component.argument.position if component.argument else component.position
            self.problems.append(error("singular_model", message, where))
            return
        for name in outputs:
            self._impose(sympy.Symbol(name), solution[name], component)
        if component.type.role is Role.STORAGE and not self.causal.integral(component.name):
            energy = self._energy(component)  # its rate is that of its energy, in time
            self.dependent[_rate(energy)] = energy

    def _relation(self, component: Component, bond: int) -> None:
        """A nonlinear relation used the way causality needs (given, or its inverse)."""
        imposes = self.causal.imposes_effort(component.name, bond)
        needed = component.needs(imposes)
        relation = component.relation.giving(needed)
        value = self._value(relation.expression, component)
        self.conditions += [self._value(c, component) for c in relation.conditions]
        effort, flow = _bond("e", bond), _bond("f", bond)
        if component.type.role is Role.RESISTOR:
            self._impose(effort if imposes else flow, value, component)
            return
        energy = self._energy(component)
        # C: dq = f, with e = phi(q) (integral) or q = psi(e) (derivative); I: dp = e, f
        rate_of = flow if component.type.energy_prefix == "q" else effort
        if self.causal.integral(component.name):
            port = effort if component.type.energy_prefix == "q" else flow
            self._impose(port, value, component)
            self._impose(_rate(energy), rate_of, component)
        else:
            self._impose(energy, value, component)
            self._impose(rate_of, _rate(energy), component)
            self.dependent[_rate(energy)] = energy

    # elimination

    def _depends(self, variable: sympy.Symbol, known: set) -> set[sympy.Symbol]:
        """The variables (of `known`) an equation's right-hand side reads; a dependent rate
        reads its energy variable and the rates of the states that energy depends on."""
        if variable in self.dependent:
            energy = self.dependent[variable]
            return {energy} | {_rate(x) for x in self._base_states(energy)}
        return self.explicit[variable].free_symbols & known

    def _base_states(self, variable: sympy.Symbol) -> set[sympy.Symbol]:
        """The states a variable is computed from, through the causal equations."""
        seen, stack, found = set(), [variable], set()
        while stack:
            v = stack.pop()
            if v in seen:
                continue
            seen.add(v)
            if v in self.states:
                found.add(v)
            elif v in self.explicit:
                stack.extend(self.explicit[v].free_symbols)
            elif v in self.dependent:
                stack.append(self.dependent[v])
        return found

    def eliminate(self) -> dict[sympy.Symbol, sympy.Expr]:
        """Every variable in terms of the states, the input and the parameters; algebraic
        loops (strongly connected pieces) solved together, exactly."""
        import networkx as nx

        known = set(self.explicit) | set(self.dependent)
        depends = nx.DiGraph()
        depends.add_nodes_from(known, key=str)
        for variable in known:
            depends.add_edges_from((variable, w) for w in self._depends(variable, known))
        condensed = nx.condensation(depends)
        resolved: dict[sympy.Symbol, sympy.Expr] = {}
        for node in reversed(list(nx.topological_sort(condensed))):
            members = sorted(condensed.nodes[node]["members"], key=str)
            if len(members) == 1 and not depends.has_edge(members[0], members[0]):
                (variable,) = members
                resolved[variable] = self._equation(variable, resolved)
                continue
            solved = self._loop(members, resolved)
            if solved is None:
                return resolved
            resolved.update(solved)
        return resolved

    def _equation(self, variable: sympy.Symbol, resolved: dict) -> sympy.Expr:
        """The right-hand side of a variable's equation, in terms of resolved variables
        where they are (a dependent rate by the chain rule: d/dt of its energy)."""
        if variable not in self.dependent:
            return self.explicit[variable].xreplace(resolved)
        energy = resolved.get(self.dependent[variable])
        if energy is None:  # its energy variable is in the same loop: not solvable here
            return variable
        if INPUT in energy.free_symbols:
            component = self.where.get(self.dependent[variable])
            message = (
                f"{component.label} is in derivative causality and its energy variable "
                f"follows the input ({self.dependent[variable]} = {energy}): its state "
                "equations would need the input's derivative; make the input reach it "
                "through a resistor, or use a flow (effort) source instead"
            )
            self.problems.append(error("input_derivative", message, component.position))
            return sympy.Integer(0)
        return sympy.Add(
            *(
                sympy.diff(energy, x) * resolved.get(_rate(x), _rate(x))
                for x in sorted(energy.free_symbols & set(self.states), key=str)
            )
        )

    def _loop(self, members: list[sympy.Symbol], resolved: dict) -> dict | None:
        """An algebraic loop's variables, solved exactly together: a linear loop always
        (when it determines them), a nonlinear one when sympy finds exactly one solution."""
        equations = [v - self._equation(v, resolved) for v in members]
        components = [self.where[v] for v in members if v in self.where]
        resistors = [c for c in components if c.type.role is Role.RESISTOR]
        place = (resistors or components)[0]
        names = ", ".join(dict.fromkeys(c.label for c in components))
        try:
            matrix, rest = sympy.linear_eq_to_matrix(equations, members)
        except NonlinearError:
            return self._nonlinear_loop(equations, members, place, names)
        if matrix.rank() < len(members):
            message = (
                f"the algebraic loop through {names} does not determine its variables "
                "(its equations are singular)"
            )
            self.problems.append(error("algebraic_loop", message, _at(place)))
            return None
        solution = matrix.LUsolve(rest)
        return {v: sympy.cancel(solution[i]) for i, v in enumerate(members)}

    def _nonlinear_loop(self, equations, members, place: Component, names: str) -> dict | None:
        solutions = []
        if len(members) <= MAX_NONLINEAR_LOOP:
            solutions = bounded.within(_solve, equations, members) or []
        if len(solutions) == 1 and set(solutions[0]) == set(members):
            return {v: _tidy(solutions[0][v]) for v in members}
        how = f"has {len(solutions)} solutions" if solutions else "cannot be solved exactly"
        message = (
            f"the algebraic loop through {names} is nonlinear and {how}: give one of its "
            "resistors the inverse relation, or add a small storage element (a C or I) "
            "that breaks the loop"
        )
        self.problems.append(error("algebraic_loop", message, _at(place)))
        return None


MAX_NONLINEAR_LOOP = 4  # variables: sympy.solve of more can take unbounded time


def _solve(equations: list, unknowns: list) -> list[dict]:
    return sympy.solve(equations, unknowns, dict=True)


def _at(component: Component):
    if component.relation is not None:
        return component.relation.position
    return component.argument.position if component.argument else component.position


def _gauss_jordan(rows: list[dict], outputs: list[str]) -> dict[str, sympy.Expr] | None:
    """A component's few linear rows (forms equal to zero) solved for its outputs, the
    other variables as they are; None when the rows do not determine them. The pivot is a
    coefficient of 1 or -1 where there is one (junctions, sources: no division at all)."""
    rows = [{name: c for name, c in row.items() if c != 0} for row in rows]
    free = list(range(len(rows)))
    pivots = {}
    for name in outputs:
        candidates = [i for i in free if name in rows[i]]
        if not candidates:
            return None
        i = next((i for i in candidates if rows[i][name] in (1, -1)), candidates[0])
        free.remove(i)
        scale = rows[i][name]
        pivot = {w: c / scale for w, c in rows[i].items()} if scale != 1 else rows[i]
        rows[i] = pivot
        for j, row in enumerate(rows):
            factor = row.get(name)
            if j == i or factor is None:
                continue
            for w, c in pivot.items():
                value = row.get(w, 0) - factor * c
                if value == 0:
                    row.pop(w, None)
                else:
                    row[w] = value
        pivots[name] = i
    solution = {}
    for name, i in pivots.items():
        terms = [-c * sympy.Symbol(w) for w, c in rows[i].items() if w != name]
        if any(w in pivots and w != name for w in rows[i]):
            return None
        solution[name] = sympy.Add(*terms)
    return solution


def _tidy(expression: sympy.Expr) -> sympy.Expr:
    """A simpler equal form: a rational function in lowest terms, when that is shorter (an
    expression with functions or roots in it stays as the substitutions wrote it: cancel
    would take long over them and seldom shortens them)."""
    if not expression.is_rational_function():
        return expression
    cancelled = sympy.cancel(expression)
    return cancelled if sympy.count_ops(cancelled) <= sympy.count_ops(expression) else expression


def state_equations(
    causal: CausalBondGraph, parametrisation: Parametrisation
) -> tuple[tuple[sympy.Symbol, ...], sympy.Matrix, sympy.Matrix, tuple[sympy.Expr, ...]]:
    """The states, f, g, and the domain of the inverses used (expressions >= 0 there);
    raise `ModelError` for a loop that cannot be solved or a state that needs the
    input's derivative."""
    graph = causal.bondgraph
    work = _Derivation(causal, parametrisation)
    for component in graph.components:
        work.component(component)
    for state, variable in work.integrators.items():
        work.states.append(state)
        work.explicit[_rate(state)] = variable
    if work.problems:
        raise ModelError(graph.source, work.problems)
    resolved = work.eliminate()
    if work.problems:
        raise ModelError(graph.source, work.problems)
    f = sympy.Matrix([_tidy(resolved[_rate(x)]) for x in work.states])
    g = sympy.Matrix([_tidy(resolved[OUTPUT])])
    domain = tuple(dict.fromkeys(_tidy(c.xreplace(resolved)) for c in work.conditions))
    return tuple(work.states), f, g, domain
