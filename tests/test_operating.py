"""Operating points and linearisation (issue 19 item 4): steady states, exact and numeric,
every branch; the small-signal model against central finite differences of f (exact
arithmetic) and of the generated simulator, and its transfer function against the
small-signal transfer functions derived by hand; the commands and their errors."""

from __future__ import annotations

import contextlib
import io
import json
import math
from pathlib import Path
from types import MappingProxyType

import numpy as np
import pytest
import sympy
from sympy import Rational, sqrt

import mtt
from mtt.cli.main import main
from mtt.derivation.equilibria import equilibria
from mtt.derivation.nonlinear import nonlinear_state_space
from mtt.derivation.parameters import ParameterChoice
from mtt.derivation.pipeline import equations_for, linearised_for, load, transfer_for
from mtt.derivation.transfer import transfer_function
from mtt.estimator import nonlinear_codegen
from mtt.language.diagnostics import ModelError

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "models"
DATA = ROOT / "tests" / "data" / "nonlinear"
S = sympy.Symbol
s = S("s")


def _at(**given) -> ParameterChoice:
    point = {name: sympy.Rational(str(value)) for name, value in given.items()}
    return ParameterChoice(at=MappingProxyType(point))


def _values(path: Path) -> dict:
    graph = load(path)
    return {S(n): p.value.value for n, p in graph.parameters.items() if n in graph.unknowns}


# Steady states -------------------------------------------------------------------------


def test_the_tanks_steady_state_is_exact_in_the_unknowns():
    system = nonlinear_state_space(MODELS / "two_tanks.bg")
    found = equilibria(system, Rational(10), _values(MODELS / "two_tanks.bg"))
    assert found.method == "exact" and len(found.branches) == 1
    (branch,) = found.branches
    a1, a2 = S("a1"), S("a2")  # a sqrt(q/area) = 10
    assert branch.x[S("q_upper")] == 5000 / a1**2 and branch.x[S("q_lower")] == 4000 / a2**2
    assert branch.numeric[S("q_upper")] == 1250 and branch.y_numeric == 16


def test_the_overflowing_tank_is_found_numerically():
    system = nonlinear_state_space(MODELS / "two_tanks.bg")
    found = equilibria(system, Rational(20), _values(MODELS / "two_tanks.bg"))
    (branch,) = found.branches
    h1 = branch.numeric[S("q_upper")] / 50  # over the rim: 20 = 2 sqrt(h1) + 20 (h1-30)^1.5
    assert h1 > 30 and math.isclose(2 * math.sqrt(h1) + 20 * (h1 - 30) ** 1.5, 20, rel_tol=1e-9)
    assert math.isclose(branch.numeric[S("q_lower")], 40 * (20 / 2.5) ** 2, rel_tol=1e-9)


def test_the_pendulum_has_two_branches_the_hanging_one_first():
    system = nonlinear_state_space(MODELS / "pendulum.bg")
    found = equilibria(system, Rational(1), _values(MODELS / "pendulum.bg"))
    angles = [b.x[S("q_joint")] for b in found.branches]
    c = Rational(1250, 2943)  # km v / (ra m g l)
    assert found.method == "exact" and angles == [sympy.asin(c), sympy.pi - sympy.asin(c)]
    assert all(b.x[S("p_arm")] == 0 and b.x[S("p_la")] == Rational(1, 200) for b in found.branches)


def test_the_diode_has_no_closed_form_and_is_solved_numerically():
    system = nonlinear_state_space(MODELS / "diode_clipper.bg")
    found = equilibria(system, Rational(1), _values(MODELS / "diode_clipper.bg"))
    (branch,) = found.branches
    v = branch.y_numeric  # (1 - v)/r = is (exp(v/vt) - 1)
    assert found.method == "numeric"
    assert math.isclose((1 - v) / 1000, 1e-12 * (math.exp(v / 0.026) - 1), rel_tol=1e-9)


# Linearisation -------------------------------------------------------------------------

POINTS = [
    ("two_tanks", {"u": 10}, None),
    ("two_tanks", {"u": 20}, None),  # overflowing: a numeric steady state
    ("pendulum", {"u": 1}, 1),
    ("pendulum", {"u": 1}, 2),
    ("diode_clipper", {"u": 1}, None),
    ("friction", {"u": 1}, None),
    ("spring", {"q_spring": 1, "p_mass": 0}, None),  # u = 4 + k3 keeps it steady
    ("lever", {"q_a": "0.5", "p_mass": 0}, None),
]


def _path(name: str) -> Path:
    return MODELS / f"{name}.bg" if (MODELS / f"{name}.bg").exists() else DATA / f"{name}.bg"


def _numbers(matrix: sympy.Matrix, values: dict) -> np.ndarray:
    return np.array(matrix.xreplace(values).evalf(30).tolist(), dtype=float)


@pytest.mark.parametrize(("name", "point", "branch"), POINTS)
def test_the_linearisation_is_the_central_difference_jacobian(name, point, branch):
    """A, B, C, D at the file's values equal central differences of f and g, computed in
    30-digit arithmetic, to 1e-8 relative."""
    path = _path(name)
    choice = _at(**point)
    choice = ParameterChoice(at=choice.at, branch=branch)
    system, small, _ = linearised_for(load(path), choice)
    values = _values(path)
    x0 = {x: v.xreplace(values) for x, v in small.x0.items()}
    u0 = small.u0.xreplace(values)
    base = [sympy.Float(v.evalf(40), 40) for v in (*[x0[x] for x in system.states], u0)]
    variables = [*system.states, system.input]
    both = sympy.Matrix([*system.f, system.g[0]])
    fd = np.zeros((len(both), len(variables)))
    for j in range(len(variables)):
        h = sympy.Float(1e-20, 40) * (abs(base[j]) or 1)  # 40 digits: no rounding to fear
        up, down = list(base), list(base)
        up[j] += h
        down[j] -= h
        at = lambda point: dict(zip(variables, point, strict=True)) | values  # noqa: E731
        difference = (both.xreplace(at(up)) - both.xreplace(at(down))).evalf(40) / (2 * h)
        fd[:, j] = np.array([complex(v).real for v in difference], dtype=float)
    exact = np.block(
        [[_numbers(small.A, values), _numbers(small.B, values)],
         [_numbers(small.C, values), _numbers(small.D, values)]]
    )  # fmt: skip
    scale = np.max(np.abs(fd))
    if name == "two_tanks" and point["u"] == 20:  # numbers rounded to 17 digits
        assert np.allclose(exact, fd, rtol=1e-8, atol=1e-8 * scale)
    else:
        assert np.allclose(exact, fd, rtol=1e-8, atol=1e-12 * scale)


@pytest.mark.parametrize(("name", "point", "branch"), POINTS[:5])
def test_the_linearisation_is_the_simulators_finite_difference(name, point, branch):
    """The generated simulator's f (numpy, double precision): central differences agree
    with A and B to 1e-8 relative, and its own Jacobians too."""
    path = _path(name)
    system, small, _ = linearised_for(load(path), ParameterChoice(at=_at(**point).at,
                                                                   branch=branch))  # fmt: skip
    values = _values(path)
    module = nonlinear_codegen.load(system)
    k = np.array([float(values[unknown]) for unknown in system.unknowns])
    x0 = np.array([float(small.x0[x].xreplace(values)) for x in system.states])
    u0 = float(small.u0.xreplace(values))
    A, B = _numbers(small.A, values), _numbers(small.B, values)
    columns = []
    for j in range(len(x0) + 1):
        step = 1e-6 * abs(([*x0, u0])[j]) or 1e-8  # the truncation error of tanh near 0
        up, down = np.append(x0, u0), np.append(x0, u0)
        up[j] += step
        down[j] -= step
        rate = [module.rhs(z[:-1], z[-1], k) for z in (up, down)]
        columns.append((rate[0] - rate[1]) / (2 * step))
    fd = np.column_stack(columns)
    exact = np.hstack([A, B])
    assert np.allclose(fd, exact, rtol=1e-8, atol=1e-8 * np.max(np.abs(exact)))
    jac = module.jacobians(x0, u0, k)  # (below the tanks' rim: no 0/0 from the weir)
    assert np.allclose(jac.f_x, A, rtol=1e-12, atol=1e-12 * np.max(np.abs(A)))


def _tf(A, B, C, D) -> sympy.Expr:
    n = A.shape[0]
    return sympy.cancel((C * (s * sympy.eye(n) - A).inv() * B + D)[0])


def _equal(derived, hand) -> bool:
    return sympy.cancel(derived.numerator / derived.denominator - hand) == 0


def test_the_tanks_small_signal_transfer_function_is_the_hand_derived_one():
    # a sqrt(q/area) = u0 gives the slope d/dq = a^2 / (2 area u0) at the steady state
    a1, a2, u0 = S("a1"), S("a2"), 10
    k1, k2 = a1**2 / (2 * 50 * u0), a2**2 / (2 * 40 * u0)
    hand = Rational(1, 40) * k1 / ((s + k1) * (s + k2))
    assert _equal(transfer_for(MODELS / "two_tanks.bg", _at(u=10)), hand)


def test_the_pendulum_small_signal_transfer_function_is_the_hand_derived_one():
    # about the hanging branch: the friction's slope at rest fc/v0 + b, gravity's
    # m g l cos(angle) = sqrt((m g l)^2 - (km v / ra)^2)
    j, fc = S("j"), S("fc")
    stiffness = sqrt(Rational(2943, 5000) ** 2 - Rational(1, 4) ** 2)
    A = sympy.Matrix(
        [[-200, -1 / (2 * j), 0], [50, -(100 * fc + Rational(1, 100)) / j, -stiffness],
         [0, 1 / j, 0]]
    )  # fmt: skip
    B, C = sympy.Matrix([1, 0, 0]), sympy.Matrix([[0, 1 / j, 0]])
    hand = _tf(A, B, C, sympy.zeros(1, 1))
    choice = ParameterChoice(at=_at(u=1).at, branch=1)
    assert _equal(transfer_for(MODELS / "pendulum.bg", choice), hand)


def test_the_orifice_in_resistance_causality_linearises_through_its_inverse():
    # dp/dt = u - (p / (l a))^2 with l = 2; at u0, p0 = l a sqrt(u0): slope 2 sqrt(u0)/(l a)
    a = S("a")
    slope = 2 * sqrt(4) / (2 * a)
    hand = Rational(1, 2) / (s + slope)
    assert _equal(transfer_for(DATA / "inverse.bg", _at(u=4)), hand)


@pytest.mark.parametrize("model", ["rlc", "dc_motor", "dc_drive", "rlc3"])
def test_a_linear_model_linearises_to_its_own_transfer_function(model):
    """Through the nonlinear derivation (dependent storage by the chain rule: dc_motor)."""
    path = MODELS / f"{model}.bg"
    linear = transfer_for(path)
    small = transfer_function(equations_for(load(path), _at(u=0)))
    assert (
        sympy.cancel(linear.numerator * small.denominator - small.numerator * linear.denominator)
        == 0
    )


# The API and the command line ---------------------------------------------------------


def _run(*argv: str) -> tuple[int, str, str]:
    """`mtt ARGV` in process: its status, standard output and standard error."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main(list(argv))
    return status, out.getvalue(), err.getvalue()


def test_the_api_linearises_and_compiles(tmp_path):
    tanks = mtt.load(mtt.example("two_tanks"))
    assert tanks.nonlinear and tanks.state_space.nonlinear
    with pytest.raises(mtt.MttError) as caught:
        tanks.transfer_function  # noqa: B018 - the property raises
    assert caught.value.kind == "nonlinear_model"
    small = tanks.linearise(u=10)
    assert small.theta.unknowns == ("a1", "a2") and not small.state_space.nonlinear
    module = small.estimator()
    assert module.UNKNOWNS == ("a1", "a2")
    assert str(tanks.equilibrium(10)).startswith("model two_tanks: steady states at u = 10")


def test_the_commands():
    status, out, _ = _run("equilibrium", str(MODELS / "pendulum.bg"), "--u", "1", "--json")
    record = json.loads(out)
    assert status == 0 and record["method"] == "exact" and len(record["branches"]) == 2
    assert record["branches"][0]["x"]["q_joint"] == "asin(1250/2943)"
    status, out, _ = _run("linearise", str(MODELS / "two_tanks.bg"), "--at", "u=10", "--json")
    record = json.loads(out)
    assert record["A"] == [["-a1**2/1000", "0"], ["a1**2/1000", "-a2**2/800"]]
    assert record["transfer_function"]["num"] == "20*a1**2"
    status, out, _ = _run("ss", str(MODELS / "two_tanks.bg"), "--json")
    assert json.loads(out)["states"] == ["q_upper", "q_lower"]
    status, out, _ = _run("ss", str(MODELS / "two_tanks.bg"))
    assert "dq_upper/dt = " in out and "Max(0, q_upper/50 - 30)**(3/2)" in out
    status, out, err = _run("tf", str(MODELS / "two_tanks.bg"), "--at", "x=1250;640")
    # h1 = 25, h2 = 16: the slopes a1 / (2 50 sqrt(25)) and a2 / (2 40 sqrt(16))
    assert status == 0 and "G(s) = 8*a1 / ((a1 + 500*s)*(a2 + 320*s))" in out, err


# Errors and warnings, each with its place -------------------------------------------------


def _problem(*argv):
    status, out, err = _run(*argv, "--json")
    assert status == 2, err
    return json.loads(out.splitlines()[-1])


@pytest.mark.parametrize(
    ("argv", "kind", "where"),
    [
        (["tf", "models/two_tanks.bg"], "nonlinear_model", (25, 20)),
        (["theta", "models/pendulum.bg"], "nonlinear_model", (33, 23)),
        (["linearise", "models/pendulum.bg", "--at", "u=1"], "several_equilibria", None),
        (["linearise", "models/pendulum.bg", "--at", "u=1", "--branch", "3"], "bad_point", None),
        (["linearise", "models/two_tanks.bg", "--at", "h=2"], "bad_point", None),
        (["linearise", "models/two_tanks.bg", "--at", "x=1"], "bad_point", None),
        (["linearise", "models/two_tanks.bg", "--at", "u=-1"], "no_equilibrium", None),
    ],
)
def test_operating_point_errors(argv, kind, where, monkeypatch):
    monkeypatch.chdir(ROOT)
    record = _problem(*argv)
    (error,) = record["errors"]
    assert error["kind"] == kind
    assert (error["line"], error["column"]) == (where or (None, None))


def test_a_numeric_steady_state_needs_every_value(tmp_path):
    path = tmp_path / "m.bg"
    text = (MODELS / "diode_clipper.bg").read_text()
    path.write_text(text.replace("unknown r = 1000", "unknown r"))
    system = nonlinear_state_space(path)
    with pytest.raises(ModelError) as caught:
        equilibria(system, Rational(1), {})
    (problem,) = caught.value.errors
    assert (problem.kind, problem.position) == ("missing_value", None)


def test_the_warnings_of_a_linearisation():
    notes = {}
    for path, point in [
        (MODELS / "two_tanks.bg", {"u": 20}),  # numeric steady state
        (MODELS / "two_tanks.bg", {"q_upper": 1000, "q_lower": 640}),  # not steady
        (MODELS / "diode_clipper.bg", {"u": 1}),  # exp of a number
    ]:
        _, small, _ = linearised_for(load(path), _at(**point))
        notes[path.stem, tuple(point)] = {n.kind for n in small.notes}
    assert notes["two_tanks", ("u",)] == {"numeric_point"}
    assert notes["two_tanks", ("q_upper", "q_lower")] == {"not_equilibrium"}
    assert notes["diode_clipper", ("u",)] >= {"numeric_point"}
    q = {"q_c": Rational(5, 10**8)}
    _, small, _ = linearised_for(load(MODELS / "diode_clipper.bg"), _at(**q))
    assert "rounded_constant" in {n.kind for n in small.notes}
