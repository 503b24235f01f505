"""The generated nonlinear module's fit (issue 20) on records made independently by
solve_ivp (tests/nonlinear_records.py): exact on noise-free records, calibrated on noisy
ones (fixed seeds, tolerances a correct method meets with margin), several records
jointly, validation on a new record, multiple shooting, profile intervals, and a model
whose unknowns appear only as a product reported as not identifiable."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
import sympy
from nonlinear_models import TWO_TANKS_K, two_tanks
from nonlinear_records import held, noisy, pump, tanks_output, tanks_rhs
from scipy import signal

from mtt.derivation.nonlinear import NonlinearStateSpace
from mtt.estimator import nonlinear_codegen

TRUE = np.array(TWO_TANKS_K)


@pytest.fixture(scope="module")
def tanks():
    values = dict(zip(("c1", "c2", "kp"), TRUE, strict=True))
    return nonlinear_codegen.load(two_tanks(), values=values)


def _record(seed: int, x0=(1.0, 2.0), size: int = 241, k=TRUE, high: float = 0.8):
    """A pump record between 0.3 and `high`: at 0.8 the upper tank stays below its rim, at
    1.6 it overflows now and then (events, in the simulator)."""
    t = np.arange(size) * 0.5
    u = pump(t, 0.3, high, 20, seed)
    states = held(tanks_rhs(k), t, u, x0)
    assert (states[:, 0].max() > 3.1) == (high > 1.2) and states[:, 0].min() < 3
    return t, u, tanks_output(states), states


def _quiet(function, *args, **options):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return function(*args, **options)


def test_noise_free_records_give_the_unknowns_and_initial_state_exactly(tanks):
    t, u, y, states = _record(0, high=1.6)  # overflowing
    found = tanks.fit(t, u, y, k0=[0.6, 0.33, 1.2], hold="zoh", multistart=0)
    assert found.ok, found.message
    np.testing.assert_allclose(found.k, TRUE, rtol=1e-6)
    np.testing.assert_allclose(found.states[0], states[0], rtol=1e-5)
    assert abs(found.offsets[0]) < 1e-6 and found.fit_percent > 99.999
    assert found.method == "pem" and found.shooting == "single" and found.identifiable
    assert found.intervals == ("wald", "wald", "wald")


def test_the_fits_jacobian_along_the_states_agrees_with_the_sensitivities(tanks):
    """The fit's Jacobian: the states simulated alone (with each interval's Gauss points),
    the sensitivities by Magnus steps along them, all intervals at once; sub-steps where
    the overflow's kink bends the Jacobian. Against the sensitivities integrated with the
    states at tight tolerances: within 0.5 % of each column's size (Gauss-Newton needs
    far less), the output the same to the simulation's tolerance."""
    t, u, _, states = _record(0, high=1.6, size=801)  # overflowing now and then
    options = ("zoh", (1e-9, 1e-12), {})
    run = tanks._simulated(t, u, TRUE, states[0], *options)
    assert run.nodes is not None and run.nodes.shape == (t.size - 1, 2, 2)
    dy_dk, dy_dx0 = tanks._jacobian_along(t, u, TRUE, states[0], *options, run)
    exact = tanks.sensitivities(t, u, TRUE, x0=states[0], hold="zoh", rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(run.y, exact.y, rtol=1e-7)
    for found, truth in ((dy_dk, exact.dy_dk), (dy_dx0, exact.dy_dx0)):
        assert np.all(np.abs(found - truth).max(0) < 5e-3 * np.abs(truth).max(0))
    run = tanks._simulated(t, u, TRUE, states[0], "linear", *options[1:])
    assert run.nodes is None  # an interpolated input: the sensitivities with the states


def test_a_noisy_record_is_fitted_within_its_interval(tanks):
    t, u, y, states = _record(1)
    found = _quiet(tanks.fit, t, u, noisy(y, 20, seed=1), hold="zoh", multistart=0, profile=None)
    assert found.ok, found.message
    assert np.all(found.ci[:, 0] < TRUE) and np.all(found.ci[:, 1] > TRUE)
    assert np.all(np.abs(found.k - TRUE) < 3 * found.k_se)
    assert np.all(found.k_se < 0.1 * TRUE)
    # Wald intervals: the normal's quantile, Student's t's where a noise model was estimated
    # (here the BIC takes AR(2), coefficients 0.12 and 0.22, as it does from this record's
    # noise itself: its autocorrelations at lags 1 and 2 are -0.09 and -0.20; Student's t for
    # about 60 degrees, 1.994)
    quantile = 1.96 if found.noise is None else 1.994
    half = np.outer(found.k_se, [-quantile, quantile])
    np.testing.assert_allclose(found.ci, found.k[:, None] + half,
                               rtol=1e-3)  # fmt: skip
    # the noise's standard deviation, as simulated (20 dB below the output's spread)
    assert found.noise_std == pytest.approx(np.std(y) / 10, rel=0.15)
    assert found.covariance.shape == (3, 3) and found.minima.shape[1] == 3


def test_records_are_fitted_jointly_and_a_new_record_is_validated(tanks):
    first, second, new = _record(2, (1.0, 2.0)), _record(3, (2.5, 1.0)), _record(4, (0.5, 3.0))
    ys = [noisy(record[2], 20, seed) for seed, record in enumerate((first, second, new))]
    found = _quiet(tanks.fit, [first[0], second[0]], [first[1], second[1]], ys[:2], hold="zoh",
                   multistart=0, profile=None)  # fmt: skip
    assert found.ok, found.message
    assert len(found.states) == len(found.offsets) == len(found.fitted) == 2
    np.testing.assert_allclose(found.states[1], second[3][0], rtol=0.15)
    assert np.all(np.abs(found.k - TRUE) < 3 * found.k_se)
    compared = found.compare(new[0], new[1], ys[2])
    truth = ys[2] - new[2]  # the simulation with the true unknowns and initial state
    true_fit = 100 * (1 - np.linalg.norm(truth) / np.linalg.norm(ys[2] - ys[2].mean()))
    assert abs(compared.fit_percent - true_fit) < 1.0
    assert compared.initial_state[1] == pytest.approx(new[3][0, 1], rel=0.05)  # observed
    assert compared.samples == new[0].size and "estimated" in compared.estimated
    fitted = found.simulate(new[0], new[1], initial_state="estimate", y=ys[2])
    np.testing.assert_allclose(fitted, compared.fitted)


def test_multiple_shooting_reaches_the_same_minimum(tanks):
    t, u, y, _ = _record(5, size=121)
    y = noisy(y, 20, seed=5)
    options = dict(hold="zoh", multistart=0, profile=None)
    single = _quiet(tanks.fit, t, u, y, shooting="single", **options)
    multiple = _quiet(tanks.fit, t, u, y, shooting="multiple", segments=4, **options)
    assert multiple.shooting == "multiple" and single.shooting == "single"
    # the same minimum: each descent stops within 1e-3 standard errors of it
    assert np.all(np.abs(multiple.k - single.k) < 0.01 * single.k_se)


def test_a_poor_start_is_rescued_by_the_multistart_and_every_minimum_is_listed(tanks):
    t, u, y, _ = _record(6)
    found = _quiet(tanks.fit, t, u, y, k0=[4.0, 0.05, 0.2], hold="zoh", multistart=3,
                   bounds=[(0.1, 2.0), (0.1, 2.0), (0.2, 5.0)])  # fmt: skip
    np.testing.assert_allclose(found.k, TRUE, rtol=1e-6)
    assert [origin for origin, _, _ in found.starts][:1] == ["k0"]
    assert len(found.starts) == 5  # k0, the model file's values, three quasi-random points
    np.testing.assert_allclose(found.minima[0], found.k)
    assert np.all(np.diff(found.minima_costs) > 0)


def test_starts_that_reach_one_minimum_report_the_first_ones_end_not_the_rounding_lowest(tanks):
    """Each descent stops within CLOSE noise variances of the minimum, so which of two starts
    ends lower there is rounding: the estimate (and the steps reported) is the first start's
    end, whatever the order of the others, not a coin toss of the last digits."""
    t, u, y, _ = _record(1)
    y = noisy(y, 20, seed=1)
    a, b = [0.6, 0.33, 1.2], [0.4, 0.5, 0.8]
    options = dict(hold="zoh", multistart=0, profile=None, noise="white", uncertainty=False)
    both = _quiet(tanks.fit, t, u, y, k0=a, starts=[b], **options)
    swapped = _quiet(tanks.fit, t, u, y, k0=b, starts=[a], **options)
    assert [reached is not None for _, _, reached in both.starts] == [True] * 3
    assert np.all(np.abs(both.k - swapped.k) < 0.01 * np.abs(both.k))  # one minimum ...
    assert not np.array_equal(both.k, swapped.k)  # ... reached to different last digits
    np.testing.assert_array_equal(both.k, _quiet(tanks.fit, t, u, y, k0=a, **options).k)
    np.testing.assert_array_equal(swapped.k, _quiet(tanks.fit, t, u, y, k0=b, **options).k)


def test_the_profile_interval_ends_where_the_refitted_cost_rises_by_3_84_variances(tanks):
    t, u, y, _ = _record(7)
    y = noisy(y, 20, seed=7)
    found = _quiet(tanks.fit, t, u, y, hold="zoh", multistart=0, profile="kp")
    assert found.intervals == ("wald", "wald", "profile")
    wald = found.k[2] + 1.96 * found.k_se[2] * np.array([-1.0, 1.0])
    assert found.ci[2, 1] - wald[1] > 0.05 * (wald[1] - wald[0])  # skewed: not quadratic
    rss = sum(float(r @ r) for r in found.residuals)
    for end in found.ci[2]:  # kp held at the end (a box of width 1e-9), the rest refitted
        bounds = [(0.05, 5.0), (0.05, 5.0), (end, end * (1 + 1e-9))]
        held_there = _quiet(tanks.fit, t, u, y, k0=found.k, hold="zoh", multistart=0,
                            bounds=bounds, profile=None)  # fmt: skip
        rise = sum(float(r @ r) for r in held_there.residuals) - rss
        assert rise / found.noise_std**2 == pytest.approx(3.84, abs=0.1)


def _product_tank() -> NonlinearStateSpace:
    """One tank filled by a pump of gain a b and drained through an orifice c: a and b
    appear only as their product."""
    x, u, y = sympy.symbols("x u y")
    a, b, c = sympy.symbols("a b c")
    f = sympy.Matrix([a * b * u - c * sympy.sqrt(x)])
    return NonlinearStateSpace("product_tank", (x,), u, y, (a, b, c), {}, f, sympy.Matrix([x]))


def test_two_unknowns_seen_only_as_a_product_are_reported_not_identifiable():
    module = nonlinear_codegen.load(_product_tank(), values=dict(a=2.0, b=0.5, c=0.5))
    t = np.arange(201) * 0.5
    u = pump(t, 0.3, 1.0, 20, seed=8)
    states = held(lambda x, v: [1.0 * v - 0.5 * math.sqrt(max(x[0], 0.0))], t, u, [1.0])
    with pytest.warns(module.EstimationWarning, match="a\\*b"):
        found = module.fit(t, u, noisy(states[:, 0], 30, seed=8), hold="zoh", multistart=0)
    assert not found.ok and not found.identifiable
    assert found.determined == "the output depends on a and b only through a*b"
    assert np.all(np.isinf(found.k_se[:2]))
    assert 0 < found.k_se[2] < 0.05 * found.k[2]  # c is determined: its standard error stays
    assert abs(found.k[2] - 0.5) < 3 * found.k_se[2]
    assert found.k[0] * found.k[1] == pytest.approx(1.0, rel=0.02)
    assert found.message.startswith("the unknowns are not separately determined")


@pytest.mark.parametrize(
    ("options", "message"),
    [
        (dict(shooting="twice"), "shooting must be one of"),
        (dict(x0=[1.0, 2.0, 3.0]), "x0 must end in an axis of the 2 values"),
        (dict(profile="c3"), "profile must be 'auto', None or an unknown's name"),
        (dict(segments=1), "segments must be a whole number >= 2"),
        (dict(k0=[1.0, 2.0]), "k0 must give the 3 unknowns"),
        (dict(bounds=[(1.0, 0.5), (0.1, 1.0), (0.1, 2.0)]), "lo < hi"),
    ],
)
def test_arguments_are_checked(tanks, options, message):
    t = np.arange(50) * 0.5
    with pytest.raises(ValueError, match=message):
        tanks.fit(t, np.ones(t.size), np.ones(t.size), **options)


def test_coloured_noise_is_modelled_and_widens_the_intervals(tanks):
    """AR(1) output noise (pole 0.9): noise="auto" chooses AR(1) from the output-error
    residuals, fits again to the whitened prediction errors and gives the prediction-error
    k_se, several times the white-noise fit's (which is too small here)."""
    t, u, y, _ = _record(9, size=401)
    scale = np.std(y) / 10 * math.sqrt(1 - 0.9**2)
    v = signal.lfilter([1.0], [1.0, -0.9], scale * np.random.default_rng(9).standard_normal(t.size))
    found = _quiet(tanks.fit, t, u, y + v, hold="zoh", multistart=0, profile=None)
    white = _quiet(tanks.fit, t, u, y + v, hold="zoh", multistart=0, profile=None, noise="white")
    assert found.ok, found.message
    assert found.noise.kind == "AR(1)" and found.noise.ar[1] == pytest.approx(-0.9, abs=0.1)
    assert found.noise.std == pytest.approx(found.noise_std) and "AR(1) noise" in found.message
    assert found.noise_std == pytest.approx(scale, rel=0.2)  # the innovations' std, not v's
    assert white.noise is None and np.all(found.k_se > 2 * white.k_se)
    assert np.all(np.abs(found.k - TRUE) < 3 * found.k_se)
    assert found.minima[0] == pytest.approx(found.k) and found.minima_costs[0] == pytest.approx(
        sum(float(r @ r) for r in found.residuals)
    )  # the output errors' sum of squares at the estimate
    with pytest.raises(ValueError, match="noise must be one of"):
        tanks.fit(t, u, y, noise="pink")


def test_coloured_noise_intervals_take_students_t_for_the_noise_models_uncertainty(tanks):
    """With an estimated AR(1) noise model (pole 0.9) k_se rests on the whitening's
    low-frequency gain, itself uncertain: the intervals take Student's t quantile for k_se's
    degrees of freedom (Satterthwaite's, from k_se's slope in the noise coefficient), wider
    than the normal's; a white noise model keeps the normal's."""
    t, u, y, _ = _record(9, size=401)
    scale = np.std(y) / 10 * math.sqrt(1 - 0.9**2)
    v = signal.lfilter([1.0], [1.0, -0.9], scale * np.random.default_rng(9).standard_normal(t.size))
    found = _quiet(tanks.fit, t, u, y + v, hold="zoh", multistart=0, profile=None)
    white = _quiet(tanks.fit, t, u, y + v, hold="zoh", multistart=0, profile=None, noise="white")
    assert found.noise.kind == "AR(1)" and white.noise is None
    quantile = (found.ci[:, 1] - found.ci[:, 0]) / (2 * found.k_se)
    assert np.allclose((found.ci[:, 1] + found.ci[:, 0]) / 2, found.k)
    assert np.all(quantile > 2.0) and np.all(quantile < 2.15)  # 2.03 to 2.08: nu 15 to 25
    assert (white.ci[:, 1] - white.ci[:, 0]) / (2 * white.k_se) == pytest.approx(1.959963984540054)


def test_a_fit_that_reaches_no_minimum_says_so_not_that_the_model_cannot_be_simulated(tanks):
    """5 s of a step (the unknowns and the initial state hardly separated): the descent
    still creeps along the valley after its 100 simulations. No estimate, ok False, and
    the message says so (it said the model could not be simulated)."""
    t = np.arange(21) * 0.25
    u = np.where(t < 2.5, 0.5, 0.7)
    y = tanks_output(held(tanks_rhs(TRUE), t, u, (1.0, 2.0)))
    found = _quiet(tanks.fit, t, u, y, hold="zoh", multistart=0, profile=None, shooting="single")
    assert not found.ok and np.isnan(found.k).all()
    assert found.message.startswith("no start reached a minimum of the criterion")
    assert "reaches no minimum within 100 simulations" in found.message


def test_a_constant_output_is_refused_as_the_linear_fit_refuses_it(tanks):
    """The pump varies, the level does not (a wrong column, a sensor off): the estimate
    answers rounding error, so ok is False with the linear verdict's reason first, and
    fit_percent is NaN."""
    t = np.arange(241) * 0.5
    u = 0.3 + 0.5 * (np.sin(t / 7) > 0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", tanks.EstimationWarning)
        result = tanks.fit(t, u, np.full(t.size, 2.0), hold="zoh", multistart=0)
    assert not result.ok and math.isnan(result.fit_percent)
    assert result.warnings[0].startswith("the output is constant: nothing in it responds")
    # no noise is in a constant output: its residuals, the model's misfit, are not modelled
    # as coloured noise (an AR(1) with pole 0.996 was, on the misfit's 3e-5)
    assert result.noise is None and "noise)" not in result.message


def test_auto_noise_on_white_records_chooses_as_the_bic_does_from_the_noise_itself(tanks):
    """White output noise: the noise model chosen from the output-error residuals is the
    one the same BIC chooses from the record's noise itself (about its mean, as the offset
    takes it), white on most records and AR(2) on seed 1's (a lag-2 autocorrelation of
    -0.20, 3 standard errors in 241 samples: the BIC's own rate on white noise of this
    length is 2 to 3 %). The fit does not colour the residuals (simulation tolerances,
    nuisances): their autocorrelations sit within 0.05 of the noise's."""
    chooser = tanks._choose_noise.__globals__

    class Noise:  # one record's noise answering the chooser's sums
        def __init__(self, v):
            self.v = v

        def noise_sums(self, Theta, k, settings, request):
            return chooser["_noise_sums"](self.v, request)

    kinds, shifts = [], []
    for seed in range(4):
        t, u, clean, _ = _record(seed)
        y = noisy(clean, 20, seed)
        found = _quiet(tanks.fit, t, u, y, hold="zoh", multistart=0, profile=None)
        v = y - clean - np.mean(y - clean)
        truth = chooser["_choose_noise"](None, Noise(v), None, "auto", None, v.size)
        kinds.append("white" if found.noise is None else found.noise.kind)
        assert kinds[-1] == truth.kind
        r = np.ravel(found.residuals)  # y - y^ (at the prediction-error fit on seed 1)
        lagged = [r[:-j] @ r[j:] / (r @ r) - v[:-j] @ v[j:] / (v @ v) for j in (1, 2, 3)]
        shifts.append(lagged)
    # the residuals are the noise less its projection on the 6 fitted parameters' columns
    # (slow ones): their autocorrelations up to about P/N = 0.025 below the noise's (0.022 here)
    assert np.max(np.abs(shifts)) < 0.05, shifts
    assert kinds == ["white", "AR(2)", "white", "white"]
