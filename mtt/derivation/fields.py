"""The algebra of identifiability: fibres of k -> [theta(k)], and what the data determine.

Values k give the transfer function of true values k* exactly when f(k) = f(k*) for the
coefficient ratios f = theta_i / theta_r (see `identifiability`): k lies in the fibre of f
through k*. In the variables (t, k) the fibre is cut out by the numerators of
f_i(k) - f_i(k*) and by 1 - t Q(k), Q the product of the denominators (the saturation
variable t keeps them away from zero). Its reduced Groebner basis tells:

* membership: a rational function h is determined by the data (lies in the field F the
  ratios generate) exactly when h(k) - h(k*) vanishes on the fibre of a generic k*: when
  its numerator lies in the fibre's ideal, which is radical for generic k* (generic
  smoothness; Mueller-Quade and Steinwandt, J. Symb. Comput. 1999);
* the number of points of a zero-dimensional fibre: its standard monomials;
* the points: in shape position (a linear form z of k that separates them) the lex basis
  is {t - g_t(z), k_i - g_i(z), P(z)}, so the roots of P give every point, and with k*
  symbolic (coefficients in the field Q(k*)), each linear factor of P a point rational in k*.
"""

from __future__ import annotations

import random
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cached_property
from itertools import combinations, product

import sympy
from sympy.polys.domains import QQ
from sympy.polys.fglmtools import matrix_fglm
from sympy.polys.groebnertools import groebner as ring_groebner
from sympy.polys.orderings import grevlex, lex
from sympy.polys.rings import PolyElement, PolyRing

from mtt.derivation.theta import Theta

Fraction = tuple[sympy.Expr, sympy.Expr]  # numerator and denominator, polynomials in k
SEED = 20240611  # pseudo-random choices are the same at every run


@dataclass(frozen=True)
class System:
    """Theta's coefficient polynomials theta_i(k), and symbols for the true values k*. With
    several channels (a transfer matrix), each channel's coefficients are a group: the
    data determine the ratios within each group."""

    xs: tuple[sympy.Symbol, ...]  # the unknowns k
    ys: tuple[sympy.Dummy, ...]  # their true values k*
    symbols: tuple[sympy.Symbol, ...]  # the parameters kept symbolic: generic constants
    groups: tuple[tuple[sympy.Expr, ...], ...]  # per channel: rows of theta(k) not 0

    @classmethod
    def of(cls, *thetas: Theta) -> System:
        theta = thetas[0]
        xs = tuple(sympy.Symbol(name) for name in theta.unknowns)
        values = dict(zip(theta.unknowns, xs, strict=True))
        return cls(
            xs=xs,
            ys=tuple(sympy.Dummy(f"{name}_true") for name in theta.unknowns),
            symbols=tuple(sympy.Symbol(name) for name in theta.symbols),
            groups=tuple(
                tuple(e for e in (sympy.expand(c) for c in t.matrix * t.K(values)) if e != 0)
                for t in thetas
            ),
        )

    @property
    def coefficients(self) -> tuple[sympy.Expr, ...]:
        """Every channel's coefficients."""
        return tuple(c for group in self.groups for c in group)

    @property
    def identity(self) -> dict[str, sympy.Expr]:
        return {x.name: x for x in self.xs}

    def named(self, expression: sympy.Expr) -> sympy.Expr:
        """A function of the true values, written with the unknowns' names."""
        return expression.xreplace(dict(zip(self.ys, self.xs, strict=True)))

    def depends(self, expression: sympy.Expr) -> bool:
        return bool(expression.free_symbols & set(self.xs))

    def ratios(self) -> list[Fraction]:
        """theta_i / theta_r for every i != r in each group, r the row with the fewest
        terms (a constant one when there is one): they generate what the data determine."""
        found = []
        for rows in self.groups:
            r = min(
                range(len(rows)),
                key=lambda i: (self.depends(rows[i]), len(sympy.Add.make_args(rows[i]))),
            )
            found += [
                sympy.fraction(sympy.cancel(rows[i] / rows[r])) for i in range(len(rows)) if i != r
            ]
        return found

    def generic(self) -> Fibre:
        """The fibre of the ratios through symbolic true values."""
        true = dict(zip(self.xs, self.ys, strict=True))
        return Fibre(self, true, QQ.frac_field(*self.ys, *self.symbols)).of(self.ratios())

    def at(self, values: Mapping[str, sympy.Rational]) -> Fibre:
        """The fibre of the ratios through numeric true values (kept symbols valued too)."""
        true = {s: values[s.name] for s in (*self.xs, *self.symbols)}
        return Fibre(self, true, QQ).of(self.ratios())


@dataclass(frozen=True)
class Fibre:
    """The values k at which given rational functions take their values at k*."""

    system: System
    true: dict[sympy.Symbol, sympy.Expr]  # k -> k* (and at a point, symbol -> value)
    domain: object  # the field of the true values: Q(k*, symbols), or QQ at a point
    functions: tuple[Fraction, ...] = ()

    def of(self, functions: list[Fraction]) -> Fibre:
        """The fibre of other functions through the same true values."""
        return Fibre(self.system, self.true, self.domain, tuple(functions))

    @property
    def numeric(self) -> bool:
        return self.domain == QQ

    def _constant(self, expression: sympy.Expr) -> sympy.Expr:
        """At a point, the kept symbols take their values (else they stay generic)."""
        if not self.numeric:
            return expression
        return expression.xreplace({s: self.true[s] for s in self.system.symbols})

    def _difference(self, function: Fraction) -> sympy.Expr:
        """The numerator of h(k) - h(k*), h = p/q."""
        p, q = (self._constant(e) for e in function)
        return sympy.expand(p * q.xreplace(self.true) - p.xreplace(self.true) * q)

    @cached_property
    def ring(self) -> PolyRing:
        """(t, k...) when some denominator depends on k, else (k...); grevlex."""
        saturated = any(self.system.depends(q) for _, q in self.functions)
        gens = ((sympy.Dummy("t"),) if saturated else ()) + self.system.xs
        return PolyRing(gens, self.domain, grevlex)

    @cached_property
    def basis(self) -> list[PolyElement]:
        """The reduced Groebner basis of the fibre's ideal; empty for the zero ideal."""
        ring = self.ring
        equations = [ring.from_expr(self._difference(f)) for f in self.functions]
        denominators = {q for _, q in self.functions if self.system.depends(q)}
        if denominators:
            product_ = sympy.expand(self._constant(sympy.sqf_part(sympy.Mul(*denominators))))
            equations.append(1 - ring.gens[0] * ring.from_expr(product_))
        equations = [e for e in equations if e]
        return ring_groebner(equations, ring) if equations else []

    def contains(self, function: Fraction) -> bool:
        """Whether h = p/q takes its true value on the whole fibre."""
        difference = self._difference(function)
        if difference == 0:
            return True
        return bool(self.basis) and not self.ring.from_expr(difference).rem(self.basis)

    @property
    def zero_dimensional(self) -> bool:
        """Finitely many points: a pure power of every variable leads some basis element."""
        leading = [g.LM for g in self.basis]
        return all(any(sum(m) == m[i] > 0 for m in leading) for i in range(self.ring.ngens))

    def count(self) -> int:
        """The number of points of a zero-dimensional fibre, with multiplicity."""
        leading = [g.LM for g in self.basis]
        bounds = [min(m[i] for m in leading if sum(m) == m[i]) for i in range(self.ring.ngens)]
        return sum(
            not any(all(a >= b for a, b in zip(m, lm, strict=True)) for lm in leading)
            for m in product(*(range(b) for b in bounds))
        )

    def _shape(self) -> tuple[PolyElement, dict[sympy.Symbol, PolyElement]] | None:
        """(P(z), {k_i: g_i(z)}) for a separating linear form z, or None."""
        rng = random.Random(SEED)
        z = sympy.Dummy("z")
        ring = PolyRing((*self.ring.symbols, z), self.domain, grevlex)
        univariate = PolyRing((z,), self.domain, lex)
        xs = self.system.xs
        last = ring.ngens - 1
        for _ in range(4):
            form = ring.from_expr(z - sum(rng.randint(1, 9) * x for x in xs))
            basis = ring_groebner([*(g.set_ring(ring) for g in self.basis), form], ring)
            eliminant, values = None, {}
            for g in matrix_fglm(basis, ring, lex):
                degrees = g.degrees()
                used = [i for i, d in enumerate(degrees) if d]
                if used == [last]:
                    eliminant = univariate.from_dict({(m[last],): c for m, c in g.terms()})
                elif set(used[1:]) <= {last} and degrees[used[0]] == 1:
                    i = used[0]  # g = k_i - g_i(z) (or t - g_t(z))
                    rest = {(m[last],): -c for m, c in g.terms() if not m[i]}
                    values[ring.symbols[i]] = univariate.from_dict(rest)
            if eliminant is not None and all(x in values for x in xs):
                return eliminant, {x: values[x] for x in xs}
        return None

    def rational_points(self) -> tuple[dict[str, sympy.Expr], ...]:
        """The points of the generic fibre that are rational functions of the true values,
        written with the unknowns' names, the true values first."""
        shape = self._shape()
        if shape is None:
            return ()
        eliminant, values = shape
        z = eliminant.ring.symbols[0]
        numerator = sympy.fraction(sympy.together(eliminant.as_expr()))[0]
        found = []
        for factor, _ in sympy.factor_list(numerator)[1]:
            poly = sympy.Poly(factor, z)
            if poly.degree() != 1:
                continue
            root = self.domain.from_sympy(-poly.coeff_monomial(1) / poly.coeff_monomial(z))
            at_root = {x: self.domain.to_sympy(g.evaluate(0, root)) for x, g in values.items()}
            found.append({x.name: self.system.named(sympy.factor(v)) for x, v in at_root.items()})
        identity = self.system.identity
        return tuple(sorted(found, key=lambda point: (point != identity, str(point))))

    def points(self) -> list[dict[str, sympy.Expr]] | None:
        """Every point of a fibre through numeric true values: exact where rational, else
        to 15 digits; None when a point is double (special true values) or no linear form
        separated them."""
        shape = self._shape()
        if shape is None:
            return None
        eliminant, values = shape
        if eliminant.gcd(eliminant.diff(0)).degree() > 0:
            return None
        z = eliminant.ring.symbols[0]
        points = []
        for root in sympy.Poly(eliminant.as_expr(), z).all_roots():
            point = {}
            for x, g in values.items():
                value = sympy.expand(g.as_expr().subs(z, root))
                point[x.name] = value if value.is_Rational else sympy.N(value, 15)
            points.append(point)
        return points


def _normal(h: sympy.Expr, system: System) -> sympy.Expr | None:
    """The simplest of h, 1/h and their images a h + b (which generate the same field):
    numerator and denominator primitive with positive leading terms, and a polynomial's
    constant term dropped; None for a constant."""
    h = sympy.cancel(h)
    if not system.depends(h):
        return None
    forms = []
    for form in (h, 1 / h):
        p, q = sympy.fraction(sympy.cancel(form))
        if system.depends(q):
            forms.append(_primitive(p, system) / _primitive(q, system))
        else:
            poly = sympy.Poly(p, *system.xs)
            forms.append(_primitive((poly - poly.coeff_monomial(1)).as_expr(), system))
    return min((sympy.factor(form) for form in forms), key=_complexity)


def _primitive(p: sympy.Expr, system: System) -> sympy.Expr:
    """p over its content (in the numbers and kept symbols), with a positive leading term."""
    poly = sympy.Poly(p, *system.xs)
    if poly.domain.is_Field:
        poly = poly.clear_denoms(convert=True)[1]
    poly = poly.primitive()[1]
    return (-poly if poly.LC().could_extract_minus_sign() else poly).as_expr()


def _complexity(h: sympy.Expr) -> tuple[int, int]:
    return sympy.count_ops(h), len(str(h))


def _candidates(system: System) -> list[tuple[sympy.Expr, bool]]:
    """(h, whether it is a function of the ratios): the unknowns, their pairwise products,
    quotients and sums, and every coefficient ratio normalised; simplest first."""
    found: dict[sympy.Expr, bool] = {}
    for a, b in combinations(system.xs, 2):
        for h in (a * b, a / b, b / a, a + b):
            found[h] = False
    found |= dict.fromkeys(system.xs, False)
    for rows in system.groups:
        for i, j in combinations(range(len(rows)), 2):
            h = _normal(rows[i] / rows[j], system)
            if h is not None:
                found[h] = True
    return sorted(found.items(), key=lambda item: _complexity(item[0]))


def _independent(system: System, functions: list[sympy.Expr]) -> bool:
    """Whether the functions are algebraically independent: their Jacobian has full rank at
    a pseudo-random point (a lower bound of its generic rank: never wrongly true)."""
    rng = random.Random(SEED)
    point = {s: sympy.Integer(rng.randint(10**6, 10**9)) for s in (*system.xs, *system.symbols)}
    jacobian = sympy.Matrix(
        [[sympy.diff(h, x).xreplace(point) for x in system.xs] for h in functions]
    )
    return jacobian.rank() == len(functions)


def generators(fibre: Fibre, rank: int) -> tuple[sympy.Expr, ...]:
    """Simple generators of the field F of the fibre's functions (the ratios): the
    simplest candidates in F, first `rank` independent ones, then more until every ratio
    lies in the field they generate."""
    system = fibre.system
    candidates = _candidates(system)
    known: dict[sympy.Expr, bool] = {}

    def in_F(h: sympy.Expr, of_ratios: bool) -> bool:
        if h not in known:
            known[h] = of_ratios or fibre.contains(sympy.fraction(sympy.cancel(h)))
        return known[h]

    chosen: list[sympy.Expr] = []
    for h, of_ratios in candidates:
        if len(chosen) == rank:
            break
        if _independent(system, [*chosen, h]) and in_F(h, of_ratios):
            chosen.append(h)
    while True:
        field = fibre.of([sympy.fraction(sympy.cancel(h)) for h in chosen])
        if all(field.contains(ratio) for ratio in fibre.functions):
            return tuple(chosen)
        chosen.append(
            next(
                h
                for h, of_ratios in candidates
                if h not in chosen
                and in_F(h, of_ratios)
                and not field.contains(sympy.fraction(sympy.cancel(h)))
            )
        )
