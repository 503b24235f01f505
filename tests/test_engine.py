"""The exact-moment engine of the generated estimators, against independent computations:
exact arithmetic (mpmath), scipy's simulations, the paper's ODE, and the cost from its
definition."""

from __future__ import annotations

import math
import pickle

import mpmath
import numpy as np
import pytest
from estimators import exact_cost, step
from scipy import signal

PAPER = dict(beta=0.1, S0=1e-4)


def exact_filter_states(c, t, w, hold: str) -> np.ndarray:
    """s^i w / C(s) at the sample times, in 40-digit arithmetic: the state of 1/C(s) and
    the input's level and slope over each interval, propagated by mpmath's exponential."""
    mpmath.mp.dps = 40
    order = len(c) - 1
    c = [mpmath.mpf(float(value)) for value in c]
    F = mpmath.zeros(order + 2, order + 2)
    for i in range(order - 1):
        F[i, i + 1] = 1
    for j in range(order):
        F[order - 1, j] = -c[order - j] / c[0]
    F[order - 1, order] = 1 / c[0]
    F[order, order + 1] = 1  # level' = slope
    x = mpmath.zeros(order + 2, 1)
    states = [np.zeros(order)]
    exponentials = {}
    for i in range(len(t) - 1):
        h = mpmath.mpf(float(t[i + 1])) - mpmath.mpf(float(t[i]))
        if h not in exponentials:
            exponentials[h] = mpmath.expm(F * h)
        x[order] = mpmath.mpf(float(w[i]))
        x[order + 1] = 0 if hold == "zoh" else (mpmath.mpf(float(w[i + 1])) - x[order]) / h
        x = exponentials[h] * x
        states.append(np.array([float(x[j]) for j in range(order)]))
    return np.array(states)


@pytest.mark.parametrize("dt", [2.0**-10, 2.0**-7])  # about 1e-3 and 1e-2, exact in binary
@pytest.mark.parametrize("T", [0.05, 1.0, 10.0])
def test_filter_states_are_exact_at_fine_sampling(dc_drive, T, dt):
    """Where transfer functions in z lose every digit ((1 + sT)^5 at dt = 1e-3, T = 10
    puts a 5-fold pole 1e-4 from z = 1), the states keep 12 digits."""
    t = dt * np.arange(301)
    w = np.sin(7 * t / (300 * dt)) + (t > 100 * dt)
    for hold in ("linear", "zoh"):
        states = dc_drive.filter_states(t, w, C=T, hold=hold)
        exact = exact_filter_states(dc_drive.filter_polynomial(T), t, w, hold)
        error = np.abs(states - exact).max(0) / np.abs(exact).max(0)  # of each state
        assert error.max() < 1e-12, (hold, error)


def test_long_and_irregular_records(dc_drive):
    """Across the chunks of work (2^15 samples) and on an irregular grid, as scipy's lsim."""
    t = 0.002 * np.arange(2 * dc_drive.BLOCK + 1235)
    u = np.sign(np.sin(t / 3.0)) + 0.3 * np.sin(5.0 * t)
    y = dc_drive.simulate(t, u, 10.0)
    expected = signal.lsim(dc_drive.transfer_function(10.0), u, t, interp=True)[1]
    np.testing.assert_allclose(y, expected, rtol=0, atol=1e-11 * np.abs(expected).max())
    # an irregular subset of the grid sees the same piecewise-linear input
    rng = np.random.default_rng(3)
    keep = np.r_[0, np.sort(rng.choice(np.arange(1, t.size - 1), 3000, False)), t.size - 1]
    coarse = u[keep]
    expected = signal.lsim(dc_drive.transfer_function(10.0), np.interp(t, t[keep], coarse), t)
    y = dc_drive.simulate(t[keep], coarse, 10.0)
    scale = np.abs(expected[1]).max()
    np.testing.assert_allclose(y, expected[1][keep], rtol=0, atol=1e-11 * scale)


def assert_same_trajectory(moments, ode):
    """The two engines' k^ agree to 1e-5 relative at every sample (relative to the
    trajectory's size where it crosses zero)."""
    assert moments.ok and ode.ok
    np.testing.assert_array_equal(moments.t, ode.t)
    scale = np.abs(ode.khat).max()
    np.testing.assert_allclose(moments.khat, ode.khat, rtol=1e-5, atol=1e-5 * scale)
    size = np.abs(ode.J).max(1, keepdims=True)  # the ODE's J_i are accurate to its atol
    assert np.all(np.abs(moments.J - ode.J) <= 1e-4 * np.abs(ode.J) + 1e-6 * size)


@pytest.mark.parametrize("k0", [0.0, 5.0, 20.0])
def test_moments_engine_follows_the_papers_ode_dc_drive(dc_drive, k0):
    t, u = step(10.0)
    y = dc_drive.simulate(t, u, 10.0)
    C = [1, 5, 10, 10, 5, 1]
    moments = dc_drive.estimate(t, u, y, k0=k0, C=C, **PAPER)
    ode = dc_drive.estimate(t, u, y, k0=k0, C=C, **PAPER, engine="ode", rtol=1e-8, atol=1e-11)
    assert_same_trajectory(moments, ode)


@pytest.mark.parametrize(
    "k0,T", [(0.0, 1.0), (0.25, 1.0), (0.5, 1.0), (0.75, 1.0), (1.0, 1.0), (1.0, 0.5), (1.0, 2.0)]
)
def test_moments_engine_follows_the_papers_ode_absorber(absorber, noisy_absorber, k0, T):
    moments = absorber.estimate(*noisy_absorber, k0=k0, C=T, **PAPER)
    ode = absorber.estimate(
        *noisy_absorber, k0=k0, C=T, **PAPER, engine="ode", rtol=1e-7, atol=1e-10
    )
    assert_same_trajectory(moments, ode)


def test_irregular_sampling_and_zero_order_hold_follow_the_ode(dc_drive):
    rng = np.random.default_rng(5)
    t = np.sort(np.r_[0.0, rng.uniform(0.0, 8.0, 400), 8.0])
    u = np.where(t < 4.0, 1.0, -0.5)
    y = dc_drive.simulate(t, u, 10.0, hold="zoh")
    settings = dict(k0=5.0, hold="zoh", **PAPER)
    moments = dc_drive.estimate(t, u, y, **settings)
    ode = dc_drive.estimate(t, u, y, **settings, engine="ode", rtol=1e-9, atol=1e-12)
    assert_same_trajectory(moments, ode)
    assert moments.k == pytest.approx(10.0, abs=0.01)  # the output, interpolated, is not exact


def test_a_fold_stops_both_engines_at_the_same_time(absorber):
    t, u = step(4.0)
    y = absorber.simulate(t, u, 0.72)
    moments = absorber.estimate(t, u, y, k0=0.2)
    ode = absorber.estimate(t, u, y, k0=0.2, engine="ode")
    assert not moments.ok and moments.stopped_at == pytest.approx(ode.stopped_at, rel=1e-4)
    assert moments.message.startswith(f"J_2 reached zero at t = {moments.stopped_at:.6g}")
    np.testing.assert_array_equal(moments.t, ode.t)
    np.testing.assert_allclose(moments.khat, ode.khat, rtol=1e-4)


def test_the_global_minimiser_is_the_lowest_point_of_the_exact_cost(absorber, noisy_absorber):
    """From k0 = 0 the paper's estimate ends at the spurious minimum; global_k does not."""
    t, u, y = noisy_absorber
    result = absorber.estimate(t, u, y, k0=0.0, **PAPER)
    assert result.k == pytest.approx(-0.233, abs=1e-3) and not result.at_global
    assert result.global_k[-1] == pytest.approx(0.724, abs=1e-3)
    k = np.linspace(-2.0, 2.0, 40001)
    for upto in (100, 200, 400):
        cost = exact_cost(absorber, t, u, y, k0=0.0, **PAPER, C=None, upto=upto)
        J = cost(k)
        assert result.global_k[upto] == pytest.approx(k[np.argmin(J)], abs=2e-4)
        relative = result.cost(k, t=t[upto])  # J(k) - J(k^) at that time
        np.testing.assert_allclose(relative, J - cost(result.khat[upto]), atol=1e-6 * np.ptp(J))
        grid = k[1:-1][(J[1:-1] < J[:-2]) & (J[1:-1] < J[2:])]
        assert result.minima(t[upto]) == pytest.approx(grid, abs=2e-4)
    bounded = absorber.estimate(t, u, y, k0=0.0, **PAPER, bounds=(-1.0, 0.0))
    assert bounded.global_k[-1] == pytest.approx(result.k, rel=1e-9) and bounded.at_global
    edge = absorber.estimate(t, u, y, k0=1.0, **PAPER, bounds=(0.8, 3.0))
    assert edge.global_k[-1] == 0.8 and not edge.at_global


def test_fit_is_the_global_minimum_of_the_exact_cost(dc_drive, absorber, noisy_absorber):
    t, u, y = noisy_absorber
    paper = dict(method="ls", C=None, offset=False, initial_state=False)  # J, from rest
    for beta in (0.0, 0.5):
        result = absorber.fit(t, u, y, beta=beta, **paper)
        cost = exact_cost(absorber, t, u, y, k0=0.0, beta=beta, S0=0.0, C=None, upto=t.size - 1)
        np.testing.assert_allclose(result.coefficients, cost.coef, rtol=1e-5)
        k = np.linspace(-2.0, 2.0, 40001)
        assert result.k == pytest.approx(k[np.argmin(cost(k))], abs=2e-4)
        assert result.ok and result.cost(result.k) == pytest.approx(cost(result.k), rel=1e-6)
        assert result.minima.size == 2 and result.minima[-1] == pytest.approx(result.k)
    assert absorber.fit(t, u, y, bounds=(-1.0, 0.0), **paper).k == pytest.approx(-0.233, abs=0.01)
    t, u = step(10.0)
    y = dc_drive.simulate(t, u, 10.0) + np.random.default_rng(1).uniform(-0.01, 0.01, t.size)
    assert dc_drive.fit(t, u, y, **paper).k == pytest.approx(10.0, abs=0.1)
    silent = dc_drive.fit(t, np.zeros_like(t), np.zeros_like(t), **paper)
    assert not silent.ok and math.isnan(silent.k) and "no information" in silent.message


def test_no_information_no_update(dc_drive):
    """A step held for 1000 s: once the response has settled, the data are rounding noise
    and forgetting has shrunk the stored information by e^-100; the estimate stays at 10."""
    t, u = step(1000.0)
    y = dc_drive.simulate(t, u, 10.0)
    result = dc_drive.estimate(t, u, y, k0=5.0)
    assert result.ok and abs(result.k - 10.0) < 1e-4
    assert 100.0 < result.informed_until < 500.0
    assert "stopped informing the estimate at t = " in result.message
    after = result.t > result.informed_until
    assert np.all(result.khat[after] == result.khat[after][0])
    assert np.all(np.isfinite(result.J)) and np.all(result.J[0] > 0)
    # From about 150 s the contributions v^T W v are rounding noise (|phi|^2 within eps of
    # |v|^2 |W|), though phi itself is not yet: they must not move k^ either (they moved
    # it by 1.6e-6 relative, from 9.99996963 to 9.99998529, before they were recognised).
    settled = result.khat[np.searchsorted(result.t, 150.0)]
    assert result.k == pytest.approx(settled, rel=1e-9)
    assert 150.0 < result.informed_until < 200.0


def test_a_settling_record_fed_in_chunks_gives_the_estimate(dc_drive):
    """Chunk invariance where the data fade into rounding noise (the 1000-s step): chunks
    of 1000 and single samples across the fading, as one estimate call, to 1e-9."""
    t, u = step(1000.0)
    y = dc_drive.simulate(t, u, 10.0)
    whole = dc_drive.estimate(t, u, y, k0=5.0)
    tracker = dc_drive.Tracker(k0=5.0)
    edges = (
        list(range(0, 14000, 1000)) + list(range(14000, 17000)) + list(range(17000, 30001, 1000))
    )
    edges.append(t.size)
    worst = 0.0
    for lo, hi in zip(edges, edges[1:], strict=False):
        k = tracker.update(t[lo], u[lo], y[lo]) if hi == lo + 1 else tracker.update(
            t[lo:hi], u[lo:hi], y[lo:hi])  # fmt: skip
        worst = max(worst, abs(k - whole.khat[hi - 1]) / abs(whole.khat[hi - 1]))
        assert tracker.global_k == pytest.approx(whole.global_k[hi - 1], rel=1e-9)
    assert worst < 1e-9 and tracker.k == pytest.approx(whole.k, rel=1e-9)
    assert tracker.informed_until == pytest.approx(whole.informed_until, abs=0.1)


def test_a_tracker_fed_in_chunks_gives_the_estimate(absorber, noisy_absorber):
    """Any chunk sizes, a pickled copy half way: the k^ and global_k of one estimate call."""
    t, u, y = noisy_absorber
    for k0 in (0.0, 0.25):  # the spurious minimum; crossing the hump in sub-steps
        whole = absorber.estimate(t, u, y, k0=k0, **PAPER)
        tracker = absorber.Tracker(k0=k0, **PAPER)
        assert tracker.t is None and tracker.k == k0
        edges = [0, 1, 2, 7, 37, 38, 150, 151, 300, t.size]
        for number, (lo, hi) in enumerate(zip(edges, edges[1:], strict=False)):
            if number == 5:
                tracker = pickle.loads(pickle.dumps(tracker))
            k = (
                tracker.update(t[lo], u[lo], y[lo])
                if hi == lo + 1
                else tracker.update(t[lo:hi], u[lo:hi], y[lo:hi])
            )
            assert tracker.t == t[hi - 1]
            assert k == pytest.approx(whole.khat[hi - 1], rel=1e-9, abs=1e-12)
            assert tracker.global_k == pytest.approx(whole.global_k[hi - 1], rel=1e-9)
        assert tracker.ok and tracker.informed_until is None


BAD_INPUTS = [
    ("estimate", dict(engine="euler"), r"engine must be one of 'moments', 'ode', not 'euler'"),
    (
        "estimate",
        dict(bounds=(1.0, 1.0)),
        r"bounds must be \(lo, hi\) with lo < hi, not \(1.0, 1.0\)",
    ),
    ("estimate", dict(bounds=(0.0,)), r"bounds must be a pair \(lo, hi\)"),
    ("fit", dict(beta=-1.0), r"beta must be >= 0, not -1.0"),
    ("fit", dict(t=[0.0, 2.0, 1.0]), r"t must be strictly increasing: t\[2\] = 1.0 follows t\[1\]"),
    ("fit", dict(u=[1.0, math.nan, 1.0]), r"u\[1\] is nan"),
    ("fit", dict(t=[], u=[], y=[]), r"need at least 2 samples, not 0"),
    ("fit", dict(C=[1.0, 1.0]), r"C\(s\) has degree 1"),
    ("fit", dict(hold="cubic"), r"hold must be one of"),
]


@pytest.mark.parametrize("function,change,message", BAD_INPUTS)
def test_bad_input_is_a_clear_value_error(dc_drive, function, change, message):
    arguments = dict(t=[0.0, 1.0, 2.0], u=[1.0, 1.0, 1.0], y=[0.0, 0.1, 0.2])
    if function == "estimate":
        arguments["k0"] = 1.0
    arguments.update(change)
    with pytest.raises(ValueError, match=message):
        getattr(dc_drive, function)(**arguments)


def test_bad_input_to_a_tracker(dc_drive):
    for change, message in [
        (dict(S0=0.0), r"S0 must be > 0"),
        (dict(k0=math.inf), r"k0 must be finite"),
        (dict(bounds=(2.0, -2.0)), r"lo < hi"),
        (dict(C=[1.0, -5.0, 10.0, 10.0, 5.0, 1.0]), r"C\(s\) is not stable"),
    ]:
        with pytest.raises(ValueError, match=message):
            dc_drive.Tracker(**{"k0": 1.0, **change})
    tracker = dc_drive.Tracker(k0=1.0)
    tracker.update([0.0, 0.1], [1.0, 1.0], [0.0, 0.0])
    with pytest.raises(ValueError, match=r"t\[0\] = 0.1 follows the last sample's t = 0.1"):
        tracker.update(0.1, 1.0, 0.0)
    with pytest.raises(ValueError, match=r"y\[0\] is inf"):
        tracker.update(0.2, 1.0, math.inf)
    with pytest.raises(ValueError, match=r"must have the same length, not \[2, 2, 1\]"):
        tracker.update([0.2, 0.3], [1.0, 1.0], [0.0])
    assert tracker.t == 0.1  # nothing taken from the refused updates


def test_a_held_input_is_exact_even_for_a_fast_filter(dc_drive):
    """zoh: the input jumps at every sample. The cost from its definition, on a grid fine
    enough that the held input's jumps sit one fine step from the samples (an error of
    order 1/refine^2 in Simpson's rule there), agrees with the engine's exact cost."""
    t = np.linspace(0.0, 3.0, 61)
    u = np.sign(np.sin(4.0 * t)) + 0.5
    y = dc_drive.simulate(t, u, 10.0, hold="zoh")
    settings = dict(k0=5.0, beta=0.1, S0=1e-4, C=0.05)
    result = dc_drive.estimate(t, u, y, **settings, hold="zoh")
    k = np.linspace(0.0, 20.0, 9)
    cost = exact_cost(dc_drive, t, u, y, **settings, upto=t.size - 1, refine=400, hold="zoh")
    expected = cost(k) - cost(result.k)
    np.testing.assert_allclose(result.cost(k), expected, rtol=1e-3, atol=1e-6 * expected.max())
