"""Stage 5: `Equations` -> `TransferFunction`, G(s) = C (sE - A)^-1 B + D, exact and canonical.

Canonical form: numerator and denominator coprime as polynomials in s, the unknown
and every symbolic parameter; integer coefficients with overall content 1; the
denominator's coefficient of its highest power of s has a positive leading term.
The linear solve is fraction-free over the polynomial ring (sympy's DomainMatrix),
which keeps large models fast.
"""

from __future__ import annotations

from dataclasses import dataclass
from math import gcd

import sympy
from sympy.polys.domains import ZZ
from sympy.polys.rings import PolyElement

from mtt.derivation.equations import Equations
from mtt.language.diagnostics import ModelError, error

LAPLACE = sympy.Symbol("s")


@dataclass(frozen=True)
class TransferFunction:
    equations: Equations
    gens: tuple[sympy.Expr, ...]  # s, then the generators of the coefficient field
    num: PolyElement  # over ZZ, in `gens`
    den: PolyElement

    @property
    def numerator(self) -> sympy.Expr:
        return self.num.as_expr()

    @property
    def denominator(self) -> sympy.Expr:
        return self.den.as_expr()

    def degree(self, which: str) -> int:
        """The degree in s of 'num' or 'den'."""
        poly = self.num if which == "num" else self.den
        return max((m[0] for m in poly.monoms()), default=0)


def _field(equations: Equations):
    """s adjoined to the coefficient field of the equations, as fractions over ZZ.

    Over ZZ the fraction-free solve below runs several times faster than over QQ.
    """
    gens = (LAPLACE, *getattr(equations.domain, "symbols", ()))
    return ZZ.frac_field(*gens), gens


def _singular(equations: Equations, why: str) -> ModelError:
    return ModelError(
        equations.causal.bondgraph.source,
        [error("singular_model", f"the equations have no unique solution{why}")],
    )


def transfer_function(equations: Equations) -> TransferFunction:
    """G(s) = C (sE - A)^-1 B + D; raise `ModelError` (singular_model) if it does not exist.

    G = det([[sE - A, B], [-C, D]]) / det(sE - A), both determinants exact by evaluation
    and interpolation (`determinants`); when that would need too many points (many kept
    symbols), by a fraction-free solve over the polynomials instead.
    """
    from mtt.derivation.determinants import bordered_determinants  # numpy: not for `check`

    F, gens = _field(equations)
    lift = lambda M: M.to_sparse().convert_to(F)  # noqa: E731
    D = lift(equations.D)[0, 0].element
    G = D
    size = len(equations.states)
    if size:
        pencil = lift(equations.E) * F.from_sympy(LAPLACE) - lift(equations.A)
        bordered = pencil.hstack(lift(equations.B)).vstack(
            (-lift(equations.C)).hstack(lift(equations.D))
        )
        denominators, cleared = bordered.clear_denoms_rowwise(convert=True)
        ring = cleared.domain
        entries = cleared.to_dok()
        determinants = bordered_determinants(entries, size + 1, ring.ring)
        if determinants is None:
            G = _solve(equations, F, pencil, lift(equations.B), lift(equations.C)) + D
        else:
            leading, full = determinants
            if not leading:
                raise _singular(equations, ": det(sE - A) is identically zero")
            last = F.convert(denominators.to_dok()[size, size])  # the last row's multiplier
            G = F.convert_from(full, ring) / (F.convert_from(leading, ring) * last)
    if any(not isinstance(g, sympy.Symbol) for g in gens):
        G = _evaluate_constants(equations, F, G)
    return _canonical(equations, gens, G)


def _solve(equations: Equations, F, pencil, B, C):
    """C (sE - A)^-1 B by a fraction-free solve over the polynomials in s and the symbols."""
    size = len(equations.states)
    _, cleared = pencil.hstack(B).clear_denoms_rowwise(convert=True)
    M, B = cleared[:, :size], cleared[:, size:]
    if M.rank() < size:
        raise _singular(equations, ": det(sE - A) is identically zero")
    xnum, den = M.solve_den(B)
    x = xnum.convert_to(F)
    CX = sum((C[0, j].element * x[j, 0].element for j in range(size)), F.zero)
    return CX / F.convert_from(den, M.domain)


def _evaluate_constants(equations: Equations, F, G):
    """Apply the relations between irrational constants (sqrt(2)**2 = 2, ...).

    A known parameter like sqrt(2) is a generator of the coefficient field, which knows
    nothing of its algebraic relations: terms that vanish by them would survive and leave
    G non-canonical (wrong degree, sign and content). Written out, sympy evaluates them.
    """
    num, den = (sympy.expand(p.as_expr()) for p in (G.numer, G.denom))
    if den == 0:
        raise _singular(equations, "")
    return F.from_sympy(num) / F.from_sympy(den)


def _canonical(equations: Equations, gens, G) -> TransferFunction:
    """Coprime, integer, content 1, positive leading term of the highest power of s."""
    num, den = G.numer, G.denom  # coprime, over ZZ
    content = gcd(*(int(c) for c in (*num.coeffs(), *den.coeffs()) if c))
    num, den = num.quo_ground(content), den.quo_ground(content)
    if den.LC < 0:
        num, den = -num, -den
    return TransferFunction(equations, gens, num, den)
