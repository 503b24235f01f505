"""Stage 6: transfer function -> Theta, the paper's matrix of the system.

theta = [a0..an, -b0..-bm] from the canonical denominator and numerator, and
theta(k) = Theta K(k): column j of Theta holds the coefficients of the monomial K_j(k).
With one unknown k, K(k) = [1, k, ..., k^N] (every power up to the degree N, as in the
paper). With several unknowns k1..kp, K(k) holds the monomials k1^i1 ... kp^ip that occur
in the coefficients, by total degree, then with higher powers of the earlier unknowns
first: [1, ra, jl, ra^2, ra*jl, ...]. Theta, the unknowns and the monomials are all an
estimator needs to know of the system.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import sympy
from sympy.polys.rings import PolyRing

from mtt.derivation.sparse import as_expr
from mtt.derivation.transfer import TransferFunction
from mtt.language.diagnostics import ModelError, Position, Source, error

Monomial = tuple[int, ...]  # exponents, one per unknown, in the order of `unknowns`


@dataclass(frozen=True)
class Theta:
    """Everything a generated estimator carries about its system."""

    model: str  # the model's name (an identifier)
    description: str | None
    source_name: str  # the model file as named on the command line
    input: str  # "Se:v"
    output: str  # "Df:vm"
    unknowns: tuple[str, ...]  # the parameters identified, in order
    symbols: tuple[str, ...]  # parameters kept symbolic, in model order
    defaults: Mapping[str, sympy.Expr | None]  # file values of the kept symbols (or None)
    assumed: Mapping[str, sympy.Expr]  # exact values substituted for the other parameters
    true_values: Mapping[str, sympy.Expr | None]  # the file's values of the unknowns
    num: sympy.Expr  # canonical numerator, in s, the unknowns and the symbols
    den: sympy.Expr  # canonical denominator
    n: int  # degree of den in s
    m: int  # degree of num in s
    monomials: tuple[Monomial, ...]  # the column monomials K_j: exponents per unknown
    matrix: sympy.Matrix  # (n + 1 + m + 1) x len(monomials): rows a0..an, -b0..-bm
    input_description: str | None = None  # the source's description in the model, if any
    output_description: str | None = None  # the detector's
    # where the model text names things, for messages about them (the generated code's
    # names): the model file, its name's place, and each parameter's declaration
    source: Source | None = field(default=None, repr=False, compare=False)
    name_position: Position | None = field(default=None, repr=False, compare=False)
    declared: Mapping[str, Position] = field(default_factory=dict, repr=False, compare=False)
    # several inputs or outputs: every channel's Theta over the common A(s), output by
    # output (`transfer_matrix.channel_thetas`; this one is the first), and (outputs, inputs)
    channels: tuple[Theta, ...] = field(default=(), repr=False, compare=False)
    shape: tuple[int, int] = (1, 1)

    @property
    def unknown(self) -> str | None:
        """The unknown, when there is exactly one."""
        return self.unknowns[0] if len(self.unknowns) == 1 else None

    @property
    def true_value(self) -> sympy.Expr | None:
        """The file's value of the unknown, when there is exactly one."""
        return self.true_values.get(self.unknown) if self.unknown else None

    @property
    def N(self) -> int:
        """The degree of theta in the unknowns (the total degree, with several)."""
        return max(sum(monomial) for monomial in self.monomials)

    @property
    def degrees(self) -> dict[str, int]:
        """Each unknown's highest power in theta."""
        return {
            name: max(monomial[i] for monomial in self.monomials)
            for i, name in enumerate(self.unknowns)
        }

    @property
    def row_labels(self) -> tuple[str, ...]:
        return tuple(f"a{i}" for i in range(self.n + 1)) + tuple(
            f"-b{i}" for i in range(self.m + 1)
        )

    @property
    def column_labels(self) -> tuple[str, ...]:
        """Each column's monomial as text: `1`, `k`, `k^2`, `ra*jl`."""
        return tuple(monomial_text(self.unknowns, monomial) for monomial in self.monomials)

    def K(self, values: Mapping[str, sympy.Expr]) -> sympy.Matrix:
        """K(k) at the given values of the unknowns: theta = Theta K(k)."""
        return sympy.Matrix(
            [
                sympy.Mul(
                    *(values[name] ** e for name, e in zip(self.unknowns, monomial, strict=True))
                )
                for monomial in self.monomials
            ]
        )


def refuse_cancelled(theta: Theta, *others: Theta) -> None:
    """`no_dependence` at the declaration of each unknown that occurs in no column of Theta
    (of any channel's Theta, with `others`): it reached the output (the structural check
    passed) but cancels out of the exact transfer function (`R:a(k)` in series with
    `R:b(-k)`), so nothing could identify it."""
    thetas = (theta, *others)
    idle = [name for name in theta.unknowns if all(t.degrees[name] == 0 for t in thetas)]
    what = (
        "every entry of the exact transfer matrix"
        if others
        else f"the exact transfer function from {theta.input} to {theta.output}"
    )
    if idle:
        raise ModelError(
            theta.source or Source(theta.source_name, ""),
            [
                error(
                    "no_dependence",
                    f"the unknown {name} cancels out of {what}, so the data cannot tell its "
                    "value; make it a known parameter (or choose the unknowns with --unknown)",
                    theta.declared.get(name),
                )
                for name in idle
            ],
        )


def monomial_text(unknowns: tuple[str, ...], monomial: Monomial) -> str:
    factors = [
        name if power == 1 else f"{name}^{power}"
        for name, power in zip(unknowns, monomial, strict=True)
        if power
    ]
    return "*".join(factors) or "1"


def column_order(monomial: Monomial) -> tuple:
    """By total degree, then higher powers of the earlier unknowns first."""
    return (sum(monomial), tuple(-e for e in monomial))


def theta_matrix(tf: TransferFunction) -> Theta:
    """Theta from the canonical transfer function (one column, 1, without an unknown)."""
    equations = tf.equations
    graph = equations.causal.bondgraph
    params = equations.parametrisation
    p = len(params.unknowns)
    n, m = tf.degree("den"), tf.degree("num")
    # each entry's terms first, then each entry made once (a sum built term by term costs
    # time quadratic in its terms)
    terms: list[dict[Monomial, dict]] = [{} for _ in range(n + m + 2)]
    for offset, poly, sign in ((0, tf.den, 1), (n + 1, tf.num, -1)):
        for monom, coefficient in poly.iterterms():
            power_s, powers, others = monom[0], monom[1 : 1 + p], monom[1 + p :]
            entry = terms[offset + power_s].setdefault(powers, {})
            entry[others] = coefficient if sign > 0 else -coefficient
    rest = PolyRing(tf.gens[1 + p :] or (sympy.Dummy(),), tf.num.ring.domain)  # s, unknowns first
    rows = [
        {powers: as_expr(rest.from_dict(entry if tf.gens[1 + p :] else {(0,): entry[()]}))
         for powers, entry in row.items()}
        for row in terms
    ]  # fmt: skip
    occurring = {monomial for row in rows for monomial in row}
    if p <= 1:  # every power up to the degree
        occurring = {(j,) * p for j in range(max(sum(mono) for mono in occurring) + 1)}
    monomials = tuple(sorted(occurring, key=column_order))
    source, detector = (
        graph.component(names[0]) for names in (equations.inputs, equations.outputs)
    )
    matrix = sympy.Matrix([[row.get(j, sympy.Integer(0)) for j in monomials] for row in rows])
    return Theta(
        model=graph.name,
        description=graph.description,
        source_name=graph.source.name,
        input=source.label,
        output=detector.label,
        unknowns=params.unknowns,
        symbols=params.symbols,
        defaults=params.defaults,
        assumed=params.assumed,
        true_values=params.true_values,
        num=tf.numerator,
        den=tf.denominator,
        n=n,
        m=m,
        monomials=monomials,
        matrix=matrix,
        input_description=source.description,
        output_description=detector.description,
        source=graph.source,
        name_position=graph.name_position,
        declared={name: parameter.position for name, parameter in graph.parameters.items()},
    )
