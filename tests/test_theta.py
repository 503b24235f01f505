"""Theta, the paper's matrix: eqs. (24)-(27) of method.md exactly, and its general rules."""

from __future__ import annotations

from pathlib import Path
from types import MappingProxyType

import pytest
import sympy

from mtt.derivation.nonlinear import nonlinear_parts
from mtt.derivation.parameters import ParameterChoice
from mtt.derivation.pipeline import load, theta_for, transfer_for
from mtt.language.diagnostics import ModelError
from mtt.present.report import derived_json

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "models"
SYSTEMS = Path(__file__).resolve().parent / "data" / "systems"

s, k, tau, l_ = sympy.symbols("s k tau l")


def expanded_equal(a, b) -> bool:
    return sympy.expand(a - b) == 0


# --- 5.1 DC drive ------------------------------------------------------------------------


def test_dc_drive_transfer_function_eq_24():
    # G(s) = 10 (k s^2 + 1) / ((s^3 + 10 s^2 + 11 s + 10) k s + s^2 + 10 s + 10)
    tf = transfer_for(MODELS / "dc_drive.bg")
    assert expanded_equal(tf.numerator, 10 * (k * s**2 + 1))
    assert expanded_equal(
        tf.denominator, (s**3 + 10 * s**2 + 11 * s + 10) * k * s + s**2 + 10 * s + 10
    )


def test_dc_drive_theta_eq_25():
    theta = theta_for(MODELS / "dc_drive.bg")
    assert (theta.n, theta.m, theta.N) == (4, 2, 1)
    assert theta.matrix == sympy.Matrix(
        [[10, 0], [10, 10], [1, 11], [0, 10], [0, 1], [-10, 0], [0, 0], [0, -10]]
    )
    assert theta.row_labels == ("a0", "a1", "a2", "a3", "a4", "-b0", "-b1", "-b2")
    assert theta.unknown == "k" and theta.symbols == ()
    assert theta.input == "Se:v" and theta.output == "Df:vm"
    assert theta.true_value == 10


# --- 5.2 absorber -------------------------------------------------------------------------

ABSORBER_DEN = l_ * ((k + s * tau + 1) * (3 * s * tau + 1) * k + (s * tau + 1) ** 3 + k**3)


# the pseudo bond graph in one file, and assembled from one stage file used three times
ABSORBERS = pytest.mark.parametrize("model", ["absorber.bg", "absorber_stages.bg"])


@ABSORBERS
def test_absorber_transfer_function_eq_26(model):
    # G(s) = k^3 / (l [(k + s tau + 1)(3 s tau + 1) k + (s tau + 1)^3 + k^3])
    tf = transfer_for(MODELS / model, ParameterChoice(keep=frozenset({"tau", "l"})))
    assert expanded_equal(tf.numerator, k**3)
    assert expanded_equal(tf.denominator, ABSORBER_DEN)


@ABSORBERS
def test_absorber_transfer_function_with_defaults(model):
    # tau = 2, l = 1/2: k^3 / ((1/2) [...]) = 2 k^3 / [...]
    tf = transfer_for(MODELS / model)
    assert expanded_equal(tf.numerator, 2 * k**3)
    assert expanded_equal(tf.denominator, 2 * ABSORBER_DEN.subs({tau: 2, l_: sympy.Rational(1, 2)}))


@ABSORBERS
def test_absorber_theta_eq_27(model):
    theta = theta_for(MODELS / model, ParameterChoice(keep=frozenset({"tau", "l"})))
    assert (theta.n, theta.m, theta.N) == (3, 0, 3)
    expected = sympy.Matrix(
        [
            [l_, l_, l_, l_],
            [3 * l_ * tau, 4 * l_ * tau, 3 * l_ * tau, 0],
            [3 * l_ * tau**2, 3 * l_ * tau**2, 0, 0],
            [l_ * tau**3, 0, 0, 0],
            [0, 0, 0, -1],
        ]
    )
    assert (theta.matrix - expected).expand() == sympy.zeros(5, 4)
    assert theta.symbols == ("tau", "l")
    assert theta.defaults == {"tau": 2, "l": sympy.Rational(1, 2)}


@ABSORBERS
def test_absorber_theta_with_defaults(model):
    # eq. (27) at tau = 2, l = 1/2, times 2 (the canonical form has content 1)
    theta = theta_for(MODELS / model)
    assert theta.matrix == sympy.Matrix(
        [[1, 1, 1, 1], [6, 8, 6, 0], [12, 12, 0, 0], [8, 0, 0, 0], [0, 0, 0, -2]]
    )
    assert theta.true_value == sympy.Rational(72, 100)
    assert {n: v for n, v in theta.assumed.items() if "." not in n} == {
        "tau": 2,
        "l": sympy.Rational(1, 2),
    }


# --- general rules -----------------------------------------------------------------------


def reconstruct(theta):
    """theta(k) = Theta K(k); its rows are a0..an, -b0..-bm."""
    column = theta.matrix * theta.K({name: sympy.Symbol(name) for name in theta.unknowns})
    den = sum(column[i] * s**i for i in range(theta.n + 1))
    num = -sum(column[theta.n + 1 + i] * s**i for i in range(theta.m + 1))
    return num, den


@pytest.mark.parametrize(
    "path",
    [p for p in sorted(MODELS.glob("*.bg")) if not nonlinear_parts(load(p))]
    + [SYSTEMS / "two_tanks.bg", SYSTEMS / "dc_motor.bg"],
    ids=lambda p: p.stem,
)
@pytest.mark.parametrize("symbolic", [False, True])
def test_theta_reproduces_the_transfer_function(path, symbolic):
    theta = theta_for(path, ParameterChoice(symbolic=symbolic))
    num, den = reconstruct(theta)
    assert expanded_equal(num, theta.num) and expanded_equal(den, theta.den)
    rows, cols = theta.matrix.shape
    assert (rows, cols) == (theta.n + theta.m + 2, len(theta.monomials))
    if len(theta.unknowns) == 1:  # the powers 1, k, ..., k^N
        assert theta.monomials == tuple((j,) for j in range(theta.N + 1))
        assert any(entry != 0 for entry in theta.matrix.col(theta.N))  # N is the true degree
    else:  # the monomials that occur, by degree, then higher powers of earlier unknowns first
        assert all(any(entry != 0 for entry in theta.matrix.col(j)) for j in range(cols))
        order = [(sum(e), [-x for x in e]) for e in theta.monomials]
        assert order == sorted(order) and len(set(theta.monomials)) == cols


def test_theta_of_spec_rlc_symbolic():
    # c s / (c l s^2 + c r s + 1): a0 = 1, a1 = r c, a2 = l c, -b0 = 0, -b1 = -c
    r, ll = sympy.symbols("r l")
    theta = theta_for(MODELS / "rlc.bg", ParameterChoice(symbolic=True))
    assert theta.matrix == sympy.Matrix([[1, 0], [0, r], [0, ll], [0, 0], [0, -1]])
    assert theta.symbols == ("r", "l")


def test_theta_with_another_unknown():
    # rlc with unknown r: 2 s / (s^2 + 2 r s + 20) (c = 1/10, l = 1/2)
    theta = theta_for(MODELS / "rlc.bg", ParameterChoice(unknowns=("r",)))
    assert theta.unknown == "r"
    assert theta.matrix == sympy.Matrix([[20, 0], [0, 2], [1, 0], [0, 0], [-2, 0]])


def test_theta_of_an_improper_system():
    # G = c s: n = 0, m = 1; rows a0, -b0, -b1
    theta = theta_for(SYSTEMS / "source_on_capacitor.bg")
    assert (theta.n, theta.m, theta.N) == (0, 1, 1)
    assert theta.matrix == sympy.Matrix([[1, 0], [0, 0], [0, -1]])


def test_no_unknown(tmp_path):
    path = tmp_path / "known.bg"
    path.write_text((MODELS / "rlc.bg").read_text().replace("unknown c", "param c"))
    with pytest.raises(ModelError) as caught:
        theta_for(path)
    assert caught.value.kinds() == ["no_unknown"]
    assert transfer_for(path).degree("den") == 2  # the transfer function still exists


def test_json_record_shape():
    theta = theta_for(MODELS / "dc_drive.bg")
    record = derived_json(theta, order=4)
    assert list(record) == [
        "ok", "model", "input", "output", "unknown", "unknowns", "monomials", "degrees", "symbols",
        "names", "num", "den", "n", "m", "N", "theta", "order",
    ]  # fmt: skip
    assert record["theta"][0] == ["10", "0"]
    assert record["num"] == "10*k*s**2 + 10"
    assert sympy.sympify(record["den"]) == sympy.expand(theta.den)


def test_theta_for_a_symbol_without_value(tmp_path):
    # rc_lowpass with r declared without a value: r stays symbolic, c unknown
    path = tmp_path / "rc.bg"
    path.write_text((SYSTEMS / "rc_lowpass.bg").read_text().replace("param r = 2", "param r"))
    theta = theta_for(path, ParameterChoice(overrides=MappingProxyType({})))
    r = sympy.Symbol("r")
    assert theta.symbols == ("r",) and theta.defaults == {"r": None}
    assert theta.matrix == sympy.Matrix([[1, 0], [0, r], [-1, 0]])


# --- several unknowns ----------------------------------------------------------------------

ra, jl, la, km, jm, b = sympy.symbols("ra jl la km jm b")


def test_two_unknowns_dc_motor_theta_by_hand():
    # Armature: v = (ra + la s) i + km w; shaft: km i = ((jm + jl) s + b) w, so
    # w/v = km / ((ra + la s)((jm + jl) s + b) + km^2), and the denominator is
    #   km^2 + b ra + (b la + jm ra + jl ra) s + (jm la + jl la) s^2.
    # Its coefficients are polynomials in ra and jl with the monomials 1, ra, jl, ra*jl.
    theta = theta_for(MODELS / "dc_motor.bg", ParameterChoice(symbolic=True))
    assert theta.unknowns == ("ra", "jl") and theta.unknown is None
    assert theta.monomials == ((0, 0), (1, 0), (0, 1), (1, 1))
    assert theta.column_labels == ("1", "ra", "jl", "ra*jl")
    assert (theta.n, theta.m, theta.N, theta.degrees) == (2, 0, 2, {"ra": 1, "jl": 1})
    assert theta.matrix == sympy.Matrix(
        [[km**2, b, 0, 0], [b * la, jm, 0, 1], [jm * la, 0, la, 0], [-km, 0, 0, 0]]
    )
    # with the file's values la = 1/10, km = 1, jm = 1, b = 1/10 (times 100, canonical)
    theta = theta_for(MODELS / "dc_motor.bg")
    assert theta.matrix == sympy.Matrix(
        [[100, 10, 0, 0], [1, 100, 0, 100], [10, 0, 10, 0], [-100, 0, 0, 0]]
    )
    assert theta.true_values == {"ra": 1, "jl": 10} and theta.true_value is None


def test_unknown_option_orders_the_unknowns_and_the_columns():
    theta = theta_for(MODELS / "dc_motor.bg", ParameterChoice(unknowns=("jl", "ra")))
    assert theta.unknowns == ("jl", "ra")
    assert theta.monomials == ((0, 0), (1, 0), (0, 1), (1, 1))
    assert theta.column_labels == ("1", "jl", "ra", "jl*ra")
    assert theta.matrix == sympy.Matrix(
        [[100, 0, 10, 0], [1, 0, 100, 100], [10, 10, 0, 0], [-100, 0, 0, 0]]
    )


def test_a_declared_unknown_not_chosen_keeps_its_value():
    theta = theta_for(MODELS / "dc_motor.bg", ParameterChoice(unknowns=("jl",)))
    assert (theta.unknowns, theta.unknown, theta.N) == (("jl",), "jl", 1)
    assert theta.assumed["ra"] == 1 and theta.true_value == 10
    # ra = 1: 100 jl s + 10 + 10 (jl + 1) s^2 + 101 s + 100 ... as the two-unknown Theta says
    assert theta.matrix == sympy.Matrix([[110, 0], [101, 100], [10, 10], [-100, 0]])


def test_monomials_by_total_degree_then_earlier_unknowns_first():
    # i/v of r0 a + 1/(b s) + c s with r0 = 2: b s / (b c s^2 + 2 a b s + 1)
    path = ROOT / "tests" / "data" / "valid" / "several_unknowns.bg"
    theta = theta_for(path)
    assert theta.column_labels == ("1", "b", "a*b", "b*c")
    assert theta.matrix == sympy.Matrix([[1, 0, 0, 0], [0, 0, 2, 0], [0, 0, 0, 1], [0, 0, 0, 0],
                                         [0, -1, 0, 0]])  # fmt: skip
    assert theta.degrees == {"a": 1, "b": 1, "c": 1}
    theta = theta_for(path, ParameterChoice(unknowns=("c", "b", "a")))
    assert theta.column_labels == ("1", "b", "c*b", "b*a")


def test_every_unknown_must_enter_rationally(tmp_path):
    path = tmp_path / "m.bg"
    path.write_text("model m\nunknown a = 1\nunknown b = 2\nSe:v -> 1:j\n1:j -> R:r(a*sqrt(b))\n"
                    "1:j -> C:c(a)\n1:j -> Df:i\n")  # fmt: skip
    with pytest.raises(ModelError) as caught:
        theta_for(path)
    (problem,) = caught.value.errors
    assert (problem.kind, problem.position.line, problem.position.column) == (
        "non_rational_unknown",
        5,
        12,
    )
    assert problem.message.endswith("not a rational function of the unknown b")
