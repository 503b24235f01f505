"""Stage 6: transfer function -> Theta, the paper's matrix of the system.

theta = [a0..an, -b0..-bm] from the canonical denominator and numerator, and
theta(k) = Theta K(k) with K(k) = [1, k, ..., k^N]: column j of Theta holds the
coefficients of k^j. Theta and N are all the estimator needs to know of the system.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import sympy


@dataclass(frozen=True)
class Theta:
    """Everything a generated estimator carries about its system."""

    model: str  # the model's name (an identifier)
    description: str | None
    source_name: str  # the model file as named on the command line
    input: str  # "Se:v"
    output: str  # "Df:vm"
    unknown: str  # the parameter identified
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
