"""Generated modules of several unknowns: the criterion over the product monomials, the global
search within a box, fit, estimate and the Tracker in vector form, and their arguments.

Records are simulated here with scipy.signal.lsim from the transfer functions written out
(the DC motor's from its bond graph by hand, the RLC circuit's c s / (l c s^2 + r c s + 1)),
not with the modules' own simulate. Monte Carlo figures (bias, k_se against the spread) are
in bench/montecarlo.py.
"""

from __future__ import annotations

import math
import pickle
import warnings
from pathlib import Path

import numpy as np
import pytest
from scipy import integrate, signal

MOTOR = np.array([1.0, 10.0])  # ra, jl
RLC = np.array([2.0, 0.5, 0.1])  # r, l, c


def motor_tf(k):
    """G(s) of the DC motor: km / ((la s + ra)((jm + jl) s + b) + km^2), la = 1/10, km = jm = 1,
    b = 1/10."""
    ra, jl = k
    return [1.0], np.polyadd(np.polymul([0.1, ra], [1 + jl, 0.1]), [1.0])


def rlc_tf(k):
    r, inductance, c = k
    return [c, 0.0], [inductance * c, r * c, 1.0]


def prbs(t: np.ndarray, hold: float, seed: int) -> np.ndarray:
    levels = np.random.default_rng(seed).choice([-1.0, 1.0], int(t[-1] / hold) + 1)
    return levels[np.floor(t / hold + 1e-9).astype(int)]


def record(tf, k, dt: float, t_end: float, hold: float, seed: int = 0, snr_db=None):
    t = dt * np.arange(round(t_end / dt) + 1)
    u = prbs(t, hold, seed)
    y = signal.lsim(signal.StateSpace(*signal.tf2ss(*tf(k))), u, t, interp=False)[1]
    if snr_db is not None:
        noise = math.sqrt(np.var(y) / 10 ** (snr_db / 10))
        y = y + noise * np.random.default_rng(100 + seed).standard_normal(t.size)
    return t, u, y


def quiet(function, *args, **options):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return function(*args, **options)


@pytest.mark.parametrize("method", ["pem", "iv", "ls"])
def test_noise_free_records_give_every_unknown_to_1e6(dc_motor, rlc3, method):
    """The targets of issue 11: ra, jl and r, l, c from noise-free data, 1e-6 relative. For
    "iv" and "ls" the only error left is the linear interpolation of the output between
    samples (it falls as dt^2: these records are sampled finely enough), and the exact
    output error sees it (ok False: the model file's values fit better); "pem" is exact."""
    for module, tf, k, dt, t_end, hold in (
        (dc_motor, motor_tf, MOTOR, 0.0005, 10.0, 0.25),
        (rlc3, rlc_tf, RLC, 0.0002, 2.0, 0.05),
    ):
        t, u, y = record(tf, k, dt, t_end, hold)
        result = quiet(module.fit, t, u, y, hold="zoh", method=method)
        assert result.k.shape == k.shape
        assert result.ok if method == "pem" else "fits the data better" in result.warnings[0]
        np.testing.assert_allclose(result.k, k, rtol=1e-6 if method != "pem" else 1e-9)
        assert np.all(result.k_se < 1e-5 * k) and result.covariance.shape == (k.size, k.size)
        assert result.ci.shape == (k.size, 2) and np.all(result.ci[:, 0] < result.k)


def test_the_criterion_is_the_cost_of_its_definition(dc_motor):
    """The least-squares criterion over the product monomials ra^i jl^j equals J(k) =
    1/2 int (X^T theta(k))^2 at points of the plane, X filtered by scipy's lsim (exact for
    the linearly interpolated samples) and integrated by Simpson's rule."""
    t, u, y = record(motor_tf, MOTOR, 0.01, 4.0, 0.5, snr_db=20)
    C = "(1+s)^3"
    criterion = dc_motor.moments(t, u, y, C=C, offset=False, initial_state=False, hold="zoh")
    coefficients = criterion.criterion(dc_motor.theta())
    fine = np.linspace(0.0, t[-1], 10 * (t.size - 1) + 1)
    c = dc_motor.filter_polynomial(C)
    held = u[np.minimum(np.searchsorted(t, fine + 1e-9, "right") - 1, t.size - 1)]
    rows = []
    for data, degree, linear in (
        (np.interp(fine, t, y), dc_motor.n, True),
        (held, dc_motor.m, False),
    ):
        for i in range(degree + 1):
            rows.append(signal.lsim((np.r_[1.0, np.zeros(i)], c), data, fine, interp=linear)[1])
    X = np.array(rows)
    fit = quiet(dc_motor.fit, t, u, y, C=C, method="ls", offset=False, initial_state=False,
                hold="zoh")  # fmt: skip
    np.testing.assert_array_equal(fit.coefficients, coefficients)
    for k in ([1.0, 10.0], [0.5, 20.0], [3.0, 2.0]):
        K = np.array([1.0, k[0], k[1], k[0] * k[1]])  # MONOMIALS: 1, ra, jl, ra*jl
        g = (dc_motor.theta() @ K) @ X
        assert fit.cost(k) == pytest.approx(0.5 * integrate.simpson(g**2, x=fine), rel=1e-6)
    assert list(map(tuple, dc_motor.BASIS)) == [(i, j) for i, j in (
        (0, 0), (1, 0), (0, 1), (2, 0), (1, 1), (0, 2), (2, 1), (1, 2), (2, 2))]  # fmt: skip


def biquadratic(module, tilt: float):
    """(x y - 1)^2 + (x - y)^2 / 10 + tilt x: two local minima near (1, 1) and (-1, -1)."""
    P = np.zeros(len(module.BASIS))
    for powers, value in {(2, 2): 1.0, (1, 1): -2.0 - 0.2, (0, 0): 1.0, (2, 0): 0.1,
                          (0, 2): 0.1, (1, 0): tilt}.items():  # fmt: skip
        P[[tuple(row) for row in module.BASIS].index(powers)] = value
    return P


def test_the_search_finds_every_minimum_and_the_lowest_as_a_dense_grid_does(dc_motor):
    box = np.array([[-2.0, 2.5], [-2.2, 2.0]])
    for tilt in (0.05, -0.05, 0.0):
        P = biquadratic(dc_motor, tilt)
        found = dc_motor._search(dc_motor._tensor(P), np.zeros(2), box)
        x, y = np.meshgrid(np.linspace(*box[0], 901), np.linspace(*box[1], 881), indexing="ij")
        grid = np.stack([x, y], -1)
        values = dc_motor._evaluate(dc_motor._tensor(P), grid)
        best = np.unravel_index(np.argmin(values), values.shape)
        assert found.certified and len(found.points) == 2
        assert found.values[0] <= values.min() + 1e-12
        np.testing.assert_allclose(found.points[0], grid[best], atol=0.01)
        assert np.all(np.diff(found.values) >= 0)  # lowest first
        for point in found.points:  # each a local minimum: the gradient vanishes there
            gradient = dc_motor._local_form(dc_motor._shift(dc_motor._tensor(P), point))[1]
            assert np.abs(gradient).max() < 1e-9
    # a box that holds one of them: the other is not reported, the edge is not a minimum
    found = dc_motor._search(dc_motor._tensor(biquadratic(dc_motor, 0.05)), np.zeros(2),
                             np.array([[0.0, 2.0], [0.0, 2.0]]))  # fmt: skip
    assert len(found.points) == 1 and np.all(found.points[0] > 0.5)


def test_the_profile_candidates_hold_every_local_minimum_and_the_least_value(dc_motor):
    """J is quadratic in each of dc_motor's unknowns: its local minima and least value over
    the box come from the profile's candidates (`_profile_candidates`), checked against a
    dense grid and against descents from the grid's local minima on random polynomials and
    on degenerate ones (a valley of minima, J linear or constant along the profiled
    unknown); the search certifies from them."""
    rng = np.random.default_rng(18)
    line = np.linspace(0.0, 1.0, 301)
    grid = np.stack(np.meshgrid(line, line, indexing="ij"), -1)
    box = np.array([[0.0, 1.0], [0.0, 1.0]])
    valley = np.zeros((3, 3))
    valley[0, 0], valley[1, 1], valley[2, 2] = 0.0625, -0.5, 1.0  # (x y - 1/4)^2
    linear = rng.standard_normal((3, 3))
    linear[:, 2] = 0.0  # no y^2: J linear in y
    flat = np.zeros((3, 3))
    flat[0, 0], flat[2, 0], flat[1, 0] = 1.0, 1.0, -1.0  # J = x^2 - x + 1 whatever y
    tensors = [rng.standard_normal(9) * 10.0 ** rng.uniform(-3, 3, 9) for _ in range(20)]
    for _ in range(60):  # costs: sums of squares of bilinear forms, each 0 somewhere near the box
        forms = rng.standard_normal((3, 2, 2))  # form[i, j]: the coefficient of x^i y^j
        x, y = rng.uniform(-0.2, 1.2, (2, 3))
        forms[:, 0, 0] = -(forms[:, 1, 0] * x + forms[:, 0, 1] * y + forms[:, 1, 1] * x * y)
        tensors.append(sum(signal.convolve2d(form, form) for form in forms).ravel())
    tensors += [valley.ravel(), linear.ravel(), flat.ravel(), flat.T.ravel()]
    for U in tensors:
        points, values = dc_motor._profile_candidates(U)
        scale = np.abs(U).sum()
        assert np.all((points >= 0.0) & (points <= 1.0))
        np.testing.assert_allclose(values, dc_motor._evaluate(U, points), atol=1e-14 * scale)
        assert values.min() <= dc_motor._evaluate(U, grid).min() + 1e-13 * scale  # no point lower
        found = dc_motor._search(U, np.zeros(2), box)
        assert found.certified and found.values[0] <= values.min() + 1e-10 * scale
        ends, minimum = dc_motor._descend(U, dc_motor._grid_minima(U))
        for end in ends[minimum]:  # every minimum a descent reaches is among the search's
            assert np.abs(found.points - end).max(1).min() < 1e-6
    assert dc_motor._profile_candidates(valley.ravel())[1].min() == pytest.approx(0.0, abs=1e-15)


def test_the_search_agrees_with_the_exact_univariate_minimiser(absorber, noisy_absorber):
    """The same search (its code serves any number of unknowns) on the absorber's cost, whose
    two minima the companion-matrix roots give exactly."""
    t, u, y = noisy_absorber
    P = absorber.moments(t, u, y, C="(1+s)^4", offset=False, initial_state=False).criterion(
        absorber.theta()
    )
    found = absorber._search(P, np.zeros(1), np.array([[-1.0, 2.0]]))
    assert found.certified
    np.testing.assert_allclose(found.points[:, 0], absorber._local_minima(P, 0.0)[::-1], rtol=1e-9)
    assert found.points[0, 0] == pytest.approx(0.7246, abs=1e-4)


def test_fit_takes_vectors_and_dicts_and_reports_bounds_and_minima(dc_motor):
    t, u, y = record(motor_tf, MOTOR, 0.01, 60.0, 0.5, seed=3, snr_db=20)
    result = quiet(dc_motor.fit, t, u, y, hold="zoh")
    by_name = quiet(dc_motor.fit, t, u, y, hold="zoh", k0={"jl": 10.0, "ra": 1.0},
                    bounds={"ra": (0.1, 10.0), "jl": (1.0, 100.0)})  # fmt: skip
    np.testing.assert_allclose(by_name.k, result.k, rtol=1e-8)
    np.testing.assert_array_equal(result.bounds, [[0.1, 10.0], [1.0, 100.0]])  # the default box
    # the least-squares cost's global minimum: the exact descent's start, within a percent
    assert result.minima.shape[1] == 2 and np.allclose(result.minima[0], result.k, rtol=0.01)
    assert np.all(np.abs(result.k - MOTOR) < 4 * result.k_se)
    np.testing.assert_allclose(result.k_se, np.sqrt(np.diag(result.covariance)))
    alone = quiet(dc_motor.fit, t, u, y, hold="zoh", uncertainty=False)  # the estimate alone
    np.testing.assert_array_equal(alone.k, result.k)
    assert alone.k_se.shape == (2,) and np.isnan(alone.k_se).all() and np.isnan(alone.ci).all()
    narrow = quiet(dc_motor.fit, t, u, y, hold="zoh", bounds=[(0.1, 10.0), (1.0, 5.0)])
    assert narrow.k[1] == 5.0 and any("jl = 5 is at the upper bound" in w for w in narrow.warnings)
    for bad, message in (
        (dict(bounds=[(0.1, 10.0)]), "a .lo, hi. pair for each of the 2 unknowns"),
        (dict(bounds={"ra": (1.0, 1.0)}), r"bounds\['ra'\] must be \(lo, hi\) with lo < hi"),
        (dict(bounds={"ra": (0.0, math.inf)}), "must be finite with several unknowns"),
        (dict(bounds={"r": (0.0, 1.0)}), "'r' is not an unknown of dc_motor"),
        (dict(k0=[1.0]), "must give the 2 unknowns ra, jl"),
        (dict(k0={"ra": 1.0}), "no value for the unknown 'jl'"),
        (dict(k0=[1.0, math.nan]), r"k0\[1\] \(jl\) must be finite"),
    ):
        with pytest.raises(ValueError, match=message):
            dc_motor.fit(t, u, y, **bad)
    with pytest.raises(ValueError, match="must give the 2 unknowns"):
        dc_motor.simulate(t, u, 1.0)
    np.testing.assert_array_equal(
        dc_motor.simulate(t, u, {"jl": 10.0, "ra": 1.0}), dc_motor.simulate(t, u, MOTOR)
    )


def test_estimate_follows_the_stationary_point_and_the_tracker_agrees(dc_motor):
    """estimate in vector form: with beta = 0 its final k^ is the minimiser of the cost (the
    global one, found by the search), the same from any chunking by the Tracker, which
    pickles."""
    t, u, y = record(motor_tf, MOTOR, 0.01, 20.0, 0.5, seed=1, snr_db=30)
    run = quiet(dc_motor.estimate, t, u, y, k0=[0.5, 5.0], hold="zoh", beta=0.0, S0=1e-6)
    assert run.ok and run.khat.shape == (t.size, 2) and run.at_global
    np.testing.assert_allclose(run.global_k[-1], run.k, rtol=1e-6)
    assert np.isnan(run.global_k[:-1]).all()  # the global search runs at the end only
    np.testing.assert_allclose(run.k, MOTOR, rtol=0.05)
    H = run.J[-1]
    assert H.shape == (2, 2) and np.linalg.eigvalsh(H).min() > 0
    assert run.cost(run.k) == pytest.approx(0.0, abs=1e-12)
    assert run.cost(run.k + [0.01, 0.0]) == pytest.approx(0.5 * H[0, 0] * 1e-4, rel=0.05)
    tracker = dc_motor.Tracker(k0={"ra": 0.5, "jl": 5.0}, hold="zoh", beta=0.0, S0=1e-6)
    for i in range(100):
        tracker.update(t[i], u[i], y[i])
    tracker = pickle.loads(pickle.dumps(tracker))
    for lo in range(100, t.size, 777):
        tracker.update(t[lo : lo + 777], u[lo : lo + 777], y[lo : lo + 777])
    np.testing.assert_allclose(tracker.k, run.k, rtol=1e-9)
    np.testing.assert_allclose(tracker.global_k, run.global_k[-1], rtol=1e-9)
    with pytest.raises(ValueError, match="engine='ode' integrates the paper's ODE for one unknown"):
        dc_motor.estimate(t, u, y, k0=[0.5, 5.0], engine="ode")
    weights = dc_motor.prior_weight(t, u, y, k0=MOTOR, hold="zoh")
    assert weights.shape == (2,) and np.all(weights > 0)


def test_batch_fits_carry_a_vector_per_record_and_pool_through_fit_records(dc_motor, tmp_path,
                                                                         capsys):  # fmt: skip
    """mtt.batch with two unknowns: each record's k and k_se are lists in the order of the
    unknowns (JSON), the per-record table and CSV have a column per unknown, and the pooled
    fit (the module's fit_records over the workers' sums) is the module's fit of them all."""
    import json

    from mtt.batch import fit_many
    from mtt.cli.main import main

    paths, records = [], []
    for seed in range(3):
        t, u, y = record(motor_tf, MOTOR, 0.02, 40.0, 0.5, seed=seed, snr_db=20)
        path = tmp_path / f"run_{seed}.csv"
        np.savetxt(path, np.column_stack([t, u, y]), delimiter=",", header="t,u,y", comments="")
        paths.append(str(path))
        records.append((t, u, y))
    batch = quiet(fit_many, "models/dc_motor.bg", paths, hold="zoh")
    for outcome, (t, u, y) in zip(batch, records, strict=True):
        np.testing.assert_array_equal(outcome.result.k, quiet(dc_motor.fit, t, u, y, hold="zoh").k)
        assert len(outcome.record()["k"]) == 2 and len(outcome.record()["k_se"]) == 2
    pooled = quiet(fit_many, "models/dc_motor.bg", paths, hold="zoh", pooled=True).pooled
    direct = quiet(dc_motor.fit, *(list(part) for part in zip(*records, strict=True)), hold="zoh")
    np.testing.assert_allclose(pooled.k, direct.k, rtol=1e-12)
    np.testing.assert_allclose(pooled.k_se, direct.k_se, rtol=1e-12)
    table = tmp_path / "table.csv"
    pattern = str(tmp_path / "run_*.csv")
    assert main(["fit", "models/dc_motor.bg", "--data", pattern, "--hold", "zoh", "--csv",
                 str(table)]) == 0  # fmt: skip
    lines = capsys.readouterr().out.splitlines()
    assert lines[1].split() == [
        "file",
        "ra",
        "ra",
        "k_se",
        "jl",
        "jl",
        "k_se",
        "fit",
        "%",
        "warnings",
    ]
    assert lines[2].split()[1] == f"{batch[0].result.k[0]:.6g}"
    header = table.read_text().splitlines()[0].split(",")
    assert header[:9] == ["file", "k_ra", "k_se_ra", "ci_low_ra", "ci_high_ra", "k_jl", "k_se_jl",
                          "ci_low_jl", "ci_high_jl"]  # fmt: skip
    assert main(["fit", "models/dc_motor.bg", "--data", pattern, "--hold", "zoh", "--json"]) == 0
    found = json.loads(capsys.readouterr().out)["records"]
    assert [r["k"] for r in found] == [list(outcome.result.k) for outcome in batch]


def test_a_locally_identifiable_model_has_both_minima_and_a_warning():
    """The RC ladder with both resistances unknown: (r1, r2) and (r2/2, 2 r1) give the same
    transfer function (mtt identifiability: local, 2 solutions). The search finds both
    minima of the criterion, and the fit says the data cannot tell them apart."""
    import mtt

    ladder = mtt.load(Path(__file__).parent / "data" / "identifiability" / "ladder.bg")
    module = ladder.estimator()
    t = np.linspace(0.0, 30.0, 3001)
    u = module.input_signal("prbs", t, period=0.5)
    y = module.simulate(t, u, [1.0, 3.0], hold="zoh")
    with pytest.warns(
        module.EstimationWarning,
        match=r"another local minimum of the prediction error, r1 = 1(\.[45]\d*)?, r2 = [123]\b",
    ):
        result = module.fit(t, u, y, hold="zoh")
    found = result.minima[np.argsort(result.minima[:, 0])]
    np.testing.assert_allclose(found, [[1.0, 3.0], [1.5, 2.0]], rtol=1e-3)


def test_a_valley_of_minima_or_a_flat_criterion_is_a_message_not_a_linalg_error(dc_motor):
    """r and c of an RC filter (only r c is identifiable: the criterion's minima form the
    valley r c = 1e-3), and records that excite nothing: no local minimum is reported, fit
    says why (the search solved with a singular Hessian, a LinAlgError, before)."""
    import mtt

    rc = mtt.load(Path(__file__).parent / "data" / "identifiability" / "rc.bg").estimator()
    t = np.linspace(0.0, 0.05, 5001)
    u = rc.input_signal("prbs", t, period=0.002)
    clean = rc.simulate(t, u, [1000.0, 1e-6], hold="zoh")
    for seed in range(3):
        y = clean + 0.01 * np.random.default_rng(seed).standard_normal(t.size)
        for method in ("pem", "iv"):
            # no local minimum (the valley leaves the box), or a point of it where the
            # valley meets the box's edge (rounding decides): either way not identifiable
            result = quiet(rc.fit, t, u, y, hold="zoh", method=method)
            assert not result.ok and np.isinf(result.k_se).all()
            if np.isnan(result.k).all():
                assert result.minima.shape == (0, 2)
                assert "no local minimum within the bounds (it is flat along some direction" in (
                    result.message
                )
            else:
                assert result.message.startswith(
                    "the unknowns r, c are not identifiable from these data"
                )
    t = np.linspace(0.0, 20.0, 2001)
    zero, one = np.zeros_like(t), np.ones_like(t)
    result = quiet(dc_motor.fit, t, zero, zero)
    assert not result.ok and np.isinf(result.k_se).all()
    assert "the information matrix is singular" in result.message
    assert any("the input is zero: it excites nothing" in text for text in result.warnings)
    for options in ({}, dict(offset=False, initial_state=False)):  # a step, no response
        result = quiet(dc_motor.fit, t, one, zero, **options)  # (where it ends is rounding's)
        assert not result.ok
        assert any(text.startswith("the output is constant") for text in result.warnings)
