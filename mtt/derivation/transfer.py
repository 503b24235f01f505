"""Stage 5: `Equations` -> `TransferFunction`, G(s) = C (sE - A)^-1 B + D, exact and canonical.

Canonical form: numerator and denominator coprime as polynomials in s, the unknown
and every symbolic parameter; integer coefficients with overall content 1; the
denominator's coefficient of its highest power of s has a positive leading term.
The linear solve is fraction-free over the polynomial ring (sympy's DomainMatrix),
which keeps large models fast.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction
from math import gcd

import sympy
from sympy.polys.domains import ZZ
from sympy.polys.matrices import DomainMatrix
from sympy.polys.rings import PolyElement

from mtt.derivation import constants, deadline, sparse
from mtt.derivation.budget import Meter, TooLarge, refusal
from mtt.derivation.elimination import bordered_ratio
from mtt.derivation.equations import Equations
from mtt.language.bondgraph import BondGraph
from mtt.language.diagnostics import ModelError, error
from mtt.language.measures import MAX_DIGITS

LAPLACE = sympy.Symbol("s")


@dataclass(frozen=True)
class TransferFunction:
    equations: Equations
    gens: tuple[sympy.Expr, ...]  # s, then the generators of the coefficient field
    num: PolyElement  # over ZZ, in `gens`
    den: PolyElement

    @property
    def numerator(self) -> sympy.Expr:
        return sparse.as_expr(self.num)

    @property
    def denominator(self) -> sympy.Expr:
        return sparse.as_expr(self.den)

    def degree(self, which: str) -> int:
        """The degree in s of 'num' or 'den'."""
        poly = self.num if which == "num" else self.den
        return max((m[0] for m in poly.monoms()), default=0)


def _ground(equations: Equations):
    """The ground field of the coefficients: QQ, or an algebraic number field."""
    K = equations.domain
    return K.domain if K.is_FractionField else K


def _field(equations: Equations):
    """s adjoined to the coefficient field of the equations, as fractions over ZZ (or over
    the algebraic number field of the model's roots).

    Over ZZ the fraction-free solve below runs several times faster than over QQ.
    """
    K = equations.domain
    gens = (LAPLACE, *(K.symbols if K.is_FractionField else ()))
    ground = _ground(equations)
    return (ZZ if ground.is_QQ else ground).frac_field(*gens), gens


def _lifter(equations: Equations, F):
    """Matrices of the equations as matrices over F. Over Q(symbols), each fraction's
    exponents get s's in front and its rational coefficients are cleared: sympy's own
    conversion reorders every monomial through a generic path, a third of a second an
    entry with a few hundred symbols."""
    K = equations.domain
    if not (K.is_FractionField and K.domain.is_QQ):
        return lambda M: M.to_sparse().convert_to(F)
    ring = F.field.ring

    def element(fraction):
        terms = [*fraction.numer.iterterms(), *fraction.denom.iterterms()]
        scale = math.lcm(*(int(c.denominator) for _, c in terms))
        shifted = lambda poly: ring.from_dict(  # noqa: E731
            {(0, *m): int(c.numerator) * (scale // int(c.denominator)) for m, c in poly.iterterms()}
        )
        return F.field.raw_new(shifted(fraction.numer), shifted(fraction.denom))

    def lift(M):
        rows = {i: {j: element(v) for j, v in row.items()} for i, row in M.to_sdm().items()}
        return DomainMatrix(rows, M.shape, F)

    return lift


def _singular(equations: Equations, why: str) -> ModelError:
    return ModelError(
        equations.causal.bondgraph.source,
        [error("singular_model", f"the equations have no unique solution{why}")],
    )


@deadline.timed("the transfer function", lambda equations: equations.causal.bondgraph)
def transfer_function(equations: Equations) -> TransferFunction:
    """G(s) = C (sE - A)^-1 B + D; raise `ModelError` (singular_model) if it does not exist.

    G = det([[sE - A, B], [-C, D]]) / det(sE - A), both determinants exact by evaluation
    and interpolation (`determinants`); when that would need too many points (many kept
    symbols), by sparse fraction-free elimination over the polynomials (`elimination`),
    within the equations' budget (`ModelError` too_large beyond it).
    """
    try:
        return _transfer_function(equations, Meter(equations.budget, "transfer function"))
    except TooLarge as stop:
        params = equations.parametrisation
        raise refusal(equations.causal.bondgraph, params.free, stop) from None


def _transfer_function(equations: Equations, meter: Meter) -> TransferFunction:
    from mtt.derivation import determinants as evaluation  # numpy

    if equations.several:
        raise several_signals(equations)
    F, gens = _field(equations)
    lift = _lifter(equations, F)
    D = lift(equations.D)[0, 0].element
    num, den = D.numer, D.denom
    size = len(equations.states)
    if size:
        pencil = lift(equations.E) * F.from_sympy(LAPLACE) - lift(equations.A)
        bordered = pencil.hstack(lift(equations.B)).vstack(
            (-lift(equations.C)).hstack(lift(equations.D))
        )
        denominators, cleared = bordered.clear_denoms_rowwise(convert=True)
        ring = cleared.domain
        algebraic = not _ground(equations).is_QQ  # over Q(theta): theta as a variable
        entries, scales, integers = cleared.to_dok(), {}, ring.ring
        if algebraic:
            entries, scales, integers = constants.over_integers(entries, ring.ring)
        try:
            determinants = evaluation.bordered_determinants(entries, size + 1, integers)
        except evaluation.TooLarge as bits:
            raise _too_large(equations, f"could have {int(bits.args[0] * 0.30103)}") from None
        if determinants is None:  # fraction-free, over the integers still
            num, den = _eliminated(entries, size + 1, integers, algebraic and ring.ring, meter)
        else:
            num, den = determinants[1], determinants[0]
        if algebraic:
            num, den = (constants.reduced(p, ring.ring) for p in (num, den))
        if not den:
            raise _singular(equations, ": det(sE - A) is identically zero")
        # the last row's multipliers (the others' cancel between the two determinants)
        last = F.convert(denominators.to_dok()[size, size]).numer * scales.get(size, 1)
        den = sparse.product(den, last, meter)
        meter.spend(len(num) * len(den) * sparse.term_cost(num.ring))
        # one gcd, in the ring (fractions would take several), with its cofactors (sympy's
        # division takes time quadratic in the terms)
        _, num, den = num.cofactors(den)
    tf = _canonical(equations, gens, num, den)
    digits = max((_digits(x) for p in (tf.num, tf.den) for x in _rationals((p,))), default=0)
    if digits > MAX_DIGITS:
        raise _too_large(equations, f"have {int(digits)}")
    return tf


def signal_labels(graph: BondGraph, names) -> str:
    """Sources or detectors as the user writes them (Se:v, Df:i), for a message."""
    return ", ".join(graph.component(name).label for name in names)


def several_signals(equations: Equations) -> ModelError:
    """What is said where a step takes one input and one output and the model has more."""
    graph = equations.causal.bondgraph
    inputs, outputs = (
        signal_labels(graph, equations.inputs),
        signal_labels(graph, equations.outputs),
    )
    message = (
        f"from {inputs} to {outputs}: several inputs or "
        "outputs make a transfer matrix (mtt ss, tf, theta, identifiability and bode derive "
        "it, and Model.transfer_matrix); this step takes one input and one output: choose "
        "them with --input TYPE:NAME --output TYPE:NAME (input=, output= in mtt.load)"
    )
    return ModelError(graph.source, [error("several_signals", message)])


def _digits(x: Fraction) -> float:
    return max(math.log10(abs(x.numerator)) if x else 0, math.log10(x.denominator))


def _too_large(equations: Equations, have: str) -> ModelError:
    """The transfer function's coefficients are beyond `MAX_DIGITS` digits: reported at
    the component whose value holds the largest number."""
    params = equations.parametrisation
    largest, where = -1.0, None
    for component in equations.causal.bondgraph.components:
        if component.argument is not None:
            value = params.apply(component.argument.value)
            size = max(
                (_digits(Fraction(int(r.p), int(r.q))) for r in value.atoms(sympy.Rational)),
                default=0,
            )
            if size > largest:
                largest, where = size, component.argument.position
    message = (
        f"the transfer function's coefficients {have} digits, more than {MAX_DIGITS} (a limit): "
        "the model's numbers are too large together; scale its units"
    )
    return ModelError(equations.causal.bondgraph.source, [error("too_large", message, where)])


def _eliminated(entries: dict, size: int, ring, algebraic, meter: Meter):
    """det(whole) and det(leading block), both divided by the factors of the latter that
    cancel, by sparse fraction-free elimination; det(leading block) is zero for a singular
    model (over Q(theta), `algebraic` the ring over it: when a factor vanishes there)."""
    ratio = bordered_ratio(entries, size, ring, meter)
    factors = () if ratio is None else (*ratio.den, *ratio.other)
    if ratio is None or algebraic and not all(constants.reduced(f, algebraic) for f in factors):
        return ring.zero, ring.zero
    den = ring.one
    for factor in sorted(ratio.den, key=len):
        den = sparse.product(den, factor, meter)
    return ratio.num, den


def _rationals(polys) -> list[Fraction]:
    """The rational numbers the coefficients of polynomials are written with (3/2 and 1/6 in
    3/2 + sqrt(2)/6, over an algebraic number field)."""
    if polys and polys[0].ring.domain.is_ZZ:
        return [Fraction(int(c)) for p in polys for c in p.coeffs()]
    return [
        Fraction(int(r.p), int(r.q))
        for p in polys
        for c in p.coeffs()
        for r in p.ring.domain.to_sympy(c).as_coefficients_dict().values()
    ]


def _canonical(equations: Equations, gens, num, den) -> TransferFunction:
    """Coprime, integer, content 1, positive leading term of the highest power of s.

    Over an algebraic number field, the same for the rational numbers the coefficients are
    written with (sqrt(2)/6 with 1/6): den's leading coefficient made 1, then those numbers
    cleared of denominators and of their common factor (for rational coefficients, this is
    the form over ZZ).
    """
    domain = num.ring.domain  # num and den coprime
    if not domain.is_ZZ:
        num, den = num.quo_ground(den.LC), den.quo_ground(den.LC)
        scale = domain.convert(math.lcm(*(x.denominator for x in _rationals((num, den)))))
        num, den = num.mul_ground(scale), den.mul_ground(scale)
        content = domain.convert(math.gcd(*(int(x) for x in _rationals((num, den)) if x)))
        return TransferFunction(equations, gens, num.quo_ground(content), den.quo_ground(content))
    content = gcd(*(int(c) for c in (*num.coeffs(), *den.coeffs()) if c))
    num, den = num.quo_ground(content), den.quo_ground(content)
    if den.LC < 0:
        num, den = -num, -den
    return TransferFunction(equations, gens, num, den)
