"""The generated nonlinear simulator (issue 19 item 5) against independent references:
its kernels against sympy's own evaluation of the equations, its simulations against
scipy's solve_ivp on hand-written right-hand sides at tight tolerances (with solve_ivp's
own event location for the overflow), its sensitivities against central finite
differences of its simulations."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import sympy
from nonlinear_models import PENDULUM_K, TWO_TANKS_K, pendulum, two_tanks, weir_tanks
from scipy.integrate import solve_ivp

import mtt
from mtt.derivation.nonlinear import NonlinearStateSpace, nonlinear_state_space
from mtt.estimator import nonlinear_codegen
from mtt.language.diagnostics import ModelError

DATA = Path(__file__).resolve().parent / "data" / "nonlinear"
TANKS_VALUES = dict(zip(("c1", "c2", "kp"), TWO_TANKS_K, strict=True))


@pytest.fixture(scope="module")
def tanks():
    return nonlinear_codegen.load(two_tanks(), values=TANKS_VALUES)


@pytest.fixture(scope="module")
def arm():
    return nonlinear_codegen.load(pendulum(), values=dict(J=0.05, fc=0.1))


def _record(n: int = 401, span: float = 200.0, period: int = 40, seed: int = 0):
    """A pump signal that switches between 0.2 and 1 (the upper tank overflows at 1)."""
    t = np.linspace(0.0, span, n)
    bits = np.random.default_rng(seed).integers(0, 2, n // period + 1)
    return t, 0.2 + 0.8 * np.repeat(bits, period)[:n]


def _tanks_rhs(k, t, u, hold):
    c1, c2, kp = k

    def rhs(time, x):
        j = min(max(int(np.searchsorted(t, time, side="right")) - 1, 0), t.size - 2)
        uu = u[j] if hold == "zoh" else u[j] + (time - t[j]) * (u[j + 1] - u[j]) / (t[j + 1] - t[j])
        h1, h2 = x[0], x[1] / 1.5
        return [
            kp * uu - c1 * math.sqrt(h1) - 2 * max(h1 - 3, 0.0),
            c1 * math.sqrt(h1) - c2 * math.sqrt(h2),
        ]

    return rhs


def _reference(rhs, t, x0, events=None):
    """States at every sample, one solve_ivp per sample interval (DOP853, rtol 1e-12), and
    the times events fired."""
    x, xs, fired = np.array(x0, dtype=float), [np.array(x0, dtype=float)], []
    for a, b in zip(t[:-1], t[1:], strict=True):
        run = solve_ivp(rhs, (a, b), x, method="DOP853", rtol=1e-12, atol=1e-14, events=events)
        if events is not None:
            fired += run.t_events[0].tolist()
        x = run.y[:, -1]
        xs.append(x)
    return np.array(xs), fired


def _crossing(time, x):
    return x[0] - 3.0


def _multisine(n: int = 151, span: float = 200.0):
    """A pump signal changing at every sample (the integrators' other regime: RODAS4
    steps from sample to sample where LSODA would restart at each)."""
    t = np.linspace(0.0, span, n)
    harmonics = np.arange(1, 6)
    wave = np.cos(2 * np.pi * np.outer(t / 50.0, harmonics) - np.pi * harmonics**2 / 5).sum(1)
    return t, 0.8 + 0.4 * wave / np.abs(wave).max()


@pytest.mark.parametrize("signal", [_record, _multisine])
@pytest.mark.parametrize("hold", ["zoh", "linear"])
def test_two_tanks_match_a_tight_reference_through_every_overflow(tanks, hold, signal):
    """The overflow is a kink (max): taken on the branch the state is on, crossed under
    the error control (no event: the sensitivities stay continuous there)."""
    t, u = signal()
    x0, tolerances = [1.0, 1.0], dict(rtol=1e-10, atol=1e-12)
    y = tanks.simulate(t, u, x0=x0, hold=hold, **tolerances)
    run = tanks.sensitivities(t, u, x0=x0, hold=hold, **tolerances)
    states, fired = _reference(_tanks_rhs(TWO_TANKS_K, t, u, hold), t, x0, _crossing)
    assert np.max(np.abs(y - states[:, 1] / 1.5)) < 1e-9 * np.max(np.abs(y))
    assert np.max(np.abs(run.x - states)) < 1e-9 * np.max(np.abs(states))
    assert len(fired) >= 3  # the record overflows, stops, and overflows again
    assert not run.events


@pytest.mark.parametrize("hold", ["zoh", "linear"])
def test_a_weir_over_the_rim_is_simulated_through_its_kink(hold):
    """20 max(h1 - 30, 0)^(3/2): the branch over the rim has no value below it, so the
    integrators may not step past the surface on it (they approach it); many sets at
    once as well."""
    module = nonlinear_codegen.load(weir_tanks(), values={"a1": 2, "a2": 2.5})
    t = np.linspace(0.0, 1500.0, 301)
    u = 8.0 + 6.0 * module.input_signal("prbs", t, period=150.0)
    x0 = [1000.0, 1000.0]

    def rhs(time, x):
        j = min(max(int(np.searchsorted(t, time, side="right")) - 1, 0), t.size - 2)
        uu = u[j] if hold == "zoh" else u[j] + (time - t[j]) * (u[j + 1] - u[j]) / (t[j + 1] - t[j])
        fall = 2 * math.sqrt(x[0] / 50) + 20 * max(x[0] / 50 - 30, 0.0) ** 1.5
        return [uu - fall, fall - 2.5 * math.sqrt(x[1] / 40)]

    states, fired = _reference(rhs, t, x0, lambda time, x: x[0] / 50 - 30)
    run = module.sensitivities(t, u, x0=x0, hold=hold, rtol=1e-10, atol=1e-10)
    assert len(fired) >= 2 and not run.events
    assert np.max(np.abs(run.x - states)) < 1e-8 * np.max(np.abs(states))
    rows = module.simulate(t, u, [[2.0, 2.5], [2.1, 2.4]], x0=x0, hold=hold, rtol=1e-10, atol=1e-10)
    assert np.max(np.abs(rows[0] - states[:, 1] / 40)) < 1e-8 * np.max(states[:, 1] / 40)


def test_pendulum_matches_a_tight_reference(arm):
    t = np.linspace(0.0, 10.0, 501)
    u = arm.input_signal("multisine", t, amplitude=3.0, period=5.0)
    J, fc = PENDULUM_K

    def rhs(time, x):
        uu = np.interp(time, t, u)
        i, w = 20 * x[0], x[1] / J
        return [uu - i - w / 2, i / 2 - math.sin(x[2]) / 2 - fc * math.tanh(50 * w) - w / 100, w]

    states, _ = _reference(rhs, t, [0.0, 0.0, 0.0])
    y = arm.simulate(t, u, rtol=1e-11, atol=1e-13)
    assert np.max(np.abs(y - states[:, 2])) < 1e-8 * np.max(np.abs(states[:, 2]))
    assert np.ptp(y) > 1.0  # it swings through large angles


def _central(simulate, point, i, step):
    up, down = np.array(point, dtype=float), np.array(point, dtype=float)
    up[i] += step
    down[i] -= step
    return (simulate(up) - simulate(down)) / (2 * step)


def _agree_with_finite_differences(module, t, u, k, x0, tight, tolerance=1e-6):
    run = module.sensitivities(t, u, k, x0=x0, **tight)
    for i in range(k.size):
        fd = _central(lambda k_: module.simulate(t, u, k_, x0=x0, **tight), k, i, 1e-4 * k[i])
        assert np.max(np.abs(run.dy_dk[:, i] - fd)) < tolerance * np.max(np.abs(fd)), i
    for i in range(x0.size):
        fd = _central(lambda x_: module.simulate(t, u, k, x0=x_, **tight), x0, i, 1e-4)
        scale = max(np.max(np.abs(fd)), 1e-3 * np.max(np.abs(run.y)))
        assert np.max(np.abs(run.dy_dx0[:, i] - fd)) < tolerance * scale, i
    return run


@pytest.mark.parametrize("hold", ["zoh", "linear"])
def test_sensitivities_agree_with_finite_differences(tanks, arm, hold):
    tight = dict(hold=hold, rtol=1e-12, atol=1e-14)
    t, u = _record(n=401, span=100.0, period=40)
    _agree_with_finite_differences(tanks, t, u, np.array(TWO_TANKS_K), np.array([1.0, 1.0]), tight)
    t = np.linspace(0.0, 5.0, 251)
    u = arm.input_signal("square", t, amplitude=3.0, period=2.0)
    x0 = np.array([0.0, 0.01, 0.2])
    _agree_with_finite_differences(arm, t, u, np.array(PENDULUM_K), x0, tight)


def test_a_looser_tolerance_of_the_sensitivities_alone_keeps_them_to_it(tanks):
    """sensitivity_rtol (the fit's Jacobian): the states at rtol, the sensitivities at
    their own tolerance, with fewer steps."""
    t, u = _record(n=801, span=400.0, period=40)
    k, x0 = np.array(TWO_TANKS_K), np.array([1.0, 1.0])
    exact = tanks.sensitivities(t, u, k, x0=x0, hold="zoh", rtol=1e-12, atol=1e-14)
    loose = tanks.sensitivities(t, u, k, x0=x0, hold="zoh", sensitivity_rtol=1e-6)
    np.testing.assert_allclose(loose.y, exact.y, rtol=1e-7)
    for name in ("dy_dk", "dy_dx0"):
        scale = np.max(np.abs(getattr(exact, name)))
        assert np.max(np.abs(getattr(loose, name) - getattr(exact, name))) < 1e-4 * scale
    with pytest.raises(ValueError, match="sensitivity_rtol must be"):
        tanks.sensitivities(t, u, k, x0=x0, sensitivity_rtol=-1.0)


def test_sensitivities_jump_where_a_discontinuous_relation_switches():
    """sign friction, the arm swinging without sticking: crossings of w = 0, each with
    the jump of the sensitivities that the crossing time's shift makes."""
    module = nonlinear_codegen.load(pendulum("sign"), values=dict(J=0.05, fc=0.1))
    t = np.linspace(0.0, 2.0, 101)
    u = 4.0 * np.cos(2 * np.pi * t)
    k, x0 = np.array(PENDULUM_K), np.array([0.0, 0.01, 0.0])
    tight = dict(hold="linear", rtol=1e-12, atol=1e-14)
    run = _agree_with_finite_differences(module, t, u, k, x0, tight, tolerance=1e-5)
    assert len(run.events) >= 4 and {event[1] for event in run.events} == {0}


def test_stiction_is_reported_not_smoothed():
    module = nonlinear_codegen.load(pendulum("sign"), values=dict(J=0.05, fc=0.1))
    t = np.linspace(0.0, 2.0, 201)
    with pytest.raises(module.SimulationError, match="sliding mode"):
        module.simulate(t, 0.05 * np.ones(t.size), x0=[0.0, 0.0, 0.0])


def test_a_tank_run_dry_is_held_empty(tanks):
    """(It was a SimulationError; it empties at 2 sqrt(0.5)/c1 = 2.828 and stays empty:
    tests/test_nonlinear_edges.py.)"""
    t = np.linspace(0.0, 100.0, 101)
    run = tanks.sensitivities(t, np.zeros(t.size), x0=[0.5, 0.5])
    assert np.all(run.x[t > 2.83, 0] == 0.0) and np.all(run.x[t < 2.82, 0] > 0.0)
    assert run.events[0][:2] == (pytest.approx(2 * math.sqrt(0.5) / 0.5, abs=1e-6), 0)


@pytest.mark.parametrize("signal", [_record, _multisine])
def test_rows_of_parameters_are_simulated_as_one_at_a_time(tanks, signal):
    """Many sets at once (one LSODA system of them all on long pieces, RODAS4 in arrays
    where the input changes at every sample) equal one set at a time, events included."""
    t, u = signal(n=101, span=100.0)
    k = np.array([TWO_TANKS_K, (0.6, 0.35, 1.1), (0.45, 0.5, 0.9), (0.5, 0.3, 1.2)])
    x0 = np.array([[1.0, 1.0], [2.0, 0.5], [3.5, 1.0], [1.0, 3.0]])
    together = tanks.simulate(t, u, k, x0=x0, hold="zoh", rtol=1e-10, atol=1e-12)
    assert together.shape == (4, t.size)
    for row in range(4):
        alone = tanks.simulate(t, u, k[row], x0=x0[row], hold="zoh", rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(together[row], alone, rtol=1e-8)
    run = tanks.sensitivities(t, u, k, x0=x0[0], hold="zoh")
    assert run.dy_dk.shape == (4, t.size, 3) and run.dx_dx0.shape == (4, t.size, 2, 2)


def test_many_sets_cross_the_overflow_each_at_its_own_time(tanks):
    """The stacked run keeps each set's overflow on its branch and runs a set found past
    the rim again from its crossing: every set as if simulated alone, crossings in both
    directions at times that differ from set to set."""
    t, u = _record(n=1201, span=600.0, period=200, seed=3)
    k = np.column_stack((np.linspace(0.42, 0.52, 8), np.full(8, 0.4), np.linspace(1.1, 1.0, 8)))
    x0 = np.array([1.0, 1.0])
    together = tanks.simulate(t, u, k, x0=x0, hold="zoh", rtol=1e-10, atol=1e-12)
    levels = []
    for row in range(8):
        alone = tanks.sensitivities(t, u, k[row], x0=x0, hold="zoh", rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(together[row], alone.y, rtol=0, atol=1e-8 * alone.y.max())
        levels.append(alone.x[:, 0])
    over = np.array(levels) > 3.0
    assert (np.diff(over.astype(int), axis=1) == 1).any(axis=1).all()  # each set overflows
    assert (np.diff(over.astype(int), axis=1) == -1).any(axis=1).all()  # and stops
    assert len({int(np.argmax(row)) for row in over}) > 4  # at times of its own


def test_pendulum_sets_started_in_step_stop_together_and_as_if_alone(arm, monkeypatch):
    """After each switch of the voltage every arm stops and turns, each at its own time,
    where tanh(50 w) turns within a millisecond; the batch starts the sets' shares of the
    run so that those moments fall on one sample (a pilot finds them): every set as if
    simulated alone, and the sets were started apart."""
    t = np.linspace(0.0, 20.0, 2001)
    u = 3.0 * np.where((np.arange(t.size) // 250) % 2, -1.0, 1.0)
    k = np.column_stack((np.linspace(0.04, 0.06, 8), np.linspace(0.12, 0.08, 8)))
    shifted = []
    pilot = arm._shifts

    def watched(*arguments):
        shifts, reach = pilot(*arguments)
        shifted.append(0 if shifts is None else int(shifts.max()))
        return shifts, reach

    monkeypatch.setattr(arm, "_shifts", watched)
    together = arm.simulate(t, u, k, hold="zoh", rtol=1e-9, atol=1e-11)
    assert max(shifted, default=0) >= 2  # the sets' stops were samples apart, and brought in step
    for row in range(8):
        alone = arm.simulate(t, u, k[row], hold="zoh", rtol=1e-11, atol=1e-13)
        np.testing.assert_allclose(together[row], alone, rtol=0, atol=1e-8 * np.abs(alone).max())


def test_kernels_equal_sympys_evaluation_of_the_equations(tanks, arm):
    rng = np.random.default_rng(1)
    for module, system, k in ((tanks, two_tanks(), TWO_TANKS_K), (arm, pendulum(), PENDULUM_K)):
        x_, u_, k_ = list(system.states), system.input, list(system.unknowns)
        f = sympy.lambdify([x_, u_, k_], list(system.f), "math")
        g = sympy.lambdify([x_, u_, k_], list(system.g), "math")
        jac = sympy.lambdify(
            [x_, u_, k_], [system.f.jacobian(x_).tolist(), system.f.jacobian(k_).tolist()], "math"
        )
        for _ in range(5):
            x = rng.uniform(0.5, 4.0, len(x_))
            u = rng.uniform(0, 2)
            np.testing.assert_allclose(module.rhs(x, u, k), np.ravel(f(x, u, k)), rtol=1e-14)
            np.testing.assert_allclose(module.output(x, u, k), np.ravel(g(x, u, k)), rtol=1e-14)
            d = module.jacobians(x, u, k)
            f_x, f_k = jac(x, u, k)
            np.testing.assert_allclose(d.f_x, np.array(f_x, dtype=float), rtol=1e-13, atol=1e-15)
            np.testing.assert_allclose(d.f_k, np.array(f_k, dtype=float), rtol=1e-13, atol=1e-15)
        points = rng.uniform(0.5, 4.0, (7, len(x_)))  # vectorised over a leading axis
        batch = module.rhs(points, 1.0, k)
        assert batch.shape == (7, len(x_))
        np.testing.assert_allclose(batch[3], module.rhs(points[3], 1.0, k), rtol=1e-15)


def test_second_derivative_kernel_is_the_derivative_of_the_jacobian(tanks):
    """`second` (for the batch integrator's sensitivities): d(f_x) and d(f_k) along a
    direction in (x, u), against central differences of the Jacobians."""
    x, u, k, v, du = np.array([2.0, 1.5]), 0.7, TWO_TANKS_K, np.array([0.3, -0.2]), 0.5
    arguments = (*x, u, *k)
    modes = tanks._FLOAT.modes(*arguments)
    d = np.array(tanks._FLOAT.second(*arguments, *modes, *v, du))
    h = 1e-6
    up = tanks.jacobians(x + h * v, u + h * du, k)
    down = tanks.jacobians(x - h * v, u - h * du, k)
    expected = np.concatenate(
        [((up.f_x - down.f_x) / (2 * h)).ravel(), ((up.f_k - down.f_k) / (2 * h)).ravel()]
    )
    np.testing.assert_allclose(d, expected, rtol=1e-7, atol=1e-9)


def test_the_rosenbrock_step_is_of_order_four(tanks):
    """RODAS4 on the tanks with an input ramp (the time derivative term): halving the step
    divides the error after a fixed time by 2^4."""

    def run(steps: int) -> np.ndarray:
        x, h = [2.0, 1.0], 4.0 / steps
        for i in range(steps):
            x = list(tanks._FLOAT.rosenbrock(*x, 0.5 + 0.1 * i * h, *TWO_TANKS_K, 0.1, h)[:2])
        return np.array(x)

    exact = run(2048)
    errors = [np.max(np.abs(run(steps) - exact)) for steps in (4, 8, 16)]
    assert errors[0] / errors[1] == pytest.approx(16, rel=0.15)
    assert errors[1] / errors[2] == pytest.approx(16, rel=0.15)


def test_generation_is_deterministic_and_splices_no_model_text():
    system = two_tanks()
    tricky = 'a """ docstring end\n and "quotes"'
    first = nonlinear_codegen.render(system, values=TANKS_VALUES, description=tricky)
    again = nonlinear_codegen.render(two_tanks(), values=TANKS_VALUES, description=tricky)
    assert first == again
    assert tricky not in first and repr(tricky) in first
    compile(first, "two_tanks.py", "exec")


def _renamed(system: NonlinearStateSpace, **changes) -> NonlinearStateSpace:
    fields = {name: getattr(system, name) for name in system.__dataclass_fields__}
    return NonlinearStateSpace(**(fields | changes))


@pytest.mark.parametrize(
    ("changes", "kind"),
    [
        ({"name": "two tanks"}, "bad_name"),
        ({"name": "json"}, "reserved_name"),
        ({"f": sympy.Matrix([sympy.Symbol("rtol"), 0])}, "reserved_name"),
        ({"g": sympy.Matrix([sympy.gamma(sympy.Symbol("q1"))])}, "unsupported_relation"),
    ],
)
def test_what_the_module_cannot_carry_is_a_model_error(changes, kind):
    with pytest.raises(ModelError) as caught:
        nonlinear_codegen.render(_renamed(two_tanks(), **changes))
    assert caught.value.diagnostics[0].kind == kind


def test_arguments_are_checked(tanks):
    t, u = _record(n=11, span=10.0, period=5)
    with pytest.raises(ValueError, match="hold must be one of"):
        tanks.simulate(t, u, hold="cubic")
    with pytest.raises(ValueError, match="k must give the 3 unknowns"):
        tanks.simulate(t, u, [0.5, 0.4])
    with pytest.raises(ValueError, match="x0 must end in an axis of the 2 values q1, q2"):
        tanks.simulate(t, u, x0=[1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="the same number of rows"):
        tanks.simulate(t, u, np.ones((3, 3)), x0=np.ones((2, 2)))
    with pytest.raises(ValueError, match="unexpected parameter"):
        tanks.simulate(t, u, area=2.0)


def test_mtt_compile_writes_the_simulator_of_a_nonlinear_model(tmp_path, capsys):
    """Without --at a nonlinear model compiles to its simulator, which runs as a user
    imports it (a file, numpy and scipy only); with --at, to its small-signal estimator."""
    import importlib.util
    import json

    from mtt.cli.main import main

    root = Path(__file__).resolve().parent.parent
    target = tmp_path / "two_tanks.py"
    assert (
        main(["compile", str(root / "models" / "two_tanks.bg"), "-o", str(target), "--json"]) == 0
    )
    written = json.loads(capsys.readouterr().out)
    assert written["kind"] == "simulator" and written["unknowns"] == ["a1", "a2"]
    spec = importlib.util.spec_from_file_location("two_tanks", target)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert "import mtt" not in target.read_text() and module.TRUE_VALUE == (2.0, 2.5)
    t = np.linspace(0.0, 600.0, 601)
    api = mtt.load(root / "models" / "two_tanks.bg")
    expected = api.simulator().simulate(t, np.full(t.size, 10.0), x0=[1000.0, 1000.0])
    assert np.array_equal(module.simulate(t, np.full(t.size, 10.0), x0=[1000.0, 1000.0]), expected)
    (tmp_path / "api").mkdir()
    assert api.compile(tmp_path / "api").name == "two_tanks.py"
    assert "Simulate the nonlinear model" in (tmp_path / "api" / "two_tanks.py").read_text()
    linear = tmp_path / "small.py"
    args = ["compile", str(root / "models" / "two_tanks.bg"), "--at", "u=10", "-o", str(linear)]
    assert main(args) == 0
    assert linear.read_text().startswith('"""Identify the unknown parameters a1, a2')


def test_mtt_simulate_runs_a_nonlinear_model_by_its_simulator(capsys):
    """Without --at, `mtt simulate` gives the nonlinear model's own response (from rest):
    here the tanks filled by a constant pump, against solve_ivp on the equations written
    by hand (below the rim: no overflow)."""
    import json

    from mtt.cli.main import main

    model = Path(__file__).resolve().parent.parent / "models" / "two_tanks.bg"
    argv = ["simulate", str(model), "--signal", "step", "--amplitude", "10", "--t-end", "600"]
    assert main([*argv, "--dt", "50", "--json"]) == 0
    run = json.loads(capsys.readouterr().out)
    t, u, y = (np.array(run[name]) for name in ("t", "u", "y"))
    assert np.all(u[1:] == 10.0)

    def tanks(_, q):
        upper = 2.0 * math.sqrt(max(q[0], 0.0) / 50)
        return [10.0 - upper, upper - 2.5 * math.sqrt(max(q[1], 0.0) / 40)]

    hand = solve_ivp(tanks, (0.0, 600.0), [0.0, 0.0], t_eval=t, rtol=1e-10, atol=1e-10)
    assert np.allclose(y, hand.y[1] / 40, rtol=1e-6, atol=1e-8)
    assert 10 < y[-1] < 16  # filling towards the steady level (10 / 2.5)^2 = 16


def test_a_steady_state_beyond_newtons_reach_is_found_by_continuation_in_the_input():
    """The diode clipper at 2 V: from rest, Newton's steps overshoot into exp(77); stepping
    the input up from 0 reaches the diode's forward drop, where is (exp(v/vt) - 1) carries
    the current (2 - v)/r."""
    clipper = mtt.load(mtt.example("diode_clipper")).simulator()
    q = clipper.steady_state(2.0)
    v = q[0] / 1e-7
    assert (2.0 - v) / 1000.0 == pytest.approx(1e-12 * math.expm1(v / 0.026), rel=1e-9)
    assert 0.5 < v < 0.6


def test_tanks_at_rest_are_simulated_from_sample_to_sample(capsys):
    """A tank at rest (the most common start) sits where the orifice's sqrt has an infinite
    derivative: the Rosenbrock steps of a short record cannot start there, an explicit
    step with positive weights takes the levels off zero. The command of the bug report
    (5 samples: RODAS4 alone), and rows of parameters, against solve_ivp by hand."""
    import json

    from mtt.cli.main import main

    model = Path(__file__).resolve().parent.parent / "models" / "two_tanks.bg"
    assert main(["simulate", str(model), "--t-end", "2", "--dt", "0.5", "--json"]) == 0
    run = json.loads(capsys.readouterr().out)
    t, u, y = (np.array(run[name]) for name in ("t", "u", "y"))
    assert t.size == 5 and np.all(u == u[0]) and u[0] > 0

    def hand(a1, a2):
        def tanks(_, q):
            upper = a1 * math.sqrt(max(q[0], 0.0) / 50)
            return [u[0] - upper, upper - a2 * math.sqrt(max(q[1], 0.0) / 40)]

        exact = solve_ivp(tanks, (0.0, 2.0), [0.0, 0.0], t_eval=t, method="DOP853",
                          rtol=1e-13, atol=1e-16)  # fmt: skip
        return exact.y[1] / 40

    assert np.allclose(y, hand(2.0, 2.5), rtol=1e-7, atol=0) and y[-1] > 0
    simulator = mtt.load(model).simulator()
    rows = simulator.simulate(t, u, k=[[2.0, 2.5], [1.5, 3.0]], rtol=1e-11, atol=1e-14)
    for row, k in zip(rows, ([2.0, 2.5], [1.5, 3.0]), strict=True):
        exact = hand(*k)
        assert np.max(np.abs(row - exact)) <= 1e-9 * np.max(exact)


def test_a_model_without_unknowns_simulates_and_refuses_a_fit():
    """tests/data/nonlinear/lever.bg declares no unknown: its module still simulates, with
    sensitivities to the initial state alone (sympy's jacobian refuses an empty list of
    unknowns, and the kernels once unpacked none into an empty target), and its fit says
    there is nothing to fit."""
    lever = nonlinear_codegen.load(nonlinear_state_space(DATA / "lever.bg"), values={})
    assert lever.UNKNOWNS == () and lever.STATES == ("p_mass", "q_a")
    t = np.linspace(0.0, 2.0, 81)
    u = np.where(t < 1.0, 1.0, 0.5)

    def rhs(time, x):  # p' = u / n, q' = p / 3 / n, n = 2 cos(q): the lever's ratio
        ratio = 2.0 * math.cos(x[1])
        return [(1.0 if time < 1.0 else 0.5) / ratio, x[0] / 3.0 / ratio]

    states, _ = _reference(rhs, t, [0.0, 0.0])
    run = lever.sensitivities(t, u, hold="zoh", rtol=1e-10, atol=1e-12)
    assert np.max(np.abs(run.x - states)) < 1e-8 * np.max(np.abs(states))
    assert np.allclose(lever.simulate(t, u, hold="zoh"), states[:, 0] / 3.0, rtol=1e-7, atol=1e-9)
    assert run.dy_dk.shape == (t.size, 0) and run.dx_dx0.shape == (t.size, 2, 2)
    with pytest.raises(ValueError, match="declares no unknown parameter: nothing to fit"):
        lever.fit(t, u, run.y)
