"""Several inputs and outputs: exact transfer matrices of hand-derived systems, checked
three ways.

Every expected G(s) = B(s) / A(s) below is derived by hand in its comment (Kirchhoff's and
Newton's laws, the absorber's stage balances) and written over the common characteristic
polynomial, canonical: integer coefficients with content 1, A's leading term positive.
Independently, each entry must equal tests/oracle.py's transfer function of that input to
that output (no causality, no state space), and C (sE - A)^-1 B + D of mtt's own state
space, inverted here by sympy.
"""

from __future__ import annotations

import functools
from pathlib import Path

import pytest
import sympy
from oracle import oracle_tf

from mtt.derivation.parameters import ParameterChoice
from mtt.derivation.pipeline import equations_for, load, transfer_for
from mtt.derivation.transfer_matrix import TransferMatrix, transfer_matrix
from mtt.language.diagnostics import ModelError

ROOT = Path(__file__).resolve().parent.parent
MATRICES = Path(__file__).resolve().parent / "data" / "matrices"
s = sympy.Symbol("s")
inductance = sympy.Symbol("l")
c, k, n, r, jl, tau, flow, ra, km, j, b = sympy.symbols("c k n r jl tau l ra km j b")


def M(*rows):
    return sympy.Matrix(rows)


# model: (file, inputs, outputs, keep, A, B)
HAND = {
    # DC motor, la = 1/10, ra = 1, km = 1, jm = 1, b = 1/10, load inertia jl:
    # la i' = v - ra i - km w, (jm + jl) w' = km i - b w + tl; the determinant of
    # [[la s + ra, km], [-km, (jm + jl) s + b]] times 100 is A; speed = km v + (la s + ra) tl,
    # current = ((jm + jl) s + b) v - km tl, over it.
    "dc_motor_load": (
        ROOT / "models" / "dc_motor_load.bg",
        "Se:v,Se:tl",
        "Df:speed,Df:current",
        (),
        10 * (jl + 1) * s**2 + (100 * jl + 101) * s + 110,
        M([100, 10 * s + 100], [100 * (jl + 1) * s + 10, -100]),
    ),
    # The absorber's stages, scaled by aV = l/k (H = tau l/k): with a = tau s + k + 1,
    # [[a, -1, 0], [-k, a, -1], [0, -k, a]] x = (k/l) [feed, 0, gas]; det = a (a^2 - 2k),
    # x3 = (k/l) (k^2 feed + (a^2 - k) gas) / det.
    "absorber_gas": (
        ROOT / "models" / "absorber_gas.bg",
        "Sf:feed,Sf:gas_feed",
        "De:x_l",
        ("tau", "l"),
        flow * (tau * s + k + 1) * ((tau * s + k + 1) ** 2 - 2 * k),
        M([k**3, k * ((tau * s + k + 1) ** 2 - k)]),
    ),
    # DC motor, la = 1/10, every other parameter unknown: D = (la s + ra)(j s + b) + km^2,
    # speed = km v / D, current = (j s + b) v / D; times 10.
    "dc_motor_sensors": (
        ROOT / "models" / "dc_motor_sensors.bg",
        "Se:v",
        "Df:speed,Df:current",
        (),
        j * s**2 + (b + 10 * j * ra) * s + 10 * b * ra + 10 * km**2,
        M([10 * km], [10 * j * s + 10 * b]),
    ),
    # c1 p1' = q1 - (p1 - p2)/r1, c2 p2' = q2 + (p1 - p2)/r1 - p2/r, c1 = r1 = 1, c2 = 2:
    # [[s + 1, -1], [-1, 2s + 1 + 1/r]] p = q; its inverse's adjugate over the
    # determinant, times r.
    "two_tanks": (
        MATRICES / "two_tanks.bg",
        "Sf:q1,Sf:q2",
        "De:h1,De:h2",
        (),
        2 * r * s**2 + (3 * r + 1) * s + 1,
        M([2 * r * s + r + 1, r], [r, r * s + r]),
    ),
    # Series RLC, r = 2, l = 1/2: i = c s v / (l c s^2 + r c s + 1), vc = i / (c s); times 2.
    "rlc_two_outputs": (
        MATRICES / "rlc_two_outputs.bg",
        "Se:v",
        "De:vc,Df:i",
        (),
        c * s**2 + 4 * c * s + 2,
        M([2], [2 * c * s]),
    ),
    # Two RC branches, i1 = s v / (s + 1) (r1 = c1 = 1), i2 = c s v / (2 c s + 1) (r2 = 2);
    # A = (s + 1)(2 c s + 1), each numerator holding the other branch's factor.
    "parallel_rc": (
        MATRICES / "parallel_rc.bg",
        "Se:v",
        "Df:i1,Df:i2",
        (),
        (s + 1) * (2 * c * s + 1),
        M([s * (2 * c * s + 1)], [c * s * (s + 1)]),
    ),
    # Node voltage e = r (i1 + i2), i1 = v1 - e (r1 = 1), i2 = (v2 - e)/2 (r2 = 2):
    # e = r (2 v1 + v2) / (3r + 2); static, A = 3r + 2.
    "resistors": (
        MATRICES / "resistors.bg",
        "Se:v1,Se:v2",
        "Df:i1,Df:i2",
        (),
        3 * r + 2,
        M([r + 2, -r], [-r, r + 1]),
    ),
    # TF: e1 = n e2, w2 = n w1. t1 = j1 s w1 + n e2, e2 = b w2 - t2 (j1 = 1, b = 1/2):
    # w1 = (t1 + n t2) / (s + n^2/2), w2 = n w1; times 2.
    "gear": (
        MATRICES / "gear.bg",
        "Se:t1,Se:t2",
        "Df:s1,Df:s2",
        (),
        2 * s + n**2,
        M([2, 2 * n], [2 * n, 2 * n**2]),
    ),
    # m1 = m2 = b = 1, spring k: s^2 v1 + k (v1 - v2) = s f1, s^2 v2 + s v2 + k (v2 - v1)
    # = s f2; [[s^2 + k, -k], [-k, s^2 + s + k]] has determinant s (s^3 + s^2 + 2ks + k).
    "two_masses": (
        MATRICES / "two_masses.bg",
        "Se:f1,Se:f2",
        "Df:y1,Df:y2",
        (),
        s**3 + s**2 + 2 * k * s + k,
        M([s**2 + s + k, k], [k, s**2 + k]),
    ),
    # c s e = ia + i, ia = (v - e)/r (r = 2): e = (v + r i)/(r c s + 1),
    # ia = (c s v - i)/(r c s + 1).
    "rc_mixed": (
        MATRICES / "rc_mixed.bg",
        "Se:v,Sf:i",
        "Df:ia,De:vn",
        (),
        2 * c * s + 1,
        M([c * s, -1], [1, 2]),
    ),
    # Two separate RL loops: i1 = v1/(s + 1), i2 = v2/(l s + 2), A their product.
    "decoupled": (
        MATRICES / "decoupled.bg",
        "Se:v1,Se:v2",
        "Df:i1,Df:i2",
        (),
        (s + 1) * (inductance * s + 2),
        M([inductance * s + 2, 0], [0, s + 1]),
    ),
}


def choice(inputs: str, outputs: str, keep=()) -> ParameterChoice:
    return ParameterChoice(input=inputs, output=outputs, keep=frozenset(keep))


@functools.cache
def derived(name: str) -> TransferMatrix:
    path, inputs, outputs, keep, _, _ = HAND[name]
    chosen = choice(inputs, outputs, keep)
    return transfer_matrix(equations_for(load(path, chosen.selection), chosen))


@pytest.mark.parametrize("name", HAND)
def test_the_hand_derived_transfer_matrix_exactly(name):
    *_, A, B = HAND[name]
    matrix = derived(name)
    assert sympy.expand(matrix.A - A) == 0, matrix.A
    assert (matrix.B - B).applyfunc(sympy.expand) == sympy.zeros(*B.shape), matrix.B


@pytest.mark.parametrize("name", HAND)
def test_each_entry_is_the_oracles_transfer_function(name):
    path, inputs, outputs, keep, _, _ = HAND[name]
    matrix = derived(name)
    for i, output in enumerate(outputs.split(",")):
        for j, input_ in enumerate(inputs.split(",")):
            expected = oracle_tf(path, keep=keep, input=input_, output=output)
            assert sympy.cancel(matrix.B[i, j] / matrix.A - expected) == 0, (output, input_)
            entry = matrix.entries[i][j]
            assert sympy.cancel(entry.numerator / entry.denominator - expected) == 0


@pytest.mark.parametrize("name", HAND)
def test_the_state_space_gives_the_same_matrix(name):
    """C (sE - A)^-1 B + D of the descriptor form, by sympy, is B/A: B has a column per
    input, C a row per output."""
    matrix = derived(name)
    ss = matrix.equations.matrices()
    rows, columns = matrix.shape
    assert ss["B"].shape[1] == ss["D"].shape[1] == columns
    assert ss["C"].shape[0] == ss["D"].shape[0] == rows
    pencil = s * ss["E"] - ss["A"]
    G = ss["C"] * pencil.inv() * ss["B"] + ss["D"] if pencil.shape[0] else ss["D"]
    assert (G - matrix.B / matrix.A).applyfunc(sympy.cancel) == sympy.zeros(rows, columns)


@pytest.mark.parametrize("name", HAND)
def test_the_common_form_is_canonical(name):
    """Integer coefficients with content 1, A's leading term positive, and no factor free
    of s that A shares with every B (A itself keeps every mode)."""
    matrix = derived(name)
    gens = matrix.characteristic.ring.symbols
    polys = [sympy.Poly(p, *gens) for p in (matrix.A, *matrix.B) if p != 0]
    assert all(p.domain == sympy.ZZ for p in polys)
    assert sympy.igcd(*(int(x) for p in polys for x in p.coeffs())) == 1
    assert sympy.Poly(matrix.A, *gens).LC() > 0
    shared = functools.reduce(sympy.gcd, [p.as_expr() for p in polys])
    assert sympy.Poly(shared, s).content() in (1, -1)
    degree = sympy.degree(matrix.A, s)
    assert matrix.n == degree and len(matrix.equations.states) >= degree


def test_entries_that_reduce_say_what_cancels():
    matrix = derived("parallel_rc")
    assert sympy.expand(matrix.cancelled(0, 0) - (2 * c * s + 1)) == 0
    assert sympy.expand(matrix.cancelled(1, 0) - (s + 1)) == 0
    first, second = (row[0] for row in matrix.entries)
    assert (first.numerator, first.denominator) == (s, s + 1)
    assert (second.numerator, sympy.expand(second.denominator)) == (c * s, 2 * c * s + 1)
    assert derived("two_masses").cancelled(0, 1) is None


def test_a_zero_entry_has_no_theta_and_the_others_theirs():
    matrix = derived("decoupled")
    assert matrix.B[0, 1] == 0 and not matrix.entries[0][1].num
    assert set(matrix.thetas) == {(0, 0), (1, 1)}
    theta = matrix.thetas[1, 1]  # 1 / (l s + 2): rows a0, a1, -b0; columns 1, l
    assert (theta.input, theta.output) == ("Se:v2", "Df:i2")
    assert theta.matrix == sympy.Matrix([[2, 0], [0, 1], [-1, 0]])


@pytest.mark.parametrize(
    "model", ["rlc", "dc_drive", "absorber", "dc_motor", "rlc3", "dc_motor_load"]
)
def test_one_input_and_one_output_is_the_transfer_function(model):
    """A 1x1 matrix over the characteristic polynomial is the canonical transfer function
    when no mode is hidden (none is, in the shipped models)."""
    path = ROOT / "models" / f"{model}.bg"
    tf = transfer_for(path)
    graph = load(path)
    matrix = transfer_matrix(equations_for(graph))
    assert matrix.shape == (1, 1) and matrix.inputs == (graph.component(graph.input).label,)
    assert sympy.expand(matrix.A - tf.denominator) == 0
    assert sympy.expand(matrix.B[0, 0] - tf.numerator) == 0


def test_several_inputs_are_checked_like_one():
    path = MATRICES / "decoupled.bg"
    with pytest.raises(ModelError) as caught:
        load(path, choice("Se:v1,Se:v1", "Df:i1").selection)
    assert caught.value.kind == "duplicate_name" and "Se:v1 is chosen twice" in str(caught.value)
    with pytest.raises(ModelError) as caught:
        load(path, choice("Se:v1,Df:i2", "Df:i1").selection)
    assert "Df:i2 (chosen with --input) is not a source" in str(caught.value)


def test_an_input_that_reaches_no_output_is_an_error():
    chosen = choice("Se:v1,Se:v2", "Df:i1")
    with pytest.raises(ModelError) as caught:
        equations_for(load(MATRICES / "decoupled.bg", chosen.selection), chosen)
    (problem,) = caught.value.errors
    assert problem.kind == "unreachable_output"
    assert "the input Se:v2 reaches none of the outputs (Df:i1)" in problem.message
    assert "its column of the transfer matrix is zero" in problem.message
