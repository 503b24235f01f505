"""A nonlinear model's small-signal model as `Equations`, for the linear chain.

The linearisation (`operating.linearise`) gives A, B, C, D as exact sympy matrices; here
they become the descriptor form the transfer function, Theta and the estimator are made
from, in the coefficient field their entries need (rational numbers, or an algebraic
number field for roots such as gravity's cos(asin(c)) = sqrt(1 - c^2), over the
unknowns and kept parameters).
"""

from __future__ import annotations

import sympy
from sympy.polys.matrices import DomainMatrix

from mtt.derivation.causality import CausalBondGraph
from mtt.derivation.constants import Constants, Unsupported
from mtt.derivation.equations import INPUT, OUTPUT, Equations, coefficient_domain
from mtt.derivation.parameters import Parametrisation
from mtt.language.diagnostics import Diagnostic, ModelError, error


def small_signal(
    causal: CausalBondGraph,
    parametrisation: Parametrisation,
    states: tuple[str, ...],
    matrices: dict[str, sympy.Matrix],
    notes: tuple[Diagnostic, ...] = (),
) -> Equations:
    """The linear model x' = A x + B u, y = C x + D u given by exact sympy matrices (a
    nonlinear model's linearisation at an operating point), in the coefficient field its
    entries need, for the linear chain (transfer function, Theta, estimator)."""
    graph = causal.bondgraph
    held, problems = Constants(), []
    unknowns = [sympy.Symbol(name) for name in parametrisation.unknowns]
    scanned = {}
    for name in "ABCD":
        for index, value in enumerate(matrices[name]):
            irrational = [k for k in unknowns if not value.is_rational_function(k)]
            if irrational:
                message = (
                    f"the small-signal model's {name} holds {value}, not a rational function "
                    f"of the unknown {irrational[0]}: give the operating point's states "
                    "(--at NAME=VALUE) rather than the input, so that it does not move "
                    "with the unknown"
                )
                problems.append(error("non_rational_unknown", message))
                continue
            try:
                scanned[name, index] = held.scan(value)
            except Unsupported as problem:
                problems.append(error(problem.kind, f"{name}: {value}: {problem}"))
    if problems:
        raise ModelError(graph.source, problems[:1])
    K = coefficient_domain(held, parametrisation.free, graph, {})
    size = len(states)

    def matrix(name: str, rows: int, cols: int) -> DomainMatrix:
        entries = [
            [held.element(K, scanned[name, i * cols + j]) for j in range(cols)] for i in range(rows)
        ]
        return DomainMatrix(entries, (rows, cols), K)

    A, B = matrix("A", size, size), matrix("B", size, 1)
    C, D = matrix("C", 1, size), matrix("D", 1, 1)
    forms = tuple((f"d{x}", _form(A, B, i, states)) for i, x in enumerate(states))
    forms += ((OUTPUT, _form(C, D, 0, states)),)
    return Equations(
        causal=causal,
        parametrisation=parametrisation,
        domain=K,
        forms=forms,
        states=tuple(states),
        E=DomainMatrix.eye(size, K),
        A=A,
        B=B,
        C=C,
        D=D,
        notes=notes,
    )


def _form(M: DomainMatrix, N: DomainMatrix, i: int, states: tuple[str, ...]) -> dict:
    """Row i of [M, N] as a form in the states and the input (its nonzero coefficients)."""
    row = M.to_list()[i] if M.shape[1] else []
    form = {x: c for x, c in zip(states, row, strict=True) if c}
    u = N.to_list()[i][0]
    return {**form, INPUT: u} if u else form
