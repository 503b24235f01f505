"""Stage 6: transfer function -> Theta, the paper's matrix of the system.

theta = [a0..an, -b0..-bm] from the canonical denominator and numerator, and
theta(k) = Theta K(k) with K(k) = [1, k, ..., k^N]: column j of Theta holds the
coefficients of k^j. Theta and N are all the estimator needs to know of the system.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import sympy

from mtt.derivation.transfer import TransferFunction


@dataclass(frozen=True)
class Theta:
    """Everything a generated estimator carries about its system."""

    model: str  # the model's name (an identifier)
    description: str | None
    source_name: str  # the model file as named on the command line
    input: str  # "Se:v"
    output: str  # "Df:vm"
    unknown: str | None  # the parameter identified
    symbols: tuple[str, ...]  # parameters kept symbolic, in file order
    defaults: Mapping[str, sympy.Expr | None]  # file values of the kept symbols (or None)
    assumed: Mapping[str, sympy.Expr]  # exact values substituted for the other parameters
    true_value: sympy.Expr | None  # the file's value of the unknown (for simulations)
    num: sympy.Expr  # canonical numerator, in s, the unknown and the symbols
    den: sympy.Expr  # canonical denominator
    n: int  # degree of den in s
    m: int  # degree of num in s
    N: int  # degree of theta in the unknown
    matrix: sympy.Matrix  # (n + 1 + m + 1) x (N + 1): rows a0..an, -b0..-bm

    @property
    def row_labels(self) -> tuple[str, ...]:
        return tuple(f"a{i}" for i in range(self.n + 1)) + tuple(
            f"-b{i}" for i in range(self.m + 1)
        )


def theta_matrix(tf: TransferFunction) -> Theta:
    """Theta from the canonical transfer function (one column, N = 0, without an unknown)."""
    equations = tf.equations
    graph = equations.causal.bondgraph
    params = equations.parametrisation
    n, m = tf.degree("den"), tf.degree("num")
    rows: list[dict[int, sympy.Expr]] = [{} for _ in range(n + m + 2)]
    skip = 2 if params.unknown else 1  # s and the unknown come first
    rest = tf.gens[skip:]
    for offset, poly, sign in ((0, tf.den, 1), (n + 1, tf.num, -1)):
        for monom, coefficient in poly.terms():
            power_s, power_k = monom[0], monom[1] if params.unknown else 0
            others = monom[skip:]
            term = (
                sign
                * sympy.Integer(int(coefficient))
                * sympy.Mul(*(g**e for g, e in zip(rest, others, strict=True)))
            )
            row = rows[offset + power_s]
            row[power_k] = row.get(power_k, sympy.Integer(0)) + term
    N = max((j for row in rows for j in row), default=0)
    matrix = sympy.Matrix([[row.get(j, sympy.Integer(0)) for j in range(N + 1)] for row in rows])
    return Theta(
        model=graph.name,
        description=graph.description,
        source_name=graph.source.name,
        input=graph.component(graph.input).label,
        output=graph.component(graph.output).label,
        unknown=params.unknown,
        symbols=params.symbols,
        defaults=params.defaults,
        assumed=params.assumed,
        true_value=params.true_value,
        num=tf.numerator,
        den=tf.denominator,
        n=n,
        m=m,
        N=N,
        matrix=matrix,
    )
