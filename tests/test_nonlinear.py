"""Nonlinear state equations (issue 19 item 3): x' = f(x, u), y = g(x, u) derived from
the bond graph, against hand derivations of eleven models (f, g and their Jacobians,
exactly), and the linear models' equations as a check of the same path."""

from __future__ import annotations

from pathlib import Path

import pytest
import sympy
from sympy import Max, Rational, cos, exp, sin, sqrt, tanh

from mtt.derivation.nonlinear import NonlinearStateSpace, nonlinear_parts, nonlinear_state_space
from mtt.derivation.pipeline import equations_for, load
from mtt.language.diagnostics import ModelError

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / "tests" / "data" / "nonlinear"
S = sympy.Symbol
u = S("u")


def _zero(expr) -> bool:
    return sympy.simplify(expr) == 0


def _hand(path: Path):
    """Each model's states, then f and g written by hand from its physics."""
    name = path.stem
    if name == "tank":  # level q/2, outflow a sqrt(level)
        q, a = S("q_tank"), S("a")
        return [q], [u - a * sqrt(q / 2)], q / 2
    if name == "two_tanks":  # orifices, and the weir 20 (h1 - 30)^(3/2) above the rim
        q1, q2, a1, a2 = S("q_upper"), S("q_lower"), S("a1"), S("a2")
        h1, h2 = q1 / 50, q2 / 40
        spill = 20 * Max(h1 - 30, 0) ** Rational(3, 2)
        out1, out2 = a1 * sqrt(h1), a2 * sqrt(h2)
        return [q1, q2], [u - out1 - spill, out1 + spill - out2], h2
    if name == "pendulum":  # current p_la/la, speed p_arm/j, angle q_joint
        p_la, p_arm, q, j, fc = S("p_la"), S("p_arm"), S("q_joint"), S("j"), S("fc")
        i, w = p_la / Rational(1, 100), p_arm / j
        km, ra, b, v0 = Rational(1, 2), 2, Rational(1, 100), Rational(1, 100)
        mgl = Rational(1, 5) * Rational(981, 100) * Rational(3, 10)
        torque = km * i - fc * tanh(w / v0) - b * w - mgl * sin(q)
        return [p_la, p_arm, q], [u - ra * i - km * w, torque, w], w
    if name == "diode_clipper":  # the capacitor's voltage q/c; the diode's Shockley law
        q, r = S("q_c"), S("r")
        c, i_s, vt = Rational(1, 10**7), Rational(1, 10**12), Rational(26, 1000)
        v = q / c
        return [q], [(u - v) / r - i_s * (exp(v / vt) - 1)], v
    if name == "friction":  # speed p/2, friction fc tanh(speed/v0) + speed/10
        p, fc = S("p_mass"), S("fc")
        w = p / 2
        return [p], [u - fc * tanh(w * 100) - w / 10], w
    if name == "spring":  # e = 4 q + k3 q^3
        p, q, k3 = S("p_mass"), S("q_spring"), S("k3")
        return [p, q], [u - 4 * q - k3 * q**3, p], p
    if name == "inverse":  # the orifice in resistance causality: e = (f/a)^2
        p, a = S("p_pipe"), S("a")
        flow = p / 2
        return [p], [u - (flow / a) ** 2], flow
    if name == "loop":  # the loop r1, r2 solved: e_b = (v - r1 i) r2 / (r1 + r2)
        p = S("p_coil")
        i = 2 * p + p**3
        e_b = (u - 2 * i) * 3 / 5
        return [p], [e_b - 5 * i], i
    if name == "dependent":  # c2 in derivative causality: q2 = 3 e, e = q1^3/2
        q1 = S("q_c1")
        e = q1**3 / 2
        rate = (u - 5 * e) / (1 + 3 * sympy.diff(e, q1))
        return [q1], [rate], e
    if name == "lever":  # ratio n = 2 cos(angle): e2 = v/n, f1 = f2/n
        p, q = S("p_mass"), S("q_a")
        n = 2 * cos(q)
        return [p, q], [u / n, p / 3 / n], p / 3
    if name == "amplifier":  # 12 sat(5 u / 12) into rl = 4 and the coil l
        p, l_ = S("p_l"), S("l")
        x = 5 * u / 12
        return [p], [12 * x / sqrt(1 + x**2) - 4 * p / l_], p / l_
    raise KeyError(name)


HAND = sorted(
    [*DATA.glob("*.bg"), *(ROOT / "models" / f"{m}.bg" for m in ("two_tanks", "pendulum",
                                                                   "diode_clipper"))]
)  # fmt: skip


def test_eleven_models_are_written_by_hand():
    assert len(HAND) == 11 and all(nonlinear_parts(load(path)) for path in HAND)


@pytest.mark.parametrize("path", HAND, ids=lambda p: p.stem)
def test_state_equations_and_jacobians_equal_the_hand_derivation(path):
    system = nonlinear_state_space(path)
    states, f, g = _hand(path)
    assert isinstance(system, NonlinearStateSpace)
    assert list(system.states) == states
    assert system.input == u and system.output == S("y")
    assert all(_zero(a - b) for a, b in zip(system.f, f, strict=True))
    assert _zero(system.g[0] - g)
    hand_f, hand_g = sympy.Matrix(f), sympy.Matrix([g])
    for variables in (states, [u]):
        assert all(_zero(e) for e in system.f.jacobian(variables) - hand_f.jacobian(variables))
        assert all(_zero(e) for e in system.g.jacobian(variables) - hand_g.jacobian(variables))
    assert all(v.is_Rational for v in system.known.values())  # exact, not floats
    assert set(system.unknowns) == {S(name) for name in load(path).unknowns}


def test_jacobians_written_by_hand():
    """Three Jacobians differentiated on paper, not by sympy."""
    tank = nonlinear_state_space(DATA / "tank.bg")
    q, a = S("q_tank"), S("a")
    assert _zero(tank.f.jacobian([q])[0] + a / (2 * sqrt(2) * sqrt(q)))
    pendulum = nonlinear_state_space(ROOT / "models" / "pendulum.bg")
    p_arm, angle, j, fc = S("p_arm"), S("q_joint"), S("j"), S("fc")
    by_hand = sympy.Matrix(
        [
            [-200, -1 / (2 * j), 0],
            [50, -fc * 100 / j * (1 - tanh(100 * p_arm / j) ** 2) - 1 / (100 * j),
             -Rational(2943, 5000) * cos(angle)],
            [0, 1 / j, 0],
        ]
    )  # fmt: skip
    assert all(_zero(e) for e in pendulum.f.jacobian(pendulum.states) - by_hand)
    diode = nonlinear_state_space(ROOT / "models" / "diode_clipper.bg")
    q, r = S("q_c"), S("r")
    slope = -1 / (r * Rational(1, 10**7)) - exp(q * 10**7 / Rational(26, 1000)) * Rational(
        10**7, 10**12
    ) / Rational(26, 1000)
    assert _zero(diode.f.jacobian([q])[0] - slope)


@pytest.mark.parametrize("model", ["rlc", "dc_drive", "rlc3", "absorber"])
def test_a_linear_model_gives_its_state_space_matrices(model):
    """The nonlinear derivation of a linear model is x' = A x + B u, y = C x + D u."""
    path = ROOT / "models" / f"{model}.bg"
    equations = equations_for(load(path))
    matrices = equations.matrices()
    assert matrices["E"] == sympy.eye(len(equations.states))  # no dependent storage here
    system = nonlinear_state_space(path)
    x = sympy.Matrix([S(s) for s in equations.states])
    assert [s.name for s in system.states] == list(equations.states)
    linear = matrices["A"] * x + matrices["B"] * u
    assert all(_zero(a - b) for a, b in zip(system.f, linear, strict=True))
    assert _zero(system.g[0] - (matrices["C"] * x + matrices["D"] * u)[0])


def test_model_text_works_as_a_file_does():
    text = (DATA / "tank.bg").read_text()
    assert nonlinear_state_space(text).f == nonlinear_state_space(DATA / "tank.bg").f


def _error(text: str) -> tuple[str, int | None, int | None]:
    with pytest.raises(ModelError) as caught:
        nonlinear_state_space(text)
    (problem,) = caught.value.errors
    where = problem.position
    return problem.kind, where.line if where else None, where.column if where else None


def test_a_nonlinear_loop_sympy_cannot_solve_is_located():
    # r1 and r2 close an algebraic loop (the coil sets only 1:c's flow); r2 is given both
    # ways, so causality leaves the loop to r1, and the loop's equation, e + exp(e) against
    # a line, has no closed form
    text = """model m
Se:v -> 1:a
1:a -> R:r1
1:a -> 0:b
0:b -> R:r2(f = e + exp(e), e = log(f))
0:b -> 1:c
1:c -> R:r3
1:c -> I:coil
1:c -> Df:i
param r1 = 2
param r3 = 5
param coil = 1
"""
    assert _error(text) == ("algebraic_loop", 3, 8)


def test_the_input_derivative_is_refused_at_the_storage():
    # a capacitor straight across the voltage source: q = u^3 needs du/dt
    text = """model m
Se:v -> 0:n
0:n -> C:c(q = e^3)
0:n -> R:r(f = e^2)
0:n -> De:y
"""
    assert _error(text) == ("input_derivative", 3, 8)
