"""The exact fit (method="pem", the default): the minimiser of the sampled-data prediction
error, on records made by scipy alone (tests/sampled.py), with fixed seeds."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from sampled import held, prbs, reference
from scipy import signal

import mtt


def quiet(module, *args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return module.fit(*args, **kwargs)


@pytest.mark.parametrize("dt", [0.01, 0.02])
def test_a_short_noise_free_record_gives_k_exactly(dc_drive, dt):
    """Issue 18: 3 s of a PRBS held 0.2 s, from a random initial state, with an offset: the
    offset and initial state take over 99 % of the information, and the answer is still
    the true k (the instrumental-variable fit gave 4.5 and 0.6)."""
    t = dt * np.arange(round(3 / dt) + 1)
    u = prbs(t, 0.2, 1)
    x0 = np.random.default_rng(2).standard_normal(4)
    y = held(t, u, 10.0, dc_drive, x0) + 0.3
    result = quiet(dc_drive, t, u, y, hold="zoh")
    assert result.method == "pem" and result.ok
    assert result.k == pytest.approx(10.0, rel=1e-6)
    assert result.offsets[0] == pytest.approx(0.3, abs=1e-6)
    np.testing.assert_allclose(result.states[0], x0, atol=1e-5)
    assert result.absorbed > 0.99  # and said, with the fraction
    assert any("offset and initial state take" in text for text in result.warnings)
    iv = quiet(dc_drive, t, u, y, hold="zoh", method="iv")
    assert not iv.ok and abs(iv.k - 10.0) > 1e-3  # the exact cost contradicts it: ok is False


def test_a_piecewise_linear_input_with_hold_linear(dc_drive):
    t = 0.01 * np.arange(301)
    u = np.interp(t, t[::20], np.random.default_rng(3).standard_normal(t[::20].size))
    x0 = np.random.default_rng(4).standard_normal(4)
    y = reference(dc_drive, t, u, 10.0, x0, "linear") - 0.1
    result = quiet(dc_drive, t, u, y, hold="linear")
    assert result.ok and result.k == pytest.approx(10.0, rel=1e-6)


def test_irregular_sampling_and_several_unknowns(dc_motor):
    rng = np.random.default_rng(5)
    t = np.r_[0.0, np.sort(rng.uniform(0.0, 20.0, 1500))]
    u = prbs(t, 0.5, 6)
    truth = np.array([1.0, 10.0])
    y = reference(dc_motor, t, u, truth, [0.3, -0.2], "zoh") + 0.05
    result = quiet(dc_motor, t, u, y, hold="zoh")
    assert result.ok
    np.testing.assert_allclose(result.k, truth, rtol=1e-6)


def test_ar_noise_is_modelled_and_k_se_follows_it(dc_drive):
    """AR(1) output noise (pole 0.9) at 10 dB: the noise model found is AR(1) near the true
    pole, k within 3 standard errors, and k_se larger than the white-noise fit's (which
    reads the coloured noise as white)."""
    t = 0.02 * np.arange(20001)
    u = prbs(t, 1.0, 7)
    clean = held(t, u, 10.0, dc_drive, np.zeros(4))
    v = signal.lfilter([1.0], [1.0, -0.9], np.random.default_rng(8).standard_normal(t.size))
    y = clean + v * np.sqrt(np.var(clean) / 10 / np.var(v))
    result = quiet(dc_drive, t, u, y, hold="zoh")
    assert result.noise.orders == (1, 0)
    assert result.noise.ar[1] == pytest.approx(-0.9, abs=0.02)
    assert abs(result.k - 10.0) < 3 * result.k_se
    white = quiet(dc_drive, t, u, y, hold="zoh", noise="white")
    assert white.k_se < 0.5 * result.k_se
    assert any("far from white" in text for text in white.warnings)
    assert not any("far from white" in text for text in result.warnings)


def test_white_noise_keeps_a_white_model(absorber):
    t = 0.01 * np.arange(4001)
    u = prbs(t, 2.0, 9)
    clean = held(t, u, 0.72, absorber, np.zeros(3), tau=2.0, l=0.5)
    y = clean + 0.1 * np.std(clean) * np.random.default_rng(10).standard_normal(t.size)
    result = quiet(absorber, t, u, y, hold="zoh")
    assert result.noise.kind == "white" and result.ok
    assert abs(result.k - 0.72) < 3 * result.k_se
    record = absorber.fit_record(result)
    assert record["noise"]["kind"] == "white" and record["ok"] is True


def test_arguments_that_mean_nothing_here_are_refused(dc_drive):
    t = 0.01 * np.arange(101)
    u = prbs(t, 0.2, 1)
    y = held(t, u, 10.0, dc_drive, np.zeros(4))
    with pytest.raises(ValueError, match="forgetting belongs to the recursive estimate"):
        dc_drive.fit(t, u, y, beta=0.5)
    with pytest.raises(ValueError, match="assumes white noise"):
        dc_drive.fit(t, u, y, method="iv", noise="ar")
    with pytest.raises(ValueError, match="noise must be one of"):
        dc_drive.fit(t, u, y, noise="pink")


def test_a_jacobian_near_the_last_full_one_is_carried_from_it(dc_drive):
    """One unknown: the Jacobian at a point within 1 % of the last one computed in full is
    carried from it to second order (the forced response alone, not the augmented system):
    J^T J and J^T eps as computed in full to 1e-4 of their scale, the basis kept; farther,
    or where the record determines k poorly, everything in full (a new basis, or none)."""
    t = 0.02 * np.arange(5001)
    u = prbs(t, 1.0, 1)
    clean = held(t, u, 10.0, dc_drive, np.zeros(4)) + 0.2
    y = clean + 0.1 * np.std(clean) * np.random.default_rng(7).standard_normal(t.size)
    settings = dict(hold="zoh", offset=True, initial_state=True, known={})
    Theta, white = dc_drive.theta(), dc_drive.WHITE
    _, basis = dc_drive._prediction(Theta, (t, u, y), 10.04, white, settings, True)
    assert basis is not None and basis.k == 10.04
    full = dc_drive._record_prediction(Theta, (t, u, y), 10.0, white, settings, True)
    carried, kept = dc_drive._prediction(
        Theta, (t, u, y), 10.0, white, settings, True, False, basis
    )
    assert kept is basis  # carried, not computed in full
    assert carried.rss == pytest.approx(full.rss, rel=1e-12)
    np.testing.assert_allclose(carried.gram, full.gram, rtol=1e-4)
    np.testing.assert_allclose(carried.free, full.free, rtol=1e-4)
    scale = np.sqrt(full.gram[0, 0] * full.rss)  # the size J^T eps has away from the minimum
    assert abs(carried.slope[0] - full.slope[0]) < 1e-4 * scale
    assert (
        dc_drive._prediction(Theta, (t, u, y), 10.5, white, settings, True, False, basis)[1]
        is not basis
    )
    short = (t[:150], u[:150], y[:150])  # k_se over 1 % of k: no basis, nothing carried
    assert dc_drive._prediction(Theta, short, 10.0, white, settings, True)[1] is None


def test_a_static_model_fits_exactly():
    model = mtt.load(
        "model divider\nparam r1 = 2\nunknown r2 = 3\nSe:v -> 1:loop\n1:loop -> R:r1\n"
        "1:loop -> R:r2\n1:loop -> Df:i\n"
    )
    module = model.estimator()
    assert module.n == 0
    t = np.linspace(0.0, 1.0, 101)
    u = np.sin(7 * t)
    result = quiet(module, t, u, u / 5.0 + 0.2)  # i = v / (r1 + r2)
    assert result.ok and result.k == pytest.approx(3.0, rel=1e-12)
    assert result.offsets[0] == pytest.approx(0.2, abs=1e-12)
    with pytest.raises(ValueError, match="static"):
        module.fit(t, u, u / 5.0, method="iv")


def test_ok_is_false_when_the_diagnostics_contradict_the_answer(dc_drive):
    t = 0.01 * np.arange(1001)
    u = prbs(t, 0.2, 11)
    y = held(t, u, 10.0, dc_drive, np.zeros(4))
    y = y + 0.01 * np.random.default_rng(12).standard_normal(t.size)
    bounded = quiet(dc_drive, t, u, y, hold="zoh", bounds=(1.0, 5.0))
    assert not bounded.ok and bounded.k == 5.0
    assert "at the upper bound" in bounded.warnings[0]
    wrong = quiet(dc_drive, t, u, -y[::-1], hold="zoh", offset=False, initial_state=False,
                  bounds=(1.0, 100.0))  # fmt: skip
    assert not wrong.ok and wrong.fit_percent < 0


def test_several_unknowns_step_on_by_a_chord(dc_motor, monkeypatch):
    """Several unknowns: a step's trial point is simulated once with the point's nuisances
    held and the step continued from there by the point's own Jacobian (`Records.chord`),
    the end evaluated in full. At the point itself the chord's sum of squares and J^T eps
    are the full evaluation's, the same where the records did not hold the point's Jacobian
    (found again); and the fit ends at the minimum (Gauss-Newton's own step from there
    under SETTLED_COST) with two evaluations in full, where Gauss-Newton's plain steps take
    three on this record."""
    t = 0.01 * np.arange(10001)
    u = prbs(t, 0.5, 4)
    clean = held(t, u, [1.0, 10.0], dc_motor, np.zeros(2))
    y = clean + 0.1 * np.std(clean) * np.random.default_rng(1).standard_normal(t.size)
    settings = dict(hold="zoh", offset=True, initial_state=True, known={})
    Theta, filters = dc_motor.theta(), dc_motor.WHITE.filters
    records = dc_motor.Records([(t, u, y)])
    k = np.array([1.01, 9.9])
    full = records.prediction(Theta, k, filters, settings, True)[0]
    chord = records.chord(Theta, k, filters, settings, (k, filters))[0]
    assert chord.rss == pytest.approx(full.rss, rel=1e-12) and chord.gram is None
    scale = np.abs(full.slope).max()
    np.testing.assert_allclose(chord.slope, full.slope, rtol=1e-8, atol=1e-10 * scale)
    kept = records.chord(Theta, k * 1.001, filters, settings, (k, filters))[0]
    fresh = dc_motor.Records([(t, u, y)])  # (records held elsewhere: the origin's J found there)
    again = fresh.chord(Theta, k * 1.001, filters, settings, (k, filters))[0]
    assert again.rss == kept.rss and np.array_equal(again.slope, kept.slope)

    counted = []
    augmented = dc_motor._augmented_outputs
    monkeypatch.setattr(
        dc_motor, "_augmented_outputs", lambda *a: counted.append(1) or augmented(*a)
    )
    result = quiet(dc_motor, t, u, y, hold="zoh")
    assert result.ok and result.noise.orders == (0, 0) and len(counted) == 2
    at_end = dc_motor.Records([(t, u, y)]).prediction(Theta, result.k, filters, settings, True)[0]
    decrement = at_end.slope @ np.linalg.solve(at_end.gram, at_end.slope) / (at_end.rss / t.size)
    assert decrement < dc_motor.SETTLED_COST
    monkeypatch.setattr(dc_motor, "CHORD_FROM", np.inf)  # plain Gauss-Newton steps
    counted.clear()
    plain = quiet(dc_motor, t, u, y, hold="zoh")
    assert len(counted) == 3
    np.testing.assert_allclose(result.k, plain.k, atol=0.01 * result.k_se.min())


@pytest.mark.parametrize("condition", [10.0, 1e7, 1e10])
def test_projection_factorises_as_its_gram_conditions_say(dc_drive, condition):
    """`_Projection` factorises the nuisances' scaled Gram matrix by Cholesky below
    GRAM_CONDITION (the condition then bounded by n |R^-1|_F^2, or at 1e7, past that bound's
    reach, by the eigenvalues), else by QR: R^-1 is the one of that factorisation."""
    rng = np.random.default_rng(4)
    a, b, c, d = rng.standard_normal((4, 2000))
    XT = np.array([a, a + 2.0 * c / np.sqrt(condition), b + 0.5 * a, 1e3 * d])
    projection = dc_drive._Projection.of_rows(XT)
    scale = np.sqrt(np.diag(XT @ XT.T))
    gram = (XT @ XT.T) / np.outer(scale, scale)
    values = np.linalg.eigvalsh(gram)  # (the scaled Gram's condition: about `condition`)
    assert values[-1] / values[0] == pytest.approx(condition, rel=0.5)
    if condition < 1e8:
        R = np.linalg.cholesky(gram).T
        bound = 4 * np.sum(np.linalg.inv(R) ** 2)  # (below the eigenvalues' reach at 10 only)
        assert (bound < dc_drive.GRAM_CONDITION / dc_drive.CLEAR_CONDITION) == (condition < 1e3)
    else:
        R = np.linalg.qr(XT.T / scale, mode="r")
    # (this Gram matrix's rounding, amplified by the condition; at 1e10 Cholesky's R^-1 is not
    # QR's, whose rows differ in sign)
    rtol = 1e-14 * condition + 1e-12 if condition < 1e8 else 1e-9
    np.testing.assert_allclose(projection.inverse, np.linalg.inv(R) / scale[:, None], rtol=rtol)
    # the residuals are orthogonal to the rows either way
    W = rng.standard_normal((2, 2000))
    rest = projection.fit_rows(W)[1]
    assert np.abs(rest @ XT.T).max() < 1e-9 * np.abs(W @ XT.T).max()


def test_schur_poles_are_the_eigenvalues(dc_drive):
    """The poles `_predictor_stable` judges, from a real Schur form's 1 x 1 and 2 x 2 diagonal
    blocks in Python's scalars, are np.linalg.eigvals' (real, complex pairs, repeated); a
    matrix that is not quasi-triangular goes to eigvals itself."""
    from scipy import linalg

    rng = np.random.default_rng(6)
    for size in range(1, 7):
        for _ in range(20):
            F = linalg.schur(rng.standard_normal((size, size)) * 3.0, output="real")[0]
            blocks = dc_drive._diagonal_blocks(F)
            poles = np.sort_complex(np.array(dc_drive._schur_poles(F, blocks)))
            expected = np.sort_complex(np.linalg.eigvals(F))
            np.testing.assert_allclose(poles, expected, rtol=1e-9, atol=1e-12)
    full = rng.standard_normal((4, 4))
    assert dc_drive._diagonal_blocks(full) is None
    np.testing.assert_allclose(np.sort_complex(np.array(dc_drive._schur_poles(full, None))),
                               np.sort_complex(np.linalg.eigvals(full)))  # fmt: skip
    assert dc_drive._schur_poles(np.zeros((0, 0)), None) == []


def test_the_summary_inverts_one_entry_as_lapack_does(absorber):
    """`_eigenvalues_and_inverse` skips LAPACK for one entry (one unknown, white noise)
    within its range: the entry and its reciprocal are what eigvalsh and pinv return, to the
    bit (beyond it, LAPACK's own)."""
    rng = np.random.default_rng(11)
    for value in np.r_[np.exp(rng.uniform(-700, 700, 4000)), 1.0, 0.0, -1.0, 5e-324, 1.7e308]:
        M = np.array([[value]])
        with np.errstate(over="ignore"):  # (1 / 5e-324)
            values, inverse = absorber._eigenvalues_and_inverse(M)
            assert values.tolist() == np.linalg.eigvalsh(M).tolist()
            assert inverse.tolist() == np.linalg.pinv(M).tolist()
    M = np.array([[2.0, 1.0], [1.0, 3.0]])  # (larger: LAPACK's own)
    values, inverse = absorber._eigenvalues_and_inverse(M)
    assert values.tolist() == np.linalg.eigvalsh(M).tolist()
    assert inverse.tolist() == np.linalg.pinv(M).tolist()
