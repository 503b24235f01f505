"""Polynomials as text (mtt.present.polynomials): the fast path through sympy's sparse
polynomials writes what sympy's general expressions would, on large and small ones."""

import itertools

import sympy

from mtt.derivation.transfer import LAPLACE as s
from mtt.present.polynomials import common_factors_out, factored, in_powers_of_s, sparse, text

x, y, z, w = sympy.symbols("x y z w")


def _many_terms() -> sympy.Expr:
    """6 * x**2 * y * (a sum of 35 terms in x, y, z, w with a positive leading term)."""
    body = sum(
        (i + 1) * x**a * y**b * z**c * w**d
        for i, (a, b, c, d) in enumerate(itertools.product(range(3), repeat=4))
        if a + b + c + d <= 3
    )
    return sympy.expand(6 * x**2 * y * body)


def test_common_factors_of_many_terms_are_those_of_factor_terms():
    polynomial = _many_terms()
    assert len(sympy.Add.make_args(polynomial)) > 24
    fast = factored(polynomial)
    assert fast == sympy.factor_terms(polynomial)
    assert str(fast) == str(sympy.factor_terms(polynomial))
    assert str(fast).startswith("6*x**2*y*(")


def test_a_negative_content_is_taken_out_with_its_sign():
    polynomial = sympy.expand(-3 * x * _many_terms())
    out = common_factors_out(sparse(polynomial))
    assert sympy.expand(out - polynomial) == 0
    assert str(out).startswith("-18*x**3*y*(")


def test_few_terms_are_fully_factored():
    assert factored(sympy.expand((x + y) * (x - 2 * z))) == (x + y) * (x - 2 * z)


def test_powers_of_s_with_large_and_small_coefficients():
    big = _many_terms()
    text = in_powers_of_s(sympy.expand(big * s**2 + (x + y) * s + 3))
    assert text == f"{sympy.factor_terms(big)}*s**2 + (x + y)*s + 3"
    assert in_powers_of_s(sympy.expand(-(s**2) + 2 * s - 1)) == "-s**2 + 2*s - 1"


def test_coefficients_outside_the_rationals_take_sympys_way():
    assert sparse(sympy.sqrt(2) * x * s + 1, s) is None
    assert in_powers_of_s(sympy.sqrt(2) * x * s + 1) == "sqrt(2)*x*s + 1"
    assert in_powers_of_s(sympy.Integer(0) * s) == "0"


def test_long_sums_are_written_as_sympy_writes_them():
    big = _many_terms()
    mixed = sympy.expand(big - 7 * x**3 * y * z**2 * w + 1 - 2 * z**5)
    for e in (
        big,
        mixed,
        -mixed,
        factored(big),
        factored(sympy.expand(-3 * x * big)),
        sympy.Mul(-1, mixed, evaluate=False),
        sympy.Mul(sympy.Rational(3, 2), x, mixed, evaluate=False),  # sympy's own way
        sympy.sqrt(2) * x + y,  # short: sympy's own way
    ):
        assert text(e) == str(e)
