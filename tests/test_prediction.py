"""The exact sampled-data output of the generated modules (templates/algorithm/prediction):
the realisation, its sensitivities and `_with_nuisances`, against data made by scipy alone
(tf2ss, cont2discrete, dlsim, expm), never by the module under test."""

from __future__ import annotations

import numpy as np
import pytest
from sampled import prbs, reference
from scipy import signal


def test_dlsim_agrees_with_the_reference(dc_drive):
    """The step-by-step reference is scipy's dlsim for a held input (a check of the check)."""
    t = 0.01 * np.arange(201)
    u = prbs(t, 0.2, 0)
    x0 = np.array([0.1, -0.2, 0.3, 0.05])
    system = signal.cont2discrete(signal.tf2ss(*dc_drive.transfer_function(10.0)), 0.01)
    expected = signal.dlsim(system, u, t, x0=x0)[1][:, 0]
    assert np.max(np.abs(reference(dc_drive, t, u, 10.0, x0, "zoh") - expected)) < 1e-12


@pytest.mark.parametrize("hold", ["zoh", "linear"])
def test_with_nuisances_recovers_initial_state_and_offset(dc_drive, hold):
    t = 0.01 * np.arange(301)
    u = prbs(t, 0.2, 1) if hold == "zoh" else np.sin(3 * t) + 0.5 * np.cos(7 * t)
    x0 = np.random.default_rng(2).standard_normal(4)
    y = reference(dc_drive, t, u, 10.0, x0, hold) + 0.7
    fitted, offset, state = dc_drive._with_nuisances(
        t, u, y, 10.0, hold=hold, offset=True, initial_state=True, known={}
    )
    assert np.max(np.abs(fitted - y)) < 1e-11
    assert offset == pytest.approx(0.7, abs=1e-9)
    np.testing.assert_allclose(state, x0, atol=1e-8)


def test_with_nuisances_irregular_sampling_several_unknowns(dc_motor):
    rng = np.random.default_rng(3)
    t = np.r_[0.0, np.sort(rng.uniform(0.0, 6.0, 400))]
    u = prbs(t, 0.5, 4)
    k = {"ra": 1.3, "jl": 7.0}
    x0 = np.array([0.4, -0.9])
    y = reference(dc_motor, t, u, k, x0, "zoh") - 0.25
    fitted, offset, state = dc_motor._with_nuisances(
        t, u, y, k, hold="zoh", offset=True, initial_state=True, known={}
    )
    assert np.max(np.abs(fitted - y)) < 1e-11
    assert offset == pytest.approx(-0.25, abs=1e-9)
    np.testing.assert_allclose(state, x0, atol=1e-8)


def test_with_nuisances_flags(absorber):
    """Only what the flags allow is fitted: without them the output is `simulate`'s."""
    t = 0.01 * np.arange(401)
    u = prbs(t, 0.5, 5)
    known = {"tau": 2.0, "l": 0.5}
    clean = reference(absorber, t, u, 0.72, np.zeros(3), "zoh", **known)
    bare = absorber._with_nuisances(
        t, u, clean + 1.0, 0.72, hold="zoh", offset=False, initial_state=False, known=known
    )
    assert np.max(np.abs(bare[0] - clean)) < 1e-12
    assert bare[1] == 0.0 and not bare[2].any()
    shifted = absorber._with_nuisances(
        t, u, clean + 1.0, 0.72, hold="zoh", offset=True, initial_state=False, known=known
    )
    assert shifted[1] == pytest.approx(1.0, abs=1e-12) and not shifted[2].any()


def test_sensitivities_match_finite_differences(dc_motor):
    """dy/dk from the augmented system against central differences of the exact output."""
    t = 0.01 * np.arange(1001)
    u = prbs(t, 0.3, 6)
    k = np.array([1.0, 10.0])
    real = dc_motor._realise(dc_motor.theta(), k)
    base, dz = dc_motor._augmented(real, t, u, "zoh", np.zeros(real.order))
    slopes = dc_motor._output_slopes(real, base, dz, u)
    for j in range(2):
        step = np.zeros(2)
        step[j] = 1e-3 * k[j]
        up, down = (dc_motor._realise(dc_motor.theta(), k + s) for s in (step, -step))
        difference = (dc_motor._forced(up, t, u, "zoh") - dc_motor._forced(down, t, u, "zoh")) / (
            2 * step[j]
        )
        assert np.max(np.abs(difference - slopes[:, j])) < 1e-6 * np.max(np.abs(slopes[:, j]))


def test_fine_sampling_keeps_its_digits(dc_drive):
    """Poles near z = 1 (dt 1e-4, slowest time constant 10 s), a complex pair, and a pole
    of multiplicity five (the filter (1 + s)^5): held step responses against their closed
    forms to 1e-11."""
    t = 1e-4 * np.arange(20001)
    u = np.ones_like(t)
    num, den = dc_drive.transfer_function(10.0)
    poles = np.roots(den)
    residues = np.polyval(num, poles) / (np.polyval(np.polyder(den), poles) * poles)
    exact = num[-1] / den[-1] + (residues * np.exp(np.outer(t, poles))).sum(1).real
    assert np.max(np.abs(dc_drive.simulate(t, u, 10.0, hold="zoh") - exact)) < 1e-11
    states = dc_drive.filter_states(t[:10001], u[:10001], C="(1+s)^5", hold="zoh")
    s = t[:10001]
    first = 1 - np.exp(-s) * (1 + s + s**2 / 2 + s**3 / 6 + s**4 / 24)
    last = np.exp(-s) * (s - 3 * s**2 / 2 + s**3 / 2 - s**4 / 24)
    assert np.max(np.abs(states[:, 0] - first)) < 1e-11
    assert np.max(np.abs(states[:, 4] - last)) < 1e-11


OUTPUTS = np.array([[1.0, -0.5, 2.0], [0.0, 1.0, 0.0]])  # output rows for `_schur_rows`' H


def _companion(poles) -> np.ndarray:
    A = np.eye(3, k=1)
    A[-1] = -np.real(np.poly(poles))[:0:-1]
    return A


@pytest.mark.parametrize(
    "A",
    [_companion((-1.0, -2.0, -3.0)), _companion((-0.5 + 2j, -0.5 - 2j, -4)),
     np.array([[0.0, 1.0, 0.5], [0.0, -1.0, 1.0], [0.0, 0.0, -2.0]])],  # an integrator
)  # fmt: skip
def test_schur_rows_follow_the_step_by_step_propagation(dc_drive, A):
    """`_schur_rows` (real poles, a complex pair, an integrator kept in its own triangular
    form), several signals from a non-zero state, two of them constant: against a
    step-by-step propagation by scipy's expm."""
    from scipy import linalg

    B = np.array([0.0, 0.0, 1.0])
    h, size = 0.05, 400
    t = h * np.arange(size)
    W = np.array([np.sin(t), np.full(size, 2.5), np.full(size, -1.0)])
    start = np.array([0.3, -0.2, 0.1])
    V, _, rows = dc_drive._schur_rows(A, B, t, W, ("zoh",) * 3, start)
    states = rows if V is None else V @ rows
    outputs = dc_drive._schur_rows(A, B, t, W, ("zoh",) * 3, start, H=OUTPUTS)[2]  # (alone)
    E = linalg.expm(np.block([[A, B[:, None]], [np.zeros((1, 4))]]) * h)
    for j in range(3):
        x, expected = start.copy(), [start]
        for i in range(size - 1):
            x = E[:3, :3] @ x + E[:3, 3] * W[j, i]
            expected.append(x)
        scale = max(1.0, np.abs(states[j]).max())
        assert np.max(np.abs(states[j] - np.array(expected).T)) < 1e-12 * scale
        assert np.max(np.abs(outputs[j] - OUTPUTS @ np.array(expected).T)) < 1e-11 * scale


@pytest.mark.parametrize(
    "A",
    [_companion((-0.5 + 2j, -0.5 - 2j, -4)),
     np.array([[0.0, 1.0, 0.5], [0.0, -1.0, 1.0], [0.0, 0.0, -2.0]]),  # an integrator
     np.array([[-1e4, 1.0, 0.0], [0.0, -0.3, 2.0], [0.0, -2.0, -0.3]])],  # a mode that dies out
)  # fmt: skip
@pytest.mark.parametrize("size", [1601, 2000])
def test_schur_rows_in_blocks_follow_the_step_by_step_propagation(dc_drive, A, size):
    """A record long enough for `_triangular`'s blocks of samples, its steps a whole number
    of blocks (1600) or not (1999: a shorter last block), held and linear inputs from a
    non-zero state, a pole whose powers underflow: against a step-by-step propagation by
    scipy's expm, to the same accuracy as the scalar recursion."""
    from scipy import linalg

    B = np.array([0.0, 0.0, 1.0])
    h = 0.05
    t = h * np.arange(size)
    W = np.array([np.sin(t) + prbs(t, 1.0, 0), np.cos(3 * t), np.full(size, -1.0)])
    holds = ("linear", "zoh", "zoh")
    start = np.array([0.3, -0.2, 0.1])
    V, _, rows = dc_drive._schur_rows(A, B, t, W, holds, start)
    states = rows if V is None else V @ rows
    outputs = dc_drive._schur_rows(A, B, t, W, holds, start, H=OUTPUTS)[2]  # (alone)
    augmented = np.zeros((5, 5))  # [x; w; w'] with w' held over each interval
    augmented[:3, :3], augmented[:3, 3], augmented[3, 4] = A, B, 1.0
    E = linalg.expm(augmented * h)
    for j, hold in enumerate(holds):
        slopes = np.diff(W[j]) / h if hold == "linear" else np.zeros(size - 1)
        x, expected = start.copy(), [start]
        for i in range(size - 1):
            x = E[:3, :3] @ x + E[:3, 3] * W[j, i] + E[:3, 4] * slopes[i]
            expected.append(x)
        scale = max(1.0, np.abs(states[j]).max())
        assert np.max(np.abs(states[j] - np.array(expected).T)) < 1e-12 * scale
        assert np.max(np.abs(outputs[j] - OUTPUTS @ np.array(expected).T)) < 1e-11 * scale
