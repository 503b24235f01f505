"""What a model derives, as a Python user holds it: plain sympy and numpy, rich in Jupyter.

Each class wraps one representation of the derivation chain (mtt/derivation) and reads
the same way as the command line prints it (mtt/present/report.py): the text and LaTeX
forms exist once, there.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import sympy

from mtt.api import values
from mtt.api.exact import numeric
from mtt.derivation import theta as derived
from mtt.derivation.causality import CausalBondGraph, describe
from mtt.derivation.equations import Equations
from mtt.derivation.equilibria import Equilibria
from mtt.derivation.nonlinear import NonlinearStateSpace
from mtt.derivation.transfer import LAPLACE
from mtt.language.diagnostics import MttError
from mtt.present import nonlinear, report


def _leading_zeros_dropped(coefficients: np.ndarray) -> np.ndarray:
    return np.trim_zeros(coefficients, "f") if coefficients.any() else coefficients[-1:]


@dataclass(frozen=True)
class TransferFunction:
    """G(s) = num / den, exact: numerator and denominator are sympy polynomials in `s`, the
    unknowns and any parameter kept symbolic, coprime, with integer coefficients.

    >>> import mtt
    >>> tf = mtt.load(mtt.example("dc_drive")).transfer_function
    >>> tf.num
    10*k*s**2 + 10
    >>> num, den = tf.at(k=10)
    >>> num.tolist(), den.tolist()
    ([100.0, 0.0, 10.0], [10.0, 100.0, 111.0, 110.0, 10.0])
    """

    theta: derived.Theta

    s = LAPLACE

    @property
    def num(self) -> sympy.Expr:
        return self.theta.num

    @property
    def den(self) -> sympy.Expr:
        return self.theta.den

    @property
    def expr(self) -> sympy.Expr:
        """num / den as one sympy expression."""
        return self.theta.num / self.theta.den

    @property
    def unknowns(self) -> tuple[str, ...]:
        return self.theta.unknowns

    @property
    def symbols(self) -> tuple[str, ...]:
        """Known parameters kept symbolic (load(..., keep=...) or without a value)."""
        return self.theta.symbols

    @property
    def n(self) -> int:
        """The degree of the denominator in s (the order of the system)."""
        return self.theta.n

    @property
    def m(self) -> int:
        """The degree of the numerator in s."""
        return self.theta.m

    @cached_property
    def _coefficients(self) -> tuple[list[sympy.Expr], list[sympy.Expr]]:
        return tuple(sympy.Poly(p, LAPLACE).all_coeffs() for p in (self.num, self.den))

    def at(self, k: object = None, /, **named: object) -> tuple[np.ndarray, np.ndarray]:
        """(num, den) as float arrays, highest power of s first (scipy.signal's order), at
        the unknowns' value k (a number; for several a sequence in the order of `unknowns`
        or a dict) and the parameters named; a name not given takes the model file's value.
        A value that lowers a degree (k = 0, say) gives the shorter array, without leading
        zeros.

        >>> import mtt
        >>> tf = mtt.load(mtt.example("rlc")).transfer_function  # 2cs / (cs^2 + 4cs + 2)
        >>> [part.tolist() for part in tf.at(0.5)] == [part.tolist() for part in tf.at(c=0.5)]
        True
        """
        substitution = values.substitution(self.theta, self.theta.model, k, named)
        num, den = (
            np.array([numeric(c.xreplace(substitution), f"a coefficient of {part}") for c in p])
            for part, p in zip(("num", "den"), self._coefficients, strict=True)
        )
        if not den.any():
            at = ", ".join(f"{symbol} = {value}" for symbol, value in substitution.items())
            raise MttError(f"the denominator of G(s) is zero at {at}", kind="singular_model")
        return _leading_zeros_dropped(num), _leading_zeros_dropped(den)

    def __str__(self) -> str:
        return report.tf_text(self.theta)

    def __repr__(self) -> str:
        return f"TransferFunction({self.expr})"

    def _repr_latex_(self) -> str:
        return f"$\\displaystyle {report.tf_latex(self.theta)}$"


@dataclass(frozen=True)
class Theta:
    r"""The paper's matrix: theta(k) = [a0..an, -b0..-bm] = matrix * K, with K the column of
    `monomials` of the unknowns (1, k, k^2, ... for one unknown k): what the estimator is
    built from.

    >>> import mtt
    >>> theta = mtt.load(mtt.example("dc_drive")).theta
    >>> theta.monomials
    (1, k)
    >>> theta.matrix.T
    Matrix([
    [10, 10,  1,  0, 0, -10, 0,   0],
    [ 0, 10, 11, 10, 1,   0, 0, -10]])
    >>> print(mtt.load(mtt.example("rlc")).theta._repr_latex_())  # what Jupyter shows
    $\displaystyle \Theta = \left[\begin{matrix}2 & 0\\0 & 4...K^T = ...1 & c\end{matrix}\right]$
    """

    theta: derived.Theta

    @property
    def matrix(self) -> sympy.Matrix:
        return self.theta.matrix

    @property
    def monomials(self) -> tuple[sympy.Expr, ...]:
        """Column j of `matrix` multiplies monomials[j]."""
        unknowns = [sympy.Symbol(name) for name in self.theta.unknowns]
        return tuple(
            sympy.Mul(*(k**e for k, e in zip(unknowns, exponents, strict=True)))
            for exponents in self.theta.monomials
        )

    @property
    def rows(self) -> tuple[str, ...]:
        """Row labels: a0..an (denominator), -b0..-bm (numerator, negated)."""
        return self.theta.row_labels

    @property
    def unknowns(self) -> tuple[str, ...]:
        return self.theta.unknowns

    @property
    def N(self) -> int:
        """The degree of theta in the unknowns (the total degree, with several)."""
        return self.theta.N

    def at(self, **known: object) -> np.ndarray:
        """The matrix as floats, for values of the parameters kept symbolic (the unknowns
        are in the monomials, not in the matrix: they are what the estimator finds)."""
        given = dict(known)
        for name in self.theta.unknowns:
            if name in given:
                raise MttError(
                    f"{name} is an unknown: Theta does not depend on its value",
                    kind="bad_value",
                )
            given[name] = 0  # a placeholder, never used: no entry depends on it
        substitution = values.substitution(self.theta, self.theta.model, None, given)
        return np.array(
            [[numeric(e.xreplace(substitution), "an entry of Theta") for e in row]
             for row in self.matrix.tolist()]
        )  # fmt: skip

    def __str__(self) -> str:
        return report.theta_text(self.theta)

    def __repr__(self) -> str:
        rows, columns = self.matrix.shape
        return f"Theta({rows}x{columns}, monomials {self.monomials})"

    def _repr_latex_(self) -> str:
        K = report.latex(sympy.Matrix([self.monomials]))
        return f"$\\displaystyle {report.theta_latex(self.theta)}, \\quad K^T = {K}$"


@dataclass(frozen=True)
class StateSpace:
    """The state equations. A linear model's descriptor form E x' = A x + B u,
    y = C x + D u: exact sympy matrices, with x the energy variables (q of each C, p of
    each I) named in `states`. A nonlinear model's x' = f(x, u), y = g(x, u): `f` and `g`,
    exact sympy matrices (its A..D exist about an operating point: `Model.linearise`).

    >>> import mtt
    >>> ss = mtt.load(mtt.example("rlc")).state_space  # r = 2, l = 1/2, c unknown
    >>> ss.states
    ('p_l', 'q_c')
    >>> ss.A, ss.B.T, ss.C
    (Matrix([
    [-4, -1/c],
    [ 2,    0]]), Matrix([[1, 0]]), Matrix([[2, 0]]))
    >>> tanks = mtt.load(mtt.example("two_tanks")).state_space
    >>> tanks.nonlinear, tanks.states
    (True, ('q_upper', 'q_lower'))
    """

    equations: Equations | None
    system: NonlinearStateSpace | None = None

    @property
    def nonlinear(self) -> bool:
        return self.system is not None

    @property
    def states(self) -> tuple[str, ...]:
        if self.system is not None:
            return tuple(x.name for x in self.system.states)
        return self.equations.states

    @property
    def f(self) -> sympy.Matrix:
        """x' = f(x, u) (a nonlinear model's)."""
        return self._nonlinear().f

    @property
    def g(self) -> sympy.Matrix:
        """y = g(x, u) (a nonlinear model's)."""
        return self._nonlinear().g

    def _nonlinear(self) -> NonlinearStateSpace:
        if self.system is None:
            raise MttError(
                "a linear model's state space is its matrices E, A, B, C, D", kind="linear_model"
            )
        return self.system

    @cached_property
    def _matrices(self) -> dict[str, sympy.Matrix]:
        if self.equations is None:
            raise MttError(
                f"{self.system.name} is nonlinear: its A, B, C, D exist about an operating "
                "point (model.linearise(u=...)); f and g are its state equations",
                kind="nonlinear_model",
            )
        return self.equations.matrices()

    E = property(lambda self: self._matrices["E"])
    A = property(lambda self: self._matrices["A"])
    B = property(lambda self: self._matrices["B"])
    C = property(lambda self: self._matrices["C"])
    D = property(lambda self: self._matrices["D"])

    def at(self, k: object = None, /, **named: object) -> tuple[np.ndarray, ...]:
        """(A, B, C, D) as floats of x' = A x + B u, y = C x + D u, at the values given as
        to `TransferFunction.at` (E solved: it must be invertible there), the states in the
        order of `states`.

        >>> import mtt
        >>> A, B, C, D = mtt.load(mtt.example("rlc")).state_space.at(0.1)
        >>> A.tolist(), B.ravel().tolist(), C.ravel().tolist(), D.ravel().tolist()
        ([[-4.0, -10.0], [2.0, 0.0]], [1.0, 0.0], [2.0, 0.0], [0.0])
        """
        matrices = self._matrices  # a nonlinear model has none: MttError
        model = self.equations.causal.bondgraph.name
        substitution = values.substitution(self.equations.parametrisation, model, k, named)
        E, A, B, C, D = (
            np.array(
                [numeric(entry.xreplace(substitution), f"an entry of {name}") for entry in matrix],
                dtype=float,
            ).reshape(matrix.shape)
            for name, matrix in matrices.items()
        )
        try:
            return np.linalg.solve(E, A), np.linalg.solve(E, B), C, D
        except np.linalg.LinAlgError:
            raise MttError(
                f"E of {model}'s descriptor form is singular at these values: no x' = A x + B u",
                kind="singular_model",
            ) from None

    @property
    def relations(self) -> tuple[tuple[str, sympy.Expr], ...]:
        """The causal equations, variable = expression (bond variables e1, f1, ...)."""
        return self.equations.relations if self.equations is not None else ()

    def __str__(self) -> str:
        if self.system is not None:
            return nonlinear.equations_text(self.system)
        return report.ss_text(self.equations)

    def __repr__(self) -> str:
        kind = "nonlinear, " if self.nonlinear else ""
        return f"StateSpace({kind}states={self.states})"

    def _repr_latex_(self) -> str:
        if self.system is not None:
            return f"$\\displaystyle {nonlinear.equations_latex(self.system)}$"
        body = ",\\quad ".join(
            f"{name} = {report.latex(matrix)}" for name, matrix in self._matrices.items()
        )
        return f"$\\displaystyle {body}$"


@dataclass(frozen=True)
class SteadyStates:
    """The steady states of a model at a constant input (`Model.equilibrium`): `branches`,
    each a dict state name -> exact value (or a float where sympy could not solve)."""

    system: NonlinearStateSpace
    found: Equilibria

    @property
    def u(self) -> sympy.Expr:
        return self.found.u

    @property
    def exact(self) -> bool:
        return self.found.method == "exact"

    @property
    def branches(self) -> list[dict[str, sympy.Expr]]:
        return [{x.name: v for x, v in b.x.items()} for b in self.found.branches]

    @property
    def numeric(self) -> list[dict[str, float]]:
        """Each branch at the file's values of the unknowns and kept parameters."""
        return [{x.name: v for x, v in b.numeric.items()} for b in self.found.branches]

    def __str__(self) -> str:
        return nonlinear.equilibria_text(self.system, self.found)

    def __repr__(self) -> str:
        return f"SteadyStates(u={self.u}, branches={self.branches})"


@dataclass(frozen=True)
class Causality:
    """The causal strokes: for each bond, the component that receives its effort.

    >>> import mtt
    >>> causality = mtt.load(mtt.example("rlc")).causality  # a series loop: I:l sets its flow
    >>> causality.strokes
    {1: '1:loop', 2: '1:loop', 3: 'I:l', 4: '1:loop', 5: '1:loop'}
    >>> causality.dependent, causality.loops
    ((), ())
    """

    causal: CausalBondGraph

    def _label(self, name: str) -> str:
        return self.causal.bondgraph.component(name).label

    @property
    def strokes(self) -> dict[int, str]:
        """Bond number -> the component (TYPE:NAME) at the end with the causal stroke."""
        return {
            bond.number: self._label(self.causal.stroke_at(bond.number))
            for bond in self.causal.bondgraph.bonds
        }

    @property
    def dependent(self) -> tuple[str, ...]:
        """Storage elements in derivative causality."""
        return tuple(self._label(name) for name in self.causal.dependent)

    @property
    def loops(self) -> tuple[str, ...]:
        """Resistors given an arbitrary causality: each closes an algebraic loop."""
        return tuple(self._label(name) for name in self.causal.loops)

    def __str__(self) -> str:
        return describe(self.causal)

    def __repr__(self) -> str:
        return f"Causality(strokes={self.strokes})"
