"""mtt's Python API (mtt.load, Model and its stages) against hand-derived values and the paper."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
import sympy
from scipy import signal

import mtt
from mtt.derivation import pipeline
from mtt.estimator import codegen
from mtt.language.diagnostics import ModelError

RC = """model rc
param r = 1000
unknown c = 1e-6
Se:v -> 1:loop
1:loop -> R:r
1:loop -> 0:out
0:out -> C:c
0:out -> De:vc
"""
s, k, c, r, tau, L = sympy.symbols("s k c r tau l")  # L is the flow ratio l


@pytest.fixture(scope="module")
def dc_drive() -> mtt.Model:
    return mtt.load(mtt.example("dc_drive"))


def kind_of(call, *args, **kwargs) -> mtt.MttError:
    with pytest.raises(mtt.MttError) as caught:
        call(*args, **kwargs)
    return caught.value


# load ----------------------------------------------------------------------------------


def test_a_file_name_a_path_and_the_text_give_the_same_model(tmp_path):
    path = tmp_path / "rc.bg"
    path.write_text(RC)
    models = [mtt.load(str(path)), mtt.load(path), mtt.load(RC)]
    assert [m.transfer_function.expr for m in models] == [1 / (1000 * c * s + 1)] * 3
    assert [m.source.name for m in models] == [str(path), str(path), "<string>"]


def test_set_keep_and_unknowns_choose_the_parameters():
    assert mtt.load(RC, set={"r": 0.1}).transfer_function.expr == 10 / (c * s + 10)
    assert mtt.load(RC, set={"r": "1/3"}).transfer_function.expr == 3 / (c * s + 3)
    assert mtt.load(RC, keep="r").transfer_function.expr == 1 / (c * r * s + 1)
    assert mtt.load(RC, keep=["r"]).transfer_function.symbols == ("r",)
    model = mtt.load(RC, unknowns=["r"])
    assert model.unknowns == ("r",)
    assert model.transfer_function.expr == 1000000 / (r * s + 1000000)
    assert mtt.load(RC, input="Se:v", output="De:vc").output == "De:vc"


def test_several_unknowns_in_the_transfer_function_theta_and_the_estimator():
    motor = mtt.load(mtt.example("dc_motor"))
    ra, jl = sympy.symbols("ra jl")
    # G = km / ((la s + ra)(J s + b) + km^2), J = jm + jl, with la = 1/10, km = jm = 1, b = 1/10
    G = 1 / ((s / 10 + ra) * ((1 + jl) * s + sympy.Rational(1, 10)) + 1)
    assert sympy.cancel(motor.transfer_function.expr - G) == 0
    assert motor.theta.monomials == (1, ra, jl, jl * ra)
    den = motor.transfer_function.at(ra=2, jl=3)[1]
    # (s/10 + 2)(4 s + 1/10) + 1 = 0.4 s^2 + 8.01 s + 1.2
    np.testing.assert_allclose(den / den[0], [1, 8.01 / 0.4, 1.2 / 0.4])
    rc = mtt.load(RC, unknowns="r,c")
    assert rc.unknowns == ("r", "c") and rc.theta.monomials == (1, c * r)
    assert motor.estimator().UNKNOWNS == ("ra", "jl") and motor.estimator().TRUE_VALUE == (
        1.0,
        10.0,
    )
    assert kind_of(motor.to_scipy, 1).kind == "bad_argument"


def test_the_paper_dc_drive_transfer_function_and_theta(dc_drive):
    paper = 10 * (k * s**2 + 1) / ((s**3 + 10 * s**2 + 11 * s + 10) * k * s + s**2 + 10 * s + 10)
    assert sympy.cancel(dc_drive.transfer_function.expr - paper) == 0
    assert dc_drive.theta.matrix == sympy.Matrix(
        [[10, 0], [10, 10], [1, 11], [0, 10], [0, 1], [-10, 0], [0, 0], [0, -10]]
    )
    assert dc_drive.theta.monomials == (1, k)


def test_the_paper_absorber_theta_with_tau_and_l_kept():
    theta = mtt.load(mtt.example("absorber"), keep="tau,l").theta
    assert theta.matrix == sympy.Matrix(
        [
            [L, L, L, L],
            [3 * L * tau, 4 * L * tau, 3 * L * tau, 0],
            [3 * L * tau**2, 3 * L * tau**2, 0, 0],
            [L * tau**3, 0, 0, 0],
            [0, 0, 0, -1],
        ]
    )
    assert theta.monomials == (1, k, k**2, k**3)
    assert theta.at(tau=2, l=0.5)[3].tolist() == [4.0, 0.0, 0.0, 0.0]


def test_at_gives_numeric_coefficients_highest_power_first():
    tf = mtt.load(RC).transfer_function
    num, den = tf.at()  # the file's c = 1e-6
    assert num.tolist() == [1.0] and den.tolist() == [1e-3, 1.0]
    assert tf.at(c=2e-6)[1].tolist() == [2e-3, 1.0]


def test_state_space_is_the_descriptor_form():
    ss = mtt.load(RC).state_space
    # q' = (v - q/c)/r, y = q/c with r = 1000
    assert ss.states == ("q_c",)
    expected = [[1], [-1 / (1000 * c)], [sympy.Rational(1, 1000)], [1 / c], [0]]
    matrices = [ss.E, ss.A, ss.B, ss.C, ss.D]
    assert matrices == [sympy.Matrix([row]) for row in expected]


def test_causality_strokes():
    causality = mtt.load(RC).causality
    assert causality.strokes == {1: "1:loop", 2: "R:r", 3: "1:loop", 4: "0:out", 5: "De:vc"}
    assert "1:loop ->| R:r" in str(causality)


def test_latex_display():
    model = mtt.load(RC)
    assert model.transfer_function._repr_latex_() == (
        "$\\displaystyle G(s) = \\frac{1}{1000\\,c\\,s + 1}$"
    )
    assert model.theta._repr_latex_() == (
        "$\\displaystyle \\Theta = \\left[\\begin{matrix}1 & 0\\\\0 & 1000\\\\-1 & 0"
        "\\end{matrix}\\right], \\quad K^T = \\left[\\begin{matrix}1 & c\\end{matrix}\\right]$"
    )
    assert model.state_space._repr_latex_().startswith("$\\displaystyle E = ")


# interoperability ----------------------------------------------------------------------


def test_to_scipy_has_the_frequency_response_of_the_exact_transfer_function(dc_drive):
    w = np.array([0.1, 1.0, 3.0, 30.0])
    _, response = signal.freqresp(dc_drive.to_scipy(10), w)
    G = sympy.lambdify(s, dc_drive.transfer_function.expr.subs(k, 10))
    np.testing.assert_allclose(response, G(1j * w), rtol=1e-12)


def test_to_scipy_takes_k_as_the_estimators_do(dc_drive):
    """A vector in the order of the unknowns (fit(...).k), a dict by name, or a number for one
    unknown (also as a vector of length 1): the same transfer function as by keywords."""
    motor = mtt.load(mtt.example("dc_motor"))
    # (s/10 + 2)(4 s + 1/10) + 1 = 0.4 s^2 + 8.01 s + 1.2, numerator 1, normalised by 0.4
    for k in ([2, 3], (2.0, 3.0), np.array([2.0, 3.0]), {"jl": 3, "ra": 2}):
        G = motor.to_scipy(k)
        np.testing.assert_allclose(G.num, [2.5], rtol=1e-15)
        np.testing.assert_allclose(G.den, [1.0, 20.025, 3.0], rtol=1e-15)
    np.testing.assert_allclose(motor.to_scipy({"ra": 2}).den, motor.to_scipy(ra=2).den)
    for bad in ([2.0], [1.0, 2.0, 3.0], [[2.0, 3.0]], 2.0):
        assert "give k as a sequence of 2 values in that order" in str(kind_of(motor.to_scipy, bad))
    assert kind_of(motor.to_scipy, [2, 3], ra=2).kind == "bad_argument"  # ra twice
    assert kind_of(motor.to_scipy, {"km": 2}).kind == "substituted_parameter"
    for k in ([10], np.array([10.0]), np.float64(10.0), "10"):
        assert dc_drive.to_scipy(k).den.tolist() == [1.0, 10.0, 11.1, 11.0, 1.0]


def test_to_control(dc_drive):
    control = pytest.importorskip("control")
    G = dc_drive.to_control(10)
    assert isinstance(G, control.TransferFunction)
    np.testing.assert_allclose(control.dcgain(G), 1.0)  # G(0) = 10/10


def test_several_unknowns_go_to_scipy_and_control_as_a_vector_a_dict_or_by_name():
    motor = mtt.load(mtt.example("dc_motor"))  # unknowns (ra, jl)
    # (0.1 s + ra)((1 + jl) s + 0.1) + 1 at ra = 2, jl = 5, normalised as scipy does
    expected = np.array([0.6, 12.01, 1.2]) / 0.6
    for G in (
        motor.to_scipy([2, 5]),
        motor.to_scipy(np.array([2.0, 5.0])),
        motor.to_scipy({"jl": 5, "ra": 2}),
        motor.to_scipy(ra=2, jl=5),
        motor.to_scipy({"ra": 2}, jl=5),
    ):
        np.testing.assert_allclose(G.den, expected, rtol=1e-15)
    den = motor.to_control([2, 5]).den[0][0]
    np.testing.assert_allclose(den / den[0], expected, rtol=1e-15)
    assert "give k as a sequence of 2 values" in str(kind_of(motor.to_scipy, 2))
    assert kind_of(motor.to_scipy, [1, 2, 3]).kind == "bad_argument"
    assert "ra is given twice" in str(kind_of(motor.to_scipy, [1, 2], ra=1))


def test_to_control_without_python_control_says_how_to_install(dc_drive, monkeypatch):
    monkeypatch.setitem(sys.modules, "control", None)  # import control -> ImportError
    error = kind_of(dc_drive.to_control, 10)
    assert error.kind == "missing_dependency" and "pip install -e '.[control]'" in str(error)


# the estimator -------------------------------------------------------------------------


def test_compile_writes_what_mtt_compile_writes(dc_drive, tmp_path):
    path = dc_drive.compile(tmp_path / "drive.py")
    expected = codegen.render(pipeline.theta_for(mtt.example("dc_drive")))
    assert path.read_text() == expected


def test_estimator_simulate_and_estimate_delegate_to_the_generated_module(dc_drive):
    module = dc_drive.estimator()
    assert module is dc_drive.estimator() and module.N == 1
    np.testing.assert_array_equal(module.theta(), dc_drive.theta.at())
    t = np.linspace(0.0, 10.0, 1001)
    u = np.ones_like(t)
    y = dc_drive.simulate(t, u, k=10)
    _, reference, _ = signal.lsim(dc_drive.to_scipy(10), u, t)  # linear interpolation
    np.testing.assert_allclose(y, reference, atol=1e-6)
    result = dc_drive.estimate(t, u, y, k0=5.0, beta=0.1, S0=1e-4, C=[1, 5, 10, 10, 5, 1])
    assert result.k == pytest.approx(10.0, abs=1e-3)  # the paper's Fig. 2
    error = kind_of(dc_drive.estimate, t, u, y, k0=float("nan"))
    assert error.kind == "bad_argument" and "k0" in str(error)


def test_fit_finds_the_paper_value_from_the_whole_record(dc_drive):
    t = np.linspace(0.0, 10.0, 1001)
    u = np.ones_like(t)
    y = dc_drive.simulate(t, u, k=10)
    result = dc_drive.fit(t, u, y)
    assert result.ok and result.k == pytest.approx(10.0, abs=1e-4)
    noisy = y + np.random.default_rng(0).uniform(-0.02, 0.02, t.size)
    at_rest = dict(offset=False, initial_state=False)  # the paper's step: from rest, no offset
    assert dc_drive.fit(t, u, noisy, **at_rest).k == pytest.approx(10.0, abs=0.1)
    error = kind_of(dc_drive.fit, t, u, y, beta=-1)
    assert error.kind == "bad_argument" and "beta" in str(error)


# errors --------------------------------------------------------------------------------


def test_model_errors_are_mtt_errors_located_at_the_first_error():
    error = kind_of(mtt.load, "model broken\nparam r = 1 +\nSe:v -> 1:j\n")
    assert isinstance(error, ModelError)
    assert (error.kind, error.file, error.line) == ("syntax", "<string>", 2)
    assert error.column is not None
    assert kind_of(mtt.load, "no/such/file.bg").kind == "io"


@pytest.mark.parametrize(
    ("options", "kind", "says"),
    [
        ({"input": "Sf:x"}, "undeclared_component", "Sf:x"),
        ({"set": {"x": 1}}, "undeclared_parameter", "'x'"),
        ({"set": {"r": float("inf")}}, "bad_value", "finite"),
        ({"set": {"r": True}}, "bad_value", "expected a number"),
        ({"set": {"r": "abc"}}, "undeclared_parameter", "'abc'"),
        ({"keep": ["x"]}, "undeclared_parameter", "'x'"),
        ({"unknowns": "x"}, "undeclared_parameter", "x"),
        ({"keep": 3}, "bad_value", "keep takes parameter names, not 3"),
        ({"input": 3}, "bad_value", "input takes a component TYPE:NAME, not 3"),
        ({"output": ["De:vc", 3]}, "bad_value", "output takes a component TYPE:NAME"),
        ({"set": "r=2"}, "bad_value", "set takes a dict {name: value}, not 'r=2'"),
    ],
)
def test_bad_options_are_mtt_errors(options, kind, says):
    error = kind_of(mtt.load, RC, **options)
    assert error.kind == kind and says in str(error)


@pytest.mark.parametrize(
    ("values", "kind"),
    [
        ({"x": 1}, "undeclared_parameter"),
        ({"r": 1}, "substituted_parameter"),
        ({"c": float("nan")}, "bad_value"),
        ({"c": 10**400}, "out_of_range"),
        ({"c": "sqrt(-1)"}, "bad_value"),
    ],
)
def test_bad_values_are_mtt_errors(values, kind):
    assert kind_of(mtt.load(RC).transfer_function.at, **values).kind == kind


def test_a_parameter_without_a_value_must_be_given():
    model = mtt.load(RC.replace("unknown c = 1e-6", "unknown c"))
    error = kind_of(model.transfer_function.at)
    assert error.kind == "missing_value" and "pass c=VALUE" in str(error)
    assert model.transfer_function.at(c=1)[1].tolist() == [1000.0, 1.0]


def test_theta_needs_an_unknown():
    model = mtt.load(RC.replace("unknown c", "param c"))
    assert kind_of(lambda: model.theta).kind == "no_unknown"


# import ---------------------------------------------------------------------------------


def test_import_mtt_is_light_until_the_api_is_used():
    probe = (
        "import json, sys, mtt\n"
        "before = 'sympy' in sys.modules\n"
        "names = dir(mtt)\n"
        "mtt.load\n"
        "print(json.dumps([before, 'sympy' in sys.modules, names]))\n"
    )
    output = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True)
    before, after, names = json.loads(output.stdout)
    assert (before, after) == (False, True)
    assert set(mtt.__all__) <= set(names)


def test_a_value_that_lowers_a_degree_gives_the_shorter_polynomials(dc_drive, recwarn):
    # k = 0: no load inertia, G(s) = 10 / (s^2 + 10 s + 10)
    num, den = dc_drive.transfer_function.at(k=0)
    assert (num.tolist(), den.tolist()) == ([10.0], [1.0, 10.0, 10.0])
    dc_drive.to_scipy(0)
    assert not [w for w in recwarn if "coefficients" in str(w.message)]  # scipy's BadCoefficients


KEPT_K = (  # the unknown is c; a known parameter is called k (kept symbolic)
    "model rck\nparam r = 1000\nparam k = 2\nunknown c = 1e-6\nSe:v -> 1:loop\n"
    "1:loop -> R:r\n1:loop -> 0:out\n0:out -> C:c\n0:out -> R:k\n0:out -> De:vc\n"
)


def test_the_unknown_s_value_never_lands_on_a_parameter_of_the_same_name():
    model = mtt.load(KEPT_K, keep="k")
    tf = model.transfer_function
    by_name, positional = tf.at(c=1e-3, k=5), tf.at(1e-3, k=5)
    assert all(np.array_equal(a, b) for a, b in zip(by_name, positional, strict=True))
    # k= is the parameter k, never the unknown: c keeps the file's value
    expected = signal.TransferFunction(*tf.at(c=1e-6, k=10))
    assert np.allclose(model.to_scipy(k=10).den, expected.den)
    assert not np.allclose(model.to_scipy(10).den, expected.den)
    assert "c is given twice" in str(kind_of(model.to_scipy, 1e-3, c=1e-3))


def test_discrete_time_and_state_space_exports_agree_with_the_transfer_function():
    rlc = mtt.load(mtt.example("rlc"))  # G(s) = 2cs / (cs^2 + 4cs + 2)
    G = rlc.to_scipy(0.1)
    for method in ("zoh", "foh"):
        sampled = rlc.to_scipy(0.1, dt=0.05, method=method)
        reference = signal.cont2discrete((G.num, G.den), 0.05, method=method)
        assert sampled.dt == 0.05
        np.testing.assert_allclose(sampled.num, np.trim_zeros(np.ravel(reference[0]), "f"))
        np.testing.assert_allclose(sampled.den, reference[1], atol=1e-12)
    A, B, C, D = rlc.state_space.at(0.1)
    s = 0.7j
    response = (C @ np.linalg.solve(s * np.eye(2) - A, B) + D).item()
    np.testing.assert_allclose(response, np.polyval(G.num, s) / np.polyval(G.den, s))
    assert kind_of(rlc.to_scipy, 0.1, dt=-1).kind == "bad_value"
    assert "method must be one of" in str(kind_of(rlc.to_scipy, 0.1, dt=1, method="tustin"))


def test_python_control_gets_mtt_s_names_in_either_form():
    control = pytest.importorskip("control")
    rlc = mtt.load(mtt.example("rlc"))
    tf, ss = rlc.to_control(0.1), rlc.to_control(0.1, form="ss")
    assert (tf.name, tf.input_labels, tf.output_labels) == ("rlc", ["Se:v"], ["Df:i"])
    assert ss.state_labels == ["p_l", "q_c"] and ss.input_labels == ["Se:v"]
    w = np.array([0.3, 3.0])
    np.testing.assert_allclose(ss(1j * w), tf(1j * w))
    sampled = rlc.to_control(0.1, form="ss", dt=0.05)
    assert sampled.dt == 0.05 and isinstance(sampled, control.StateSpace)
    assert kind_of(rlc.to_control, 0.1, form="zpk").kind == "bad_argument"


def test_an_option_named_like_a_parameter_is_refused_as_ambiguous():
    model = mtt.load(KEPT_K.replace("param k = 2", "param dt = 2").replace("R:k", "R:dt"),
                     keep="dt")  # fmt: skip
    assert "dt= is ambiguous" in str(kind_of(model.to_scipy, 1e-6, dt=0.1))
    sampled = model.to_scipy({"c": 1e-6, "dt": 3}, dt=0.1)  # the parameter in the dict
    assert sampled.dt == 0.1


def test_latex_spaces_its_factors_and_sets_long_names_as_one_symbol():
    model = mtt.load(
        "model m\nparam b = 1\nunknown mass = 2\nSe:f -> 1:j\n1:j -> I:mass\n1:j -> R:b\n"
        "1:j -> Df:v\n"
    )
    latex = model.transfer_function._repr_latex_()
    assert "\\mathit{mass}\\,s" in latex and "mass s" not in latex


def test_a_fit_prints_as_the_command_line_does_and_shows_as_a_table():
    rlc = mtt.load(mtt.example("rlc"))
    t = np.linspace(0.0, 10.0, 501)
    u = rlc.estimator().input_signal("prbs", t, period=0.2)
    y = (
        rlc.with_noise(rlc.simulate(t, u, hold="zoh"), 30)
        if hasattr(rlc, "with_noise")
        else (rlc.estimator().with_noise(rlc.simulate(t, u, hold="zoh"), 30))
    )
    found = rlc.fit(t, u, y, hold="zoh")
    lines = str(found).splitlines()
    assert lines[0] == "rlc: 501 samples" and found.summary() == str(found)
    assert lines[1].startswith(f"  c = {found.k:.6g} \u00b1 {found.k_se:.3g} (standard error")
    html = found._repr_html_()
    assert "<table>" in html and f"<td>{found.k:.6g}</td>" in html
    assert found.ok and found.result.k == found.k  # every attribute of the module's Fit
    both = rlc.fit([t, t], [u, u], [y, y], hold="zoh")
    assert str(both).startswith("rlc: 501 samples; 501 samples")
    with pytest.raises(mtt.MttError, match="unexpected parameter 'holds'"):
        rlc.fit(t, u, y, holds="zoh")  # a misspelt keyword is not a kept parameter either


def test_fit_and_estimate_list_the_generated_module_s_keywords():
    """The API's signatures are written out; they must stay those of the template's."""
    import inspect

    model = mtt.load(mtt.example("rlc"))
    module = model.estimator()
    for name in ("fit", "estimate"):
        ours = inspect.signature(getattr(model, name)).parameters
        theirs = inspect.signature(getattr(module, name)).parameters
        assert [(p.name, p.kind, p.default) for p in ours.values()] == [
            (p.name, p.kind, p.default) for p in theirs.values()
        ]
