"""The generated estimator's algorithm, checked against independent computations.

The modules under test are the committed ones in generated/ (test_codegen checks that they
are what mtt generates today), imported as a user imports them.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from estimators import exact_cost, step
from scipy import signal


@pytest.mark.parametrize("name", ["dc_drive", "absorber"])
def test_J_i_are_the_derivatives_of_the_exact_cost_and_khat_is_stationary(
    name, dc_drive, absorber, noisy_absorber
):
    module = {"dc_drive": dc_drive, "absorber": absorber}[name]
    if name == "absorber":
        t, u, y = noisy_absorber
        k0 = 1.0
    else:
        t, u = step(6.0)
        y = dc_drive.simulate(t, u, 10.0)
        k0 = 5.0
    settings = dict(k0=k0, beta=0.1, S0=1e-4, C=None)
    result = module.estimate(t, u, y, **settings, rtol=1e-9, atol=1e-12)
    assert result.ok
    for upto in (t.size // 3, t.size - 1):  # during the transient and at the end
        cost = exact_cost(module, t, u, y, **settings, upto=upto)
        khat = result.khat[upto]
        J = [cost.deriv(i)(khat) for i in range(1, 2 * module.N + 1)]
        np.testing.assert_allclose(result.J[:, upto], J[1:], rtol=2e-5)
        assert abs(J[0] / J[1]) < 1e-6  # J_1 = 0: a Newton step from khat goes nowhere


def test_dc_drive_converges_from_the_papers_three_starting_values(dc_drive):
    t, u = step(10.0)
    y = dc_drive.simulate(t, u, 10.0)
    for k0 in (0.0, 5.0, 20.0):
        result = dc_drive.estimate(t, u, y, k0=k0, beta=0.1, S0=1e-4, C=[1, 5, 10, 10, 5, 1])
        assert result.ok and abs(result.k - 10.0) < 0.1, (k0, result.k)
        assert result.minima() == pytest.approx([result.k])


def test_absorber_local_minima_and_cost(absorber, noisy_absorber):
    result = absorber.estimate(*noisy_absorber, k0=1.0)
    minima = result.minima()
    assert minima == pytest.approx([-0.23, 0.72], abs=0.03)
    # every local minimum of the polynomial, as a dense grid sees it
    k = np.linspace(-2.0, 2.0, 40001)
    J = result.cost(k)
    grid = k[1:-1][(J[1:-1] < J[:-2]) & (J[1:-1] < J[2:])]
    assert grid == pytest.approx(minima, abs=1e-3)
    assert result.cost(result.k) == pytest.approx(0.0, abs=1e-15)
    assert result.cost(np.array([[0.0, 0.5]])).shape == (1, 2)
    assert np.all(J >= -1e-15)  # k^ is the global minimum


def test_one_polynomials_minima_are_the_rows_bit_for_bit(absorber):
    """The fit's criterion (one row) is minimised in Python's arithmetic (`_global_minimiser`,
    `_polished`), blocks of rows in numpy's (`_global_minimisers`, `_polish`): the same
    floats, on polynomials of every kind (lower degree, constant, multiple roots, huge)."""
    rng = np.random.default_rng(7)
    found = 0
    for trial in range(3000):
        width = int(rng.integers(2, 10))
        A = rng.standard_normal(width) * 10 ** rng.uniform(-3, 3, width)
        if trial % 5 == 1:
            A[-int(rng.integers(1, width)) :] = 0.0
        elif trial % 5 == 2:
            A = np.poly1d(np.repeat(rng.standard_normal(1), width - 1), r=True).coeffs[::-1] * 1.0
        elif trial % 5 == 3:
            A = np.round(A) * 10.0 ** (150 * (trial % 2))
        bounds = [(-math.inf, math.inf), (-1.0, 1.0), (0.0, math.inf), (-math.inf, 0.5)][trial % 4]
        centre = [0.0, float(rng.standard_normal())][trial % 2]
        rows = np.stack([A, rng.standard_normal(width)])
        with np.errstate(all="ignore"):  # (the huge ones overflow)
            expected = absorber._global_minimisers(rows, np.array([centre, 0.0]), bounds)[0]
        got = absorber._global_minimiser(A, centre, bounds)
        assert np.array_equal(np.float64(got).view(np.int64), expected.view(np.int64)), trial
        found += math.isfinite(got)
        D = A[None, 1:] * np.arange(1, width)
        roots = absorber._companion_roots(D)
        roots = roots.real[:, np.isfinite(roots[0])]
        with np.errstate(all="ignore"):
            polished = absorber._polish(D, roots)[0]
        assert [
            absorber._polished(D[0].tolist(), x) for x in roots[0].tolist()
        ] == polished.tolist()
    assert 1000 < found < 2900


@pytest.mark.parametrize("hold,interp", [("linear", True), ("zoh", False)])
def test_simulate_is_exact_for_its_hold(dc_drive, hold, interp):
    t = np.linspace(0.0, 5.0, 251)
    u = np.sin(3 * t) + (t > 1.0)
    expected = signal.lsim(dc_drive.transfer_function(10.0), u, t, interp=interp)[1]
    assert dc_drive.simulate(t, u, 10.0, hold=hold) == pytest.approx(expected, abs=1e-12)
    # irregular sampling: the same piecewise-linear input seen on a subset of the samples
    keep = np.r_[0, np.sort(np.random.default_rng(1).choice(np.arange(1, 250), 80, False)), 250]
    coarse = dc_drive.simulate(t[keep], u[keep], 10.0)
    fine = dc_drive.simulate(t, np.interp(t, t[keep], u[keep]), 10.0)
    assert coarse == pytest.approx(fine[keep], abs=1e-12)


def test_transfer_function_is_theta_times_powers_of_k(absorber):
    num, den = absorber.transfer_function(0.72, tau=2.0, l=0.5)
    k = 0.72
    assert num == pytest.approx([k**3])
    expected = [4, 6 * (1 + k), 3 + 4 * k + 3 * k**2, 0.5 * (1 + k + k**2 + k**3)]
    assert den == pytest.approx(expected)
    assert absorber.theta(tau=1.0, l=1.0)[1] == pytest.approx([3, 4, 3, 0])


def test_zero_order_hold_and_other_solvers(dc_drive):
    t, u = step(10.0, dt=0.05)
    u = np.where(t < 5.0, 1.0, -1.0)
    y = dc_drive.simulate(t, u, 10.0, hold="zoh")
    zoh = dc_drive.estimate(t, u, y, k0=5.0, hold="zoh")
    assert zoh.ok and abs(zoh.k - 10.0) < 0.01
    # the same ODE, whichever solver: agreement to the tolerance asked for
    tight = dict(k0=5.0, hold="zoh", rtol=1e-9, atol=1e-12, engine="ode")
    rk23, rk45 = (dc_drive.estimate(t, u, y, method=m, **tight) for m in ("RK23", "RK45"))
    assert rk45.k == pytest.approx(rk23.k, abs=1e-6)
    assert zoh.k == pytest.approx(rk23.k, abs=1e-5)


def test_progress_reports_the_time_reached(dc_drive):
    t, u = step(2.0)
    times = []
    dc_drive.estimate(t, u, dc_drive.simulate(t, u, 10.0), k0=5.0, progress=times.append)
    assert times == sorted(times) and times[-1] == 2.0


def test_a_run_that_leaves_the_convex_region_stops_and_says_where(absorber):
    t, u = step(4.0)
    y = absorber.simulate(t, u, 0.72)
    result = absorber.estimate(t, u, y, k0=0.2)  # the cost is concave there for a while
    assert not result.ok
    assert "J_2 reached zero" in result.message
    assert 0 < result.stopped_at < 4.0
    assert f"t = {result.stopped_at:.6g}" in result.message
    assert result.t[-1] < result.stopped_at and result.t.size < t.size
    assert np.all(np.isfinite(result.khat)) and np.all(result.J[0] > 0)
    assert math.isfinite(result.k)


BAD_INPUTS = [
    (dict(y=[0.0, np.nan, 0.0]), r"y\[1\] is nan: every value must be finite"),
    (dict(u=[0.0, np.inf, 0.0]), r"u\[1\] is inf"),
    (dict(y=[0.0, 0.0]), r"must have the same length, not \[3, 3, 2\]"),
    (dict(t=[0.0, 1.0, 1.0]), r"strictly increasing: t\[2\] = 1.0 follows t\[1\] = 1.0"),
    (dict(t=[0.0], u=[1.0], y=[0.0]), r"need at least 2 samples, not 1"),
    (dict(y=[[0.0, 0.0, 0.0]]), r"one-dimensional"),
    (dict(y=[0j, 1j, 0j]), r"must be real"),
    (dict(y=["a", "b", "c"]), r"array of real numbers"),
    (dict(C=[1.0, -1.0, 1.0, 1.0, 1.0, 1.0]), r"C\(s\) is not stable: it has a root at s ="),
    (dict(C=[1.0, 4.0, 6.0, 4.0, 1.0]), r"C\(s\) has degree 4; it must exceed .* \(n = 4, m = 2\)"),
    (dict(C=-2.0), r"the filter time constant T must be > 0"),
    (dict(S0=0.0), r"S0 must be > 0, not 0.0"),
    (dict(S0=-1e-4), r"S0 must be > 0"),
    (dict(beta=-0.1), r"beta must be >= 0, not -0.1"),
    (dict(k0=math.nan), r"k0 must be finite"),
    (dict(k0="x"), r"k0 must be a real number"),
    (dict(rtol=0.0), r"rtol must be > 0"),
    (dict(hold="cubic"), r"hold must be one of 'linear', 'zoh', not 'cubic'"),
    (dict(method="LSODA"), r"method must be one of 'RK23', 'RK45', 'DOP853'"),
    (dict(tau=2.0), r"unexpected parameter 'tau' .*: none"),
]


@pytest.mark.parametrize("change,message", BAD_INPUTS)
def test_bad_input_is_a_clear_value_error(dc_drive, change, message):
    arguments = dict(t=[0.0, 1.0, 2.0], u=[1.0, 1.0, 1.0], y=[0.0, 0.1, 0.2], k0=1.0)
    arguments.update(change)
    with pytest.raises(ValueError, match=message):
        dc_drive.estimate(**arguments)


def test_bad_input_to_the_other_functions(dc_drive, absorber):
    with pytest.raises(ValueError, match=r"t must be strictly increasing"):
        dc_drive.simulate([0.0, 2.0, 1.0], [1.0, 1.0, 1.0], 10.0)
    with pytest.raises(ValueError, match=r"k must be finite"):
        dc_drive.transfer_function(math.inf)
    with pytest.raises(ValueError, match=r"tau must be finite"):
        absorber.theta(tau=math.nan)
    with pytest.raises(ValueError, match=r"unexpected parameter 'L'.*: tau, l"):
        absorber.simulate([0.0, 1.0], [1.0, 1.0], 0.72, L=0.5)


def test_the_template_defines_each_module_level_name_once():
    """The algorithm's pieces are one module: a name defined twice would silently replace
    the first definition for every function that uses it."""
    import ast
    from pathlib import Path

    source = (Path(__file__).resolve().parent.parent / "generated" / "dc_drive.py").read_text()
    names = []
    for node in ast.parse(source).body:
        if isinstance(node, ast.FunctionDef | ast.ClassDef):
            names.append(node.name)
        elif isinstance(node, ast.Assign):
            names += [target.id for target in node.targets if isinstance(target, ast.Name)]
    assert sorted({name for name in names if names.count(name) > 1}) == []


def test_a_prior_that_outweighs_the_data_is_a_warning_and_prior_weight_sets_a_relative_one(
    dc_drive,
):
    """A slow filter, T = 10: the paper's S0 = 1e-4 outweighs the data (the estimate stays
    near k0, with a warning); S0 relative to the data recovers 10."""
    t, u = step(10.0)
    y = dc_drive.simulate(t, u, 10.0)
    with pytest.warns(dc_drive.EstimationWarning, match="the data carry little information"):
        held = dc_drive.estimate(t, u, y, k0=5.0, C=10.0)
    assert held.k < 6.0 and held.warnings
    S0 = dc_drive.prior_weight(t, u, y, k0=5.0, C=10.0)
    assert 1e-12 < S0 < 1e-9
    freed = dc_drive.estimate(t, u, y, k0=5.0, C=10.0, S0=S0)
    assert freed.k == pytest.approx(10.0, rel=1e-4) and freed.warnings == ()
    for t_, u_, y_ in ((t, 0 * u, 0 * y), (t[:3], u[:3], y[:3]), (t * 1e-300, u, y)):
        with pytest.warns(dc_drive.EstimationWarning, match="the data carry little information"):
            assert dc_drive.estimate(t_, u_, y_, k0=5.0).k == pytest.approx(5.0, rel=1e-6)
    with pytest.raises(ValueError, match="no information about k at k0 = 5: no relative S0"):
        dc_drive.prior_weight(t, 0 * u, 0 * y, k0=5.0)


def test_the_denominator_is_trim_zeros_slices(absorber):
    """`_denominator` trims A(s, k)'s zeros as np.trim_zeros does (leading ones; then the
    trailing ones too), NaN and infinite coefficients kept."""
    rng = np.random.default_rng(8)
    rows = absorber.n + 1
    for trial in range(500):
        Theta = rng.standard_normal((rows + absorber.m + 1, absorber.N + 1))
        zeros = rng.choice(rows, int(rng.integers(0, rows + 1)), replace=False)
        Theta[zeros] = 0.0
        if trial % 7 == 0:
            Theta[int(rng.integers(rows)), 0] = [math.nan, math.inf][trial % 2]
        A = (Theta @ absorber._K(0.72))[absorber.n :: -1]
        front, both = absorber._denominator(Theta, 0.72)
        assert np.array_equal(front, np.trim_zeros(A, "f"), equal_nan=True)
        assert np.array_equal(both, np.trim_zeros(A), equal_nan=True)
