"""The work budget (too_large before a result outgrows it) and the sparse fraction-free
elimination that derives transfer functions in many symbols (issue 23 items 1 and 2)."""

from __future__ import annotations

import json
import random

import pytest
import sympy
from sympy.polys.domains import QQ, ZZ
from sympy.polys.matrices import DomainMatrix
from sympy.polys.rings import ring

import mtt
from mtt.cli.main import main
from mtt.derivation.budget import Budget, Meter, TooLarge
from mtt.derivation.elimination import bordered_ratio
from mtt.derivation.sparse import NotDivisible, as_expr, exact_quotient, product


def symbolic_ladder(sections: int) -> str:
    """An RC ladder with no parameter values: a voltage source, `sections` series R / shunt
    C sections, loaded by the unknown resistance k."""
    lines = ["model ladder", "unknown k"]
    lines += [f"param {kind}{i}" for i in range(1, sections + 1) for kind in "rc"]
    lines.append("Se:v -> 1:s1")
    for i in range(1, sections + 1):
        lines += [f"1:s{i} -> R:r{i}(r{i})", f"1:s{i} -> 0:n{i}", f"0:n{i} -> C:c{i}(c{i})"]
        if i < sections:
            lines.append(f"0:n{i} -> 1:s{i + 1}")
    lines += [f"0:n{sections} -> R:load(k)", f"0:n{sections} -> De:out"]
    return "\n".join(lines) + "\n"


def abcd(sections: int) -> sympy.Expr:
    """The same ladder's transfer function the textbook way: the product of the sections'
    ABCD matrices, then V_out / V_in = k / (A k + B) for the load k."""
    s, k = sympy.symbols("s k")
    chain = sympy.eye(2)
    for i in range(1, sections + 1):
        r, c = sympy.symbols(f"r{i} c{i}")
        chain = chain * sympy.Matrix([[1, r], [0, 1]]) * sympy.Matrix([[1, 0], [c * s, 1]])
    return k / sympy.expand(chain[0, 0] * k + chain[0, 1])


@pytest.mark.parametrize("sections", [1, 3, 6])
def test_the_symbolic_ladder_is_the_abcd_product(sections):
    tf = mtt.load(symbolic_ladder(sections)).transfer_function
    num, den = sympy.fraction(abcd(sections))
    assert sympy.expand(tf.num * den - tf.den * num) == 0
    assert len(sympy.Add.make_args(tf.den)) == sympy.fibonacci(2 * sections + 2)


def _random_matrix(rng: random.Random, size: int, density: float):
    R, *gens = ring("x,y,z", ZZ)
    entries = {}
    for i in range(size):
        for j in range(size):
            if rng.random() < density:
                p = R(rng.randint(-3, 3)) + rng.choice(gens) * rng.randint(-2, 2)
                if rng.random() < 0.3:
                    p += rng.choice(gens) * rng.choice(gens)
                if p:
                    entries[i, j] = p
    return R, entries


@pytest.mark.parametrize("seed", range(4))
def test_elimination_gives_the_ratio_of_the_determinants(seed):
    """det(A) / det(leading block) for random sparse matrices, some with many separate
    components, some structurally singular, against sympy's dense determinants."""
    rng = random.Random(seed)
    for _ in range(25):
        size = rng.randint(2, 7)
        R, entries = _random_matrix(rng, size, rng.choice([0.2, 0.35, 0.6]))
        dense = DomainMatrix(
            [[entries.get((i, j), R.zero) for j in range(size)] for i in range(size)],
            (size, size),
            R.to_domain(),
        )
        leading, whole = dense[: size - 1, : size - 1].det(), dense.det()
        ratio = bordered_ratio(entries, size, R, Meter(Budget(), "test"))
        if ratio is None:
            assert leading == 0
            continue
        assert leading in (
            _product(R, (*ratio.den, *ratio.other)),
            -_product(R, (*ratio.den, *ratio.other)),
        )
        assert whole * _product(R, ratio.den) == ratio.num * leading


def _product(R, factors):
    result = R.one
    for factor in factors:
        result *= factor
    return result


def test_a_ladder_beyond_the_budget_is_too_large_at_its_first_symbol():
    with pytest.raises(mtt.MttError) as caught:
        _ = mtt.load(symbolic_ladder(12)).transfer_function
    error = caught.value
    assert error.kind == "too_large" and (error.line, error.column) == (3, 7)  # param r1
    message = str(error)
    assert "transfer function" in message and "30000" in message and "--max-terms" in message
    assert "24 parameters are symbolic (r1, c1, r2" in message


def test_max_terms_sets_the_budget(capsys, tmp_path):
    path = tmp_path / "ladder.bg"
    path.write_text(symbolic_ladder(4), encoding="utf-8")  # its denominator has 55 terms
    assert mtt.load(path, max_terms=100).transfer_function.den is not None
    with pytest.raises(mtt.MttError, match="more than the 54 allowed"):
        _ = mtt.load(path, max_terms=54).transfer_function
    assert main(["tf", str(path), "--json", "--max-terms", "54"]) == 2
    record = json.loads(capsys.readouterr().out)
    assert record["ok"] is False and record["errors"][0]["kind"] == "too_large"
    assert main(["tf", str(path), "--json", "--max-terms", "100"]) == 0
    with pytest.raises(mtt.MttError, match="positive integer"):
        mtt.load(path, max_terms=0)


def test_the_meter_stops_before_the_work_exceeds_the_budget():
    meter = Meter(Budget(max_terms=19), "test stage")
    R, x, y = ring("x,y", ZZ)
    a = sum((x**i for i in range(10)), R.zero)
    assert len(product(a, a, meter)) == 19  # 100 products of terms
    with pytest.raises(TooLarge) as caught:
        product(a, a + y, meter)
    stop = caught.value
    assert (stop.stage, stop.measure, stop.size, stop.limit) == ("test stage", "terms", 29, 19)
    meter = Meter(Budget(max_terms=1000), "test stage")
    with pytest.raises(TooLarge) as caught:
        for _ in range(10_000):
            product(a, a, meter)
    assert caught.value.measure == "work" and meter.work <= caught.value.limit + 100


def _random_poly(R, rng: random.Random, terms: int, degree: int):
    p = R.zero
    for _ in range(terms):
        monomial = R(rng.randint(-9, 9))
        for x in R.gens:
            monomial *= x ** rng.randint(0, degree)
        p += monomial
    return p


def test_sparse_products_and_exact_quotients_are_sympys():
    """The heap division and the packed product against sympy's, on random polynomials
    (one-term divisors, constants, exponents past a byte's range included); a divisor that
    does not divide is refused."""
    R, *_ = ring("s,a,b,c", ZZ)
    rng, meter = random.Random(7), Meter(Budget(max_terms=10**6), "test")
    for degree in (1, 3, 70):
        for _ in range(40):
            a = _random_poly(R, rng, rng.randint(1, 12), degree)
            b = _random_poly(R, rng, rng.randint(1, 12), degree)
            assert product(a, b, meter) == a * b
            if b:
                assert exact_quotient(a * b, b, meter) == a
            if len(b) > 1 and (a * b + R.gens[0] ** 5).rem(b):
                with pytest.raises(NotDivisible):
                    exact_quotient(a * b + R.gens[0] ** 5, b, meter)
    s, a, *_ = R.gens
    with pytest.raises(NotDivisible):  # the quotient would outgrow s^2's degree in a
        exact_quotient(s**2, s + a**60, meter)


def test_a_product_stops_when_it_outgrows_the_budget_and_a_division_is_charged():
    R, x, y = ring("x,y", ZZ)
    a = sum((x**i for i in range(30)), R.zero)
    b = sum((y**i for i in range(30)), R.zero)  # a * b: 900 terms
    with pytest.raises(TooLarge) as caught:
        product(a, b, Meter(Budget(max_terms=50), "test"))
    assert caught.value.measure == "terms" and caught.value.size <= 4 * 50 + 30
    meter = Meter(Budget(max_terms=10**4), "test")
    exact_quotient(product(a, b, meter), b, meter)
    assert meter.work == 900 + 4 * 30 * 30  # the quotient's 30 terms, each times b's 30


def wheatstone() -> str:
    """A bridge of symbolic resistances (an algebraic loop) fed through the unknown k, a
    capacitance across its output."""
    lines = ["model wheatstone", "unknown k", *(f"param r{i}" for i in range(1, 6)), "param cap"]
    lines += ["Se:v -> 1:in", "1:in -> R:rin(k)", "1:in -> 0:a"]
    for name, a, b in (("r1", "a", "b"), ("r2", "a", "c"), ("r5", "b", "c")):
        lines += [f"0:{a} -> 1:j{name}", f"1:j{name} -> 0:{b}", f"1:j{name} -> R:{name}({name})"]
    lines += ["0:b -> R:r3(r3)", "0:c -> R:r4(r4)", "0:c -> C:cap(cap)", "0:c -> De:out"]
    return "\n".join(lines) + "\n"


def test_a_loop_too_large_to_tear_is_left_to_the_elimination_with_the_same_result():
    """The bridge's loop torn within the budget, or (a budget too small for the tearing)
    kept as algebraic rows of the descriptor form: the same transfer function, that of
    nodal analysis."""
    torn, kept = mtt.load(wheatstone()), mtt.load(wheatstone(), max_terms=40)
    assert len(kept.state_space.states) > len(torn.state_space.states) == 1
    s, k, cap = sympy.symbols("s k cap")
    r = sympy.symbols("r1:6")
    g = [1 / x for x in r]  # nodal analysis: conductances, the input 1 through k
    nodes = sympy.Matrix(
        [
            [1 / k + g[0] + g[1], -g[0], -g[1]],
            [-g[0], g[0] + g[2] + g[4], -g[4]],
            [-g[1], -g[4], g[1] + g[3] + g[4] + cap * s],
        ]
    )
    output = nodes.copy()
    output[:, 2] = sympy.Matrix([1 / k, 0, 0])  # Cramer's rule for the output node
    num, den = sympy.fraction(sympy.together(output.det() / nodes.det()))
    for model in (torn, kept):
        tf = model.transfer_function
        assert sympy.expand(tf.num * den - tf.den * num) == 0


def test_expressions_are_sympys_to_the_last_argument():
    """The fast conversion gives sympy's own expression, argument for argument (signs,
    constants, lone factors, rational coefficients, high powers)."""
    rng = random.Random(11)
    for domain in (ZZ, QQ):
        R, x, y, z = ring("x,y,z", domain)
        for _ in range(200):
            p = R.zero
            for _ in range(rng.randint(0, 6)):
                c = domain(rng.randint(-3, 3))
                if domain == QQ:
                    c /= QQ(rng.choice([1, 1, 2, 3]))
                p += c * x ** rng.randint(0, 3) * y ** rng.randint(0, 2) * z ** rng.randint(0, 12)
            assert sympy.srepr(as_expr(p)) == sympy.srepr(p.as_expr())
