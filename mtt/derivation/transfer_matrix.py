"""Stage 5 with several inputs and outputs: `Equations` -> `TransferMatrix`, exact.

G(s) = C (sE - A)^-1 B + D has an entry per output i and input j: G_ij is the transfer
function from input j to output i with the other inputs at zero, derived exactly and
reduced to its canonical form (`transfer`). Over the common characteristic polynomial
A(s) = det(sE - A), G_ij = B_ij(s) / A(s) with every B_ij a polynomial: A's factors free
of s that every B_ij shares are removed (integer coefficients, content 1, A's leading term
positive), its factors in s never, so A keeps every mode of the state space, also one
that no entry shows (then each entry's reduced form cancels it: `cancelled`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cached_property

import sympy
from sympy.polys.rings import PolyElement

from mtt.derivation import constants
from mtt.derivation.equations import Equations
from mtt.derivation.theta import Theta, column_order, refuse_cancelled, theta_matrix
from mtt.derivation.transfer import LAPLACE, TransferFunction, transfer_function
from mtt.language.diagnostics import ModelError, error


@dataclass(frozen=True)
class TransferMatrix:
    """G(s) = [B_ij(s) / A(s)]: rows are the outputs, columns the inputs."""

    equations: Equations
    entries: tuple[tuple[TransferFunction, ...], ...]  # [output][input], each reduced
    characteristic: PolyElement  # A(s), in the ring of the entries
    numerators: tuple[tuple[PolyElement, ...], ...]  # B_ij, G_ij = B_ij / A

    @property
    def inputs(self) -> tuple[str, ...]:
        """The inputs' labels (Se:v), one per column."""
        graph = self.equations.causal.bondgraph
        return tuple(graph.component(name).label for name in self.equations.inputs)

    @property
    def outputs(self) -> tuple[str, ...]:
        """The outputs' labels (Df:w), one per row."""
        graph = self.equations.causal.bondgraph
        return tuple(graph.component(name).label for name in self.equations.outputs)

    @property
    def shape(self) -> tuple[int, int]:
        return len(self.outputs), len(self.inputs)

    @property
    def A(self) -> sympy.Expr:
        """The common characteristic polynomial."""
        return self.characteristic.as_expr()

    @cached_property
    def B(self) -> sympy.Matrix:
        """The numerators over A."""
        return sympy.Matrix([[b.as_expr() for b in row] for row in self.numerators])

    @property
    def n(self) -> int:
        """The degree of A in s: the number of modes."""
        return _degree(self.characteristic)

    @cached_property
    def thetas(self) -> dict[tuple[int, int], Theta]:
        """Theta of each entry that is not zero, by (output, input): what the data of that
        channel determine."""
        return {
            (i, j): theta_matrix(entry)
            for i, row in enumerate(self.entries)
            for j, entry in enumerate(row)
            if entry.num
        }

    def cancelled(self, output: int, input: int) -> sympy.Expr | None:
        """The factor in s that B_ij and A share, which the reduced entry cancels (None:
        the entry over A is already reduced, up to factors free of s)."""
        b = self.numerators[output][input]
        if not b:
            return None
        common = b.gcd(self.characteristic)
        return common.as_expr() if _degree(common) else None


def _degree(poly: PolyElement) -> int:
    return max((m[0] for m in poly.monoms()), default=0)


def _content(poly: PolyElement) -> PolyElement:
    """The gcd of the coefficients of poly as a polynomial in s (a polynomial in the
    unknowns and the symbols, with the integer content)."""
    ring = poly.ring
    parts: dict[int, PolyElement] = {}
    for monom, coefficient in poly.terms():
        part = parts.setdefault(monom[0], ring.zero)
        parts[monom[0]] = part + ring({(0, *monom[1:]): coefficient})
    content = ring.zero
    for part in parts.values():
        content = content.gcd(part)
    return content


def _characteristic(equations: Equations, ring) -> PolyElement:
    """det(sE - A), cleared of denominators row by row, in `ring`: by evaluation and
    interpolation (`determinants`, the pencil bordered by a 1), else by sympy's
    fraction-free elimination."""
    from mtt.derivation import determinants  # numpy

    size = len(equations.states)
    if not size:
        return ring.one
    field = ring.to_field().to_domain()
    lift = lambda M: M.to_sparse().convert_to(field)  # noqa: E731
    pencil = lift(equations.E) * field.from_sympy(LAPLACE) - lift(equations.A)
    _, cleared = pencil.clear_denoms_rowwise(convert=True)
    entries, polynomials = cleared.to_dok(), cleared.domain.ring
    algebraic = not polynomials.domain.is_ZZ
    if algebraic:  # over Q(theta): theta as one more variable (`constants`)
        entries, _, polynomials = constants.over_integers(entries, polynomials)
    entries[size, size] = polynomials.one
    found = determinants.bordered_determinants(entries, size + 1, polynomials)
    determinant = cleared.to_dense().det() if found is None else found[0]
    if found is not None and algebraic:
        determinant = constants.reduced(determinant, cleared.domain.ring)
    if not determinant:
        raise ModelError(
            equations.causal.bondgraph.source,
            [error("singular_model", "the equations have no unique solution: "
                   "det(sE - A) is identically zero")],
        )  # fmt: skip
    return ring(determinant.as_expr()) if determinant.ring != ring else determinant


def transfer_matrix(equations: Equations) -> TransferMatrix:
    """Every entry exactly, then the common form over the characteristic polynomial."""
    outputs, inputs = len(equations.outputs), len(equations.inputs)
    entries = tuple(
        tuple(transfer_function(equations.channel(i, j)) for j in range(inputs))
        for i in range(outputs)
    )
    ring = entries[0][0].den.ring
    A = _characteristic(equations, ring)
    A = A.exquo(_content(A))
    quotients, scales = [], []
    for row in entries:
        for entry in row:
            num, den = entry.num.set_ring(ring), entry.den.set_ring(ring)
            scale = _content(den)  # a factor free of s of the reduced denominator
            quotients.append(num * A.exquo(den.exquo(scale)))
            scales.append(scale)
    common = ring.one
    for scale in scales:
        common = common * scale.exquo(common.gcd(scale))  # their lcm
    numerators = [q * common.exquo(scale) for q, scale in zip(quotients, scales, strict=True)]
    A = A * common
    shared = _content(A)
    for b in numerators:
        shared = shared.gcd(_content(b)) if b else shared
    A, numerators = A.exquo(shared), [b.exquo(shared) for b in numerators]
    if ring.domain.is_ZZ and A.LC < 0:
        A, numerators = -A, [-b for b in numerators]
    return TransferMatrix(
        equations=equations,
        entries=entries,
        characteristic=A,
        numerators=tuple(tuple(numerators[i * inputs : (i + 1) * inputs]) for i in range(outputs)),
    )


def channel_thetas(matrix: TransferMatrix) -> tuple[Theta, ...]:
    """Theta of every channel (output i, input j, row by row) over the common A(s): rows
    a0..an shared, then -b0..-bm of B_ij, every channel padded to the largest m and the
    columns of every monomial that occurs in any: what an estimator from several inputs and
    outputs needs (A(s) y_i = sum_j B_ij(s) u_j in the paper's cost, entry by entry in the
    exact fit)."""
    gens, A = matrix.entries[0][0].gens, matrix.characteristic
    thetas = [
        theta_matrix(TransferFunction(matrix.equations.channel(i, j), gens, b, A))
        for i, row in enumerate(matrix.numerators)
        for j, b in enumerate(row)
    ]
    m = max(theta.m for theta in thetas)
    monomials = tuple(
        sorted({mono for theta in thetas for mono in theta.monomials}, key=column_order)
    )
    if len(thetas[0].unknowns) <= 1 and monomials:  # every power up to the degree
        monomials = tuple(
            (j,) * len(thetas[0].unknowns) for j in range(max(map(sum, monomials)) + 1)
        )

    def padded(theta: Theta) -> Theta:
        rows = theta.matrix.tolist()
        rows += [[0] * len(theta.monomials) for _ in range(m - theta.m)]
        where = {mono: c for c, mono in enumerate(theta.monomials)}
        entries = [[row[where[mono]] if mono in where else 0 for mono in monomials] for row in rows]
        return replace(theta, m=m, monomials=monomials, matrix=sympy.Matrix(entries))

    return tuple(padded(theta) for theta in thetas)


def estimator_theta(equations: Equations) -> Theta:
    """Theta for a generated estimator: the transfer function's, or with several inputs or
    outputs channel [0, 0]'s over the common A(s) with every channel's (`channel_thetas`),
    each unknown in some channel."""
    if not equations.several:
        return theta_matrix(transfer_function(equations))
    channels = channel_thetas(transfer_matrix(equations))
    refuse_cancelled(*channels)
    shape = (len(equations.outputs), len(equations.inputs))
    return replace(channels[0], channels=channels, shape=shape)
