"""Nonlinear state equations of a bond graph: x' = f(x, u, theta), y = g(x, u, theta).

The stage after causality for models whose constitutive relations are nonlinear
(language version 3). Its result, `NonlinearStateSpace`, is the interface between the
derivation and everything downstream of it: the generated nonlinear simulator (in
mtt/estimator), operating points and linearisation.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy


@dataclass(frozen=True)
class NonlinearStateSpace:
    """x' = f(x, u, theta), y = g(x, u, theta), exact and simplified.

    The states are the energy variables of the storage elements in integral causality
    (q of a C, p of an I), in the model's component order; `f` and `g` are exact sympy
    expressions in the states, the input, the unknowns and the known parameters kept
    symbolic. Every known parameter with a value is in `known` (its exact value) and has
    already been substituted in `f` and `g`; a parameter kept symbolic is in neither, and
    appears in `f` and `g` as a free symbol. Downstream code (simulator generation,
    linearisation) may rely on: the free symbols of f and g are among states, input,
    unknowns and the kept symbols, nothing else.
    """

    name: str  # the model's name
    states: tuple[sympy.Symbol, ...]  # x: the storage elements' energy variables, in order
    input: sympy.Symbol  # u (one input for now)
    output: sympy.Symbol  # y's symbol (a name for display)
    unknowns: tuple[sympy.Symbol, ...]  # theta: the parameters to identify
    known: dict[sympy.Symbol, sympy.Expr]  # known parameters' exact values (kept ones absent)
    f: sympy.Matrix  # x' = f(x, u, unknowns, kept symbols), len(states) x 1
    g: sympy.Matrix  # y = g(x, u, ...), 1 x 1
    source: object = None  # where it came from (for located errors), optional
