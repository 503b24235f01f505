"""A model with several inputs or outputs, as a Python user holds it: its transfer matrix,
exact, and the same at given values as floats (for scipy.signal and python-control)."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import sympy

from mtt.api import values
from mtt.api.exact import numeric
from mtt.api.results import Theta, TransferFunction
from mtt.derivation import transfer_matrix as derived
from mtt.derivation.theta import theta_matrix
from mtt.derivation.transfer import LAPLACE
from mtt.language.diagnostics import MttError
from mtt.present import matrix as present


@dataclass(frozen=True)
class TransferMatrix:
    """G(s) = B(s) / A(s): a row per output, a column per input, each entry B_ij / A over
    the common characteristic polynomial A, exact (sympy); `G` holds the entries reduced.

    >>> import mtt
    >>> motor = mtt.load(mtt.example("dc_motor_load"), input="Se:v,Se:tl")
    >>> G = motor.transfer_matrix
    >>> G.inputs, G.outputs
    (('Se:v', 'Se:tl'), ('Df:speed',))
    >>> G.A
    10*jl*s**2 + 100*jl*s + 10*s**2 + 101*s + 110
    >>> G.B
    Matrix([[100, 10*s + 100]])
    """

    matrix: derived.TransferMatrix

    @property
    def inputs(self) -> tuple[str, ...]:
        return self.matrix.inputs

    @property
    def outputs(self) -> tuple[str, ...]:
        return self.matrix.outputs

    @property
    def shape(self) -> tuple[int, int]:
        """(outputs, inputs)."""
        return self.matrix.shape

    @property
    def A(self) -> sympy.Expr:
        """The common characteristic polynomial, det(sE - A) up to a factor free of s."""
        return self.matrix.A

    @property
    def B(self) -> sympy.Matrix:
        """The numerators over A: G = B / A."""
        return self.matrix.B

    @property
    def n(self) -> int:
        """The degree of A in s."""
        return self.matrix.n

    @cached_property
    def G(self) -> sympy.Matrix:
        """Each entry reduced: num_ij / den_ij with nothing in s left in common."""
        return sympy.Matrix(
            [[entry.numerator / entry.denominator for entry in row] for row in self.matrix.entries]
        )

    def _index(self, output: int | str, input: int | str) -> tuple[int, int]:
        """An entry by position or by its output's and input's labels."""
        found = []
        for given, labels, what in (
            (output, self.outputs, "output"), (input, self.inputs, "input")
        ):  # fmt: skip
            position = isinstance(given, int) and not isinstance(given, bool)
            if isinstance(given, str) and given in labels:
                found.append(labels.index(given))
            elif position and 0 <= given < len(labels):
                found.append(given)
            else:
                raise MttError(
                    f"{given!r} is not an {what} of the transfer matrix (its {what}s: "
                    f"{', '.join(labels)}, or 0..{len(labels) - 1})",
                    kind="bad_argument",
                )
        return found[0], found[1]

    def entry(self, output: int | str, input: int | str) -> TransferFunction:
        """The transfer function from an input to an output, reduced (by position, or by
        label: entry("Df:speed", "Se:tl"))."""
        i, j = self._index(output, input)
        return TransferFunction(theta_matrix(self.matrix.entries[i][j]))

    def theta(self, output: int | str, input: int | str) -> Theta:
        """That entry's Theta: what the data of that channel tell of the unknowns."""
        i, j = self._index(output, input)
        if (i, j) not in self.matrix.thetas:
            raise MttError(
                f"the entry from {self.inputs[j]} to {self.outputs[i]} is zero: it has no Theta",
                kind="bad_argument",
            )
        return Theta(self.matrix.thetas[i, j])

    def cancelled(self, output: int | str, input: int | str) -> sympy.Expr | None:
        """The factor in s that entry's B and A share (the reduced entry has cancelled it),
        or None."""
        return self.matrix.cancelled(*self._index(output, input))

    def at(self, k: object = None, /, **named: object) -> tuple[np.ndarray, np.ndarray]:
        """(B, A) as floats at the unknowns' value k and the parameters named (as
        `TransferFunction.at`): B an array (outputs, inputs, d + 1) of coefficients, A the
        d + 1 coefficients, highest power of s first, d the highest degree of A and B;
        G = B / A.

        >>> import mtt
        >>> B, A = mtt.load(mtt.example("dc_motor_load"), input="Se:v,Se:tl").transfer_matrix.at()
        >>> B.shape, A.tolist()
        ((1, 2, 3), [110.0, 1101.0, 110.0])
        """
        parametrisation = self.matrix.equations.parametrisation
        model = self.matrix.equations.causal.bondgraph.name
        substitution = values.substitution(parametrisation, model, k, named)
        size = max(sympy.degree(p, LAPLACE) for p in (self.A, *self.B)) + 1

        def coefficients(polynomial: sympy.Expr, what: str) -> list[float]:
            terms = sympy.Poly(polynomial, LAPLACE).all_coeffs()
            floats = [numeric(c.xreplace(substitution), f"a coefficient of {what}") for c in terms]
            return [0.0] * (size - len(floats)) + floats

        A = np.array(coefficients(self.A, "A"))
        if not A.any():
            raise MttError("the characteristic polynomial is zero at these values",
                           kind="singular_model")  # fmt: skip
        B = np.array([[coefficients(b, "B") for b in row] for row in self.B.tolist()])
        return B, A

    def __str__(self) -> str:
        return present.matrix_text(self.matrix)

    def __repr__(self) -> str:
        rows, columns = self.shape
        return f"TransferMatrix({rows}x{columns}, inputs={self.inputs}, outputs={self.outputs})"

    def _repr_latex_(self) -> str:
        return f"$\\displaystyle {present.matrix_latex(self.matrix)}$"
