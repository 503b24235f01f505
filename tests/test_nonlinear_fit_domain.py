"""The nonlinear fit keeps each record's estimated initial state inside the model's domain
(issue 20's leftover): a trial point whose initial state the model cannot evaluate (a
level below zero under a square root) is pulled back toward the accepted point instead of
failing to simulate, which would double the damping at each failure. Records made
independently by solve_ivp (tests/nonlinear_records.py)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import sympy
from nonlinear_records import held, noisy, pump, weir_rhs

import mtt
from mtt.derivation.nonlinear import NonlinearStateSpace
from mtt.estimator import nonlinear_codegen

TRUE = (2.0, 2.5)


@pytest.fixture(scope="module")
def tanks():
    return mtt.load(mtt.example("two_tanks")).simulator()


def _counted(module, monkeypatch) -> dict:
    """Count the fit's simulations and those that fail."""
    calls = {"simulations": 0, "failed": 0, "below zero": 0}
    simulated = module._simulated

    def counted(t, u, k, x0, *rest):
        calls["simulations"] += 1
        calls["below zero"] += int(np.any(np.asarray(x0) < 0))
        try:
            return simulated(t, u, k, x0, *rest)
        except module.SimulationError:
            calls["failed"] += 1
            raise

    monkeypatch.setattr(module, "_simulated", counted)
    return calls


def test_a_record_from_empty_tanks_is_fitted_with_no_trial_outside_the_domain(tanks, monkeypatch):
    """Two tanks filling from empty, their initial state estimated: the descent's steps
    toward negative levels are pulled back inside, every trial simulates, and the fit
    reaches the truth (before: 1.88, 2.55 with an initial upper level of 1082, 5 s)."""
    t = np.arange(301) * 5.0
    u = pump(t, 2.0, 14.0, 20, seed=3)
    y = noisy(held(weir_rhs(TRUE), t, u, [0.0, 0.0])[:, 1] / 40, 20, seed=1)
    calls = _counted(tanks, monkeypatch)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        found = tanks.fit(t, u, y, k0=[1.5, 3.0], hold="zoh", multistart=0)
    assert calls["failed"] == 0 and calls["below zero"] == 0, calls
    assert found.ok, found.message
    assert np.all(np.abs(found.k - TRUE) < 4 * found.k_se), (found.k, found.k_se)
    assert np.all(found.states[0] >= 0)


def test_a_step_out_of_the_domain_is_pulled_back_part_of_the_way(tanks):
    """within_domain: a step taking the lower level below zero ends DOMAIN_SHARE of the way
    to where the level is zero; a step inside is left alone."""
    t = np.arange(50) * 5.0
    u = np.full(t.size, 8.0)
    problem = tanks._Problem([(t, u, np.zeros(t.size))], "zoh", {}, (1e-9, 1e-12), True, True,
                             np.zeros((1, 2)))  # fmt: skip
    theta = problem.pack(np.array(TRUE), [[200.0, 100.0]], [0.0])
    inside = problem.pack(np.array(TRUE), [[150.0, 50.0]], [0.1])
    kept, pulled = problem.within_domain(theta, inside)
    assert not pulled and np.array_equal(kept, inside)
    outside = problem.pack(np.array(TRUE), [[100.0, -100.0]], [0.1])
    moved, pulled = problem.within_domain(theta, outside)
    edge = 0.5  # the step's share at which the lower level reaches zero
    assert pulled
    expected = theta + tanks.DOMAIN_SHARE * edge * (outside - theta)
    np.testing.assert_allclose(moved, expected, atol=2**-tanks.DOMAIN_BISECTIONS * 200)
    assert problem.evaluable(moved) and not problem.evaluable(outside)


def test_an_unknown_bounded_on_one_side_moves_toward_its_bound():
    """bounds=(0, inf): the descent held an unknown bounded on one side whenever its steps
    pointed toward the bound (an infinite box width made every point count as at the
    bound), so a start at 3 for the truth 1 stayed at 3 and the model file's start stopped
    14 standard errors short, both reported as minima."""
    q, u, y, a = sympy.symbols("q u y a")
    f = sympy.Matrix([u - a * sympy.sqrt(q)])
    system = NonlinearStateSpace("tank", (q,), u, y, (a,), {}, f, sympy.Matrix([q]))
    tank = nonlinear_codegen.load(system, values={"a": 1.0})
    t = np.linspace(0.0, 50.0, 201)
    pumped = np.where((t // 5) % 2 == 0, 1.0, 2.0)
    level = tank.simulate(t, pumped, 1.0, x0=[1.0], hold="zoh")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        found = tank.fit(t, pumped, level, k0=3.0, bounds=(0.0, np.inf), hold="zoh",
                         multistart=0, profile=None)  # fmt: skip
    assert found.ok, found.message
    for _, _, reached in found.starts:
        assert reached[0] == pytest.approx(1.0, rel=1e-9)
