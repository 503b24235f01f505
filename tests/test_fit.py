"""The batch fit of the generated modules on noisy data: refined instrumental variables,
uncertainty, offsets and initial state, several records, warnings.

Records are simulated here with scipy.signal.lsim from the transfer functions written out
in method.md, not with the modules' own simulate; the Monte Carlo figures (bias, k_se
against the spread, coverage) are in bench/fit.py, these tests check single records with
fixed seeds against independent computations.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from scipy import optimize, signal


def dc_drive_tf(k: float):
    return [10 * k, 0, 10], np.polyadd(k * np.array([1, 10, 11, 10, 0]), [1, 10, 10])


def prbs(t: np.ndarray, hold: float, seed: int) -> np.ndarray:
    """+-1 switching at random at multiples of `hold` (independent of the modules' PRBS)."""
    levels = np.random.default_rng(seed).choice([-1.0, 1.0], int(t[-1] / hold) + 1)
    return levels[np.floor(t / hold + 1e-9).astype(int)]


def record(seed: int, snr_db: float | None, t_end: float = 200.0, x0=None, offset=0.0):
    """The DC drive (k = 10) driven by a held PRBS, sampled every 0.02 s, exact (zoh)."""
    t = 0.02 * np.arange(round(t_end / 0.02) + 1)
    u = prbs(t, 1.0, seed)
    system = signal.StateSpace(*signal.tf2ss(*dc_drive_tf(10.0)))
    y = signal.lsim(system, u, t, X0=x0, interp=False)[1] + offset
    if snr_db is not None:
        noise = math.sqrt(np.var(y) / 10 ** (snr_db / 10))
        y = y + noise * np.random.default_rng(100 + seed).standard_normal(t.size)
    return t, u, y


def quiet_fit(module, *args, **options):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", module.EstimationWarning)
        return module.fit(*args, **options)


def test_iv_is_the_output_error_least_squares_estimate(dc_drive):
    """The refined instrumental-variable estimate is asymptotically the output-error
    least-squares one: within a fraction of its standard error of scipy's least squares of
    y - lsim(G(k)) u, and its k_se is the output-error one, sigma / |dy/dk|, here by finite
    differences of lsim."""
    t, u, y = record(1, 10.0)
    result = quiet_fit(dc_drive, t, u, y, hold="zoh", offset=False, initial_state=False)

    def residuals(p):
        return y - signal.lsim(dc_drive_tf(p[0]), u, t, interp=False)[1]

    reference = optimize.least_squares(residuals, [9.0], x_scale=[10.0], xtol=1e-12)
    assert result.iterations < 10
    assert result.k == pytest.approx(reference.x[0], abs=0.25 * result.k_se)
    r = residuals(reference.x)
    step = 1e-5 * reference.x[0]
    slope = (residuals(reference.x + step) - residuals(reference.x - step)) / (2 * step)
    k_se = math.sqrt(r @ r / (t.size - 1) / (slope @ slope))
    assert result.k_se == pytest.approx(k_se, rel=0.02)
    assert result.ci == pytest.approx((result.k - 1.96 * k_se, result.k + 1.96 * k_se), rel=1e-3)
    assert result.noise_std == pytest.approx(math.sqrt(r @ r / (t.size - 1)), rel=1e-3)
    assert result.fit_percent == pytest.approx(
        100 * (1 - np.linalg.norm(r) / np.linalg.norm(y - y.mean())), abs=0.01
    )


def test_least_squares_is_biased_by_noise_and_iv_is_not(dc_drive):
    """Four records at 10 dB: the least-squares estimates sit well below 10 (the equation
    error is correlated with the filtered noisy output), the IV ones around it; each k_se
    is near the spread the Monte Carlo shows (bench/fit.py)."""
    ls, iv = [], []
    for seed in range(4):
        t, u, y = record(seed, 10.0, t_end=400.0)
        ls.append(quiet_fit(dc_drive, t, u, y, hold="zoh", method="ls").k)
        iv.append(quiet_fit(dc_drive, t, u, y, hold="zoh").k)
    assert np.mean(ls) < 9.9 and np.mean(iv) == pytest.approx(10.0, abs=0.06)


def test_offset_and_initial_state_are_nuisances(dc_drive):
    """A non-zero initial state and a 1 % output offset, noise-free: the defaults estimate
    both and recover k; without them the estimate is far off and the residuals say so."""
    x0 = np.random.default_rng(5).standard_normal(4)
    t, u, y = record(3, None, t_end=100.0, x0=x0)
    y = y + 0.01 * np.abs(y).max()
    result = quiet_fit(dc_drive, t, u, y, hold="zoh")
    assert result.ok and result.k == pytest.approx(10.0, rel=2e-4)
    assert result.offsets[0] == pytest.approx(
        0.01 * np.abs(y - 0.01 * np.abs(y).max()).max(), rel=0.05
    )
    plain = quiet_fit(dc_drive, t, u, y, hold="zoh", offset=False, initial_state=False,
                      noise="white")  # fmt: skip
    assert abs(plain.k - 10.0) > 0.5
    assert any("residuals are far from white" in text for text in plain.warnings)
    # a noise model reads the misfit as coloured noise: an interval that says so
    coloured = quiet_fit(dc_drive, t, u, y, hold="zoh", offset=False, initial_state=False)
    assert coloured.noise.orders != (0, 0) and abs(coloured.k - 10.0) < 2 * coloured.k_se
    assert result.simulate(t, u) == pytest.approx(
        dc_drive.simulate(t, u, result.k, hold="zoh") + result.offsets[0]
    )


def test_without_uncertainty_the_estimate_is_the_same_alone(dc_drive):
    """uncertainty=False skips the validation: the same k to the bit, for both methods, and
    NaN (not a number that looks measured) where the validation would have said more."""
    t, u, y = record(3, 20.0, t_end=100.0, offset=0.3)
    for method in ("iv", "ls"):
        whole = quiet_fit(dc_drive, t, u, y, hold="zoh", method=method)
        alone = quiet_fit(dc_drive, t, u, y, hold="zoh", method=method, uncertainty=False)
        assert alone.k == whole.k and alone.ok and whole.ok
        assert alone.iterations == whole.iterations
        np.testing.assert_array_equal(alone.coefficients, whole.coefficients)
        assert math.isnan(alone.k_se) and all(math.isnan(v) for v in alone.ci)
        assert math.isnan(alone.fit_percent) and math.isnan(alone.noise_std)
        assert math.isnan(alone.offsets[0])  # the operating point is estimated in validation
        assert "uncertainty=False" in alone.message
        with pytest.raises(ValueError, match="operating point was not estimated"):
            alone.simulate(t, u)
    at_rest = quiet_fit(dc_drive, t, u, y - 0.3, hold="zoh", offset=False, uncertainty=False)
    assert at_rest.offsets == (0.0,) and at_rest.simulate(t, u)[0] == 0.0
    low = quiet_fit(dc_drive, t, u, y, hold="zoh", bounds=(1.0, 5.0), uncertainty=False)
    assert low.k == 5.0 and any("upper bound" in text for text in low.warnings)


def test_several_records_add_their_moments(dc_drive):
    first, second = record(1, 20.0, t_end=100.0), record(2, 20.0, t_end=60.0)
    both = quiet_fit(
        dc_drive, *[list(part) for part in zip(first, second, strict=True)], hold="zoh"
    )
    alone = [quiet_fit(dc_drive, *part, hold="zoh") for part in (first, second)]
    assert both.k_se < min(fit.k_se for fit in alone)
    assert both.k == pytest.approx(10.0, abs=3 * both.k_se)
    assert len(both.residuals) == 2 and both.residuals[1].size == first[0].size * 0 + second[0].size
    # the moments of one step add: two records' statistics are the sum of each one's
    parts = [dc_drive.moments(*part, k=9.5, hold="zoh") for part in (first, second)]
    total = parts[0] + parts[1]
    assert total.samples == first[0].size + second[0].size and total.nuisances == 10
    assert sum(parts).criterion(dc_drive.theta()) == pytest.approx(
        total.criterion(dc_drive.theta())
    )
    np.testing.assert_allclose(total.ZX, parts[0].ZX + parts[1].ZX)
    with pytest.raises(ValueError, match="only the moments of one kind of step"):
        parts[0] + dc_drive.moments(*first, hold="zoh")


def issued(module, *args, **options) -> list[str]:
    """The EstimationWarnings that module.fit issues, and check that the result lists them."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = module.fit(*args, **options)
    said = [str(w.message) for w in caught if issubclass(w.category, module.EstimationWarning)]
    assert said == list(result.warnings)
    return said


def test_warnings_a_user_can_act_on(dc_drive):
    t, u, y = record(1, 30.0, t_end=100.0)
    assert any("looks held between samples" in text for text in issued(dc_drive, t, u, y))
    assert issued(dc_drive, t, u, y, hold="zoh") == []
    edge = quiet_fit(dc_drive, t, u, y, hold="zoh", bounds=(0.0, 9.0))
    assert edge.k == 9.0 and any("at the upper bound" in text for text in edge.warnings)
    fast = issued(dc_drive, t, u, y, hold="zoh", method="ls", C=0.05)
    assert any("the filter is too fast for the sampling" in text for text in fast)
    zero = quiet_fit(dc_drive, t, 0 * u, 0 * y)
    assert not zero.ok and math.isnan(zero.k) and "no information" in zero.message
    assert any("the input is zero" in text for text in zero.warnings)
    short = quiet_fit(dc_drive, t[:3], u[:3], y[:3], offset=False, initial_state=False)
    assert any("only 3 samples" in text for text in short.warnings)
    assert any("the record is short" in text for text in short.warnings)
    step = np.ones_like(t[:501])
    clean = dc_drive.simulate(t[:501], step, 10.0)
    flat = quiet_fit(
        dc_drive, t[:501], step, clean + 1e-3 * np.random.default_rng(0).standard_normal(501)
    )
    assert any(
        "excites nothing that the initial state and offset do not explain" in w
        for w in flat.warnings
    )


def test_bad_records_are_clear_errors(dc_drive):
    t, u, y = record(1, None, t_end=2.0)
    for arguments, message in [
        (([t, t], [u], [y, y]), r"u must be a list of 2 arrays"),
        (([t, t[:5]], [u, u], [y, y]), r"t\[1\], u\[1\], y\[1\] must have the same length"),
        ((t[:5], u[:5], y[:5]), r"5 samples: too few to determine k and 5 nuisance"),
        (
            (t * 1e-300, u, y),
            r"^the record spans 2e-300 time units with samples 2e-302 apart: are "
            r"the times in the model's unit \(seconds\)\?",
        ),
    ]:
        with pytest.raises(ValueError, match=message):
            dc_drive.fit(*arguments)
    with pytest.raises(ValueError, match="method must be one of 'pem', 'iv', 'ls'"):
        dc_drive.fit(t, u, y, method="oe")
    with pytest.raises(ValueError, match="record must be a whole number from 0 to 0"):
        quiet_fit(dc_drive, t, u, y).simulate(t, u, record=1)


def test_input_signals_and_noise(dc_drive):
    t = np.linspace(0.0, 100.0, 10001)
    u = dc_drive.input_signal("prbs", t, amplitude=2.0, period=1.0, seed=3)
    assert set(np.unique(u)) == {-2.0, 2.0}
    jumps = t[1:][np.diff(u) != 0]
    assert np.allclose(jumps, np.round(jumps)) and jumps.size > 20
    assert not np.array_equal(
        u, dc_drive.input_signal("prbs", t, amplitude=2.0, period=1.0, seed=4)
    )
    square = dc_drive.input_signal("square", t, period=10.0)
    assert (
        square[0] == 1.0
        and square[t.searchsorted(5.5)] == -1.0
        and square[t.searchsorted(10.2)] == 1.0
    )
    multisine = dc_drive.input_signal("multisine", t, amplitude=0.5, period=50.0)
    assert np.abs(multisine).max() == pytest.approx(0.5)
    assert multisine[:5000] == pytest.approx(multisine[5000:-1])  # periodic in 50 s
    assert dc_drive.input_signal("step", t, amplitude=3.0) == pytest.approx(3.0 * np.ones_like(t))
    clean = np.sin(t)
    noisy = dc_drive.with_noise(clean, 20.0, seed=1)
    assert np.var(clean) / np.var(noisy - clean) == pytest.approx(100.0, rel=0.05)
    assert np.array_equal(noisy, dc_drive.with_noise(clean, 20.0, seed=1))
    with pytest.raises(ValueError, match="the signal kind must be one of"):
        dc_drive.input_signal("chirp", t)
    with pytest.raises(ValueError, match="y is constant"):
        dc_drive.with_noise(np.ones(5), 10.0)
    for snr in (-1e4, -6200.0):  # a ZeroDivisionError and inf noise
        with pytest.raises(ValueError, match=f"snr_db = {snr:g} makes noise of standard"):
            dc_drive.with_noise(np.arange(5.0), snr)
    assert np.array_equal(dc_drive.with_noise(np.arange(5.0), 1e4), np.arange(5.0))
    with pytest.raises(ValueError, match=r"y\[2\] is -1e\+200: signals must stay within"):
        dc_drive.fit(np.arange(4.0), np.ones(4), np.array([0, 1, -1e200, 0]))


@pytest.mark.parametrize(
    "text,expected",
    [
        ("(1+s)^5", [1, 5, 10, 10, 5, 1]),
        ("(1 + 0.5s)**5", [1 / 32, 5 / 16, 5 / 4, 5 / 2, 5 / 2, 1]),
        ("(s + 1)^5 / 2", [0.5, 2.5, 5, 5, 2.5, 0.5]),
        ("s^5 + 5*s^4 + 10 s^3 + 10s^2 + 5s + 1", [1, 5, 10, 10, 5, 1]),
        ("-(-1-s)^5", [1, 5, 10, 10, 5, 1]),
    ],
)
def test_filter_text(dc_drive, text, expected):
    assert dc_drive.filter_polynomial(text) == pytest.approx(expected)


@pytest.mark.parametrize(
    "text,message",
    [
        ("(1+sqrt(-1)*s)^5", r"cannot read 'qrt\(-1\)\*s\)\^5' at character 5"),
        ("(1+s)^400", r"the exponent 400 must be a whole number from 0 to 24"),
        ("(1+s)^50", r"the exponent 50 must be a whole number from 0 to 24"),
        ("(1+s)^1e400", r"the exponent inf must be a whole number"),  # was an OverflowError
        ("(1+s)^2.5", r"the exponent 2.5 must be a whole number"),
        ("(1+1e-300*s)^5", r"its leading coefficient underflows to 0"),
        ("1e300*(1+s)^5*1e300", r"a coefficient overflows"),
        ("(1+s)^5 (", r"expected a number, s or '\(', found the end"),
        ("auto", r"C='auto' is chosen from the data"),
    ],
)
def test_filter_text_errors(dc_drive, text, message):
    with pytest.raises(ValueError, match=message):
        dc_drive.filter_polynomial(text)
    with pytest.raises(ValueError, match="out of range: T\\^5 underflows"):
        dc_drive.filter_polynomial(1e-300)


def test_read_csv(dc_drive, tmp_path):
    good = tmp_path / "good.csv"
    good.write_bytes("\ufefftime,v,w\n0,1,2\n0.5,1e-3,-2.5\n".encode())
    assert [list(c) for c in dc_drive.read_csv(good, ("time", "w", "v"))] == [
        [0, 0.5],
        [2, -2.5],
        [1, 1e-3],
    ]
    cases = {
        "t,u,y\n": "no data: the file has a header row and nothing after it",
        "t,u,y,u\n0,1,2,3\n": "the header names the column 'u' twice",
        "t,u,y\n0,1_0,2\n": r"bad.csv:2: column 'u' holds '1_0', not a number",
        "t,u,y\n0,1\n": r"bad.csv:2: 2 values where the header names 3 columns",
        "t,u,y\n0,1,inf\n": r"bad.csv:2: column 'y' holds 'inf', not a number",
        "t,u,y\n0,1,1e400\n": r"bad.csv:2: column 'y': 1e400 is out of range",
        "t,u\n0,1\n": r"bad.csv:1: no column 'y' \(the header names t, u\)",
        "": "the file is empty",
        "t,u,y\n0,\u0663,2\n": r"bad.csv:2: column 'u' holds '\u0663', not a number",  # ASCII only
    }
    bad = tmp_path / "bad.csv"
    for text, message in cases.items():
        bad.write_text(text)
        with pytest.raises(ValueError, match=message):
            dc_drive.read_csv(bad)
    bad.write_bytes(b"t,u,y\n0,\xff,1\n")
    with pytest.raises(ValueError, match=r"bad.csv: not UTF-8 text"):
        dc_drive.read_csv(bad)


@pytest.mark.parametrize(
    "text",
    [
        "t,u,y\n0,1,2\n1,3,4\n",
        "t,u,y\r\n0,1,2\r\n1,3,4\r\n",
        "\ufeff y, x ,u,t\n 2 ,9, +1.,0\n\n4E+3,9,.5,1e-2\n\n",
        '"t",u,y\n"0",1,2\n',  # quoted: the checked reader's
        "\nt,u,y\n0,1,2\n",  # a blank line first: the checked reader's
    ],
)
def test_read_csv_fast_and_checked_readers_agree(dc_drive, tmp_path, text):
    """Plain files go through numpy's parser, anything else through the checked reader:
    the same values to the bit either way."""
    path = tmp_path / "data.csv"
    path.write_bytes(text.encode())
    checked = dc_drive._read_csv_checked(path, ("t", "u", "y"))
    for got, expected in zip(dc_drive.read_csv(path), checked, strict=True):
        np.testing.assert_array_equal(got, expected)
    rng = np.random.default_rng(5)
    values = rng.standard_normal((500, 3)) * 10.0 ** rng.integers(-300, 300, (500, 3))
    path.write_text("t,u,y\n" + "".join(f"{a!r},{b!r},{c!r}\n" for a, b, c in values.tolist()))
    assert dc_drive._read_plain_csv(path, ("t", "u", "y")) is not None
    for got, column in zip(dc_drive.read_csv(path), values.T, strict=True):
        np.testing.assert_array_equal(got, column)


def test_the_module_command_line_fits_several_files(dc_drive, tmp_path, capsys):
    paths = []
    for seed in (1, 2):
        t, u, y = record(seed, 20.0, t_end=60.0)
        path = tmp_path / f"run{seed}.csv"
        path.write_text(
            "time,volts,speed\n"
            + "".join(f"{a},{b},{c}\n" for a, b, c in zip(t, u, y, strict=True))
        )
        paths.append(str(path))
    status = dc_drive.main(
        ["fit", *paths, "--columns", "time,volts,speed", "--hold", "zoh", "--json"]
    )
    out, err = capsys.readouterr()
    assert status == 0 and err == ""
    import json

    result = json.loads(out)
    assert result["ok"] and result["k"] == pytest.approx(10.0, abs=4 * result["k_se"])
    assert len(result["offsets"]) == 2 and result["method"] == "pem" and result["warnings"] == []
    status = dc_drive.main(["fit", paths[0], "--columns", "time,volts,speed", "--filter", "(1+s)^5",
                            "--method", "ls"])  # fmt: skip
    out, err = capsys.readouterr()
    assert (
        status == 0
        and out.startswith("k = ")
        and "dc_drive.py fit: warning: the input looks held" in err
    )
    status = dc_drive.main(["fit", paths[0]])
    out, err = capsys.readouterr()
    assert status == 2 and "no column 't' (the header names time, volts, speed)" in err
    # negative numbers are values, not options (argparse took -inf and -1e3 for options)
    for argv, message in (
        (["estimate", paths[0], "--k0", "-inf"], "--k0 must be finite, not -inf"),
        (["fit", paths[0], "--k0", "-1e3", "--bounds", "-1e-3", "-1e3"], "not (-0.001, -1000.0)"),
    ):
        status = dc_drive.main([*argv, "--columns", "time,volts,speed"])
        out, err = capsys.readouterr()
        assert status == 2 and message in err and "expected one argument" not in err


def test_the_module_command_line_fails_in_json_as_mtt_fit_does(dc_drive, tmp_path, capsys):
    import json

    import mtt
    from mtt.cli.main import main as mtt_main

    missing = str(tmp_path / "missing.csv")
    status = dc_drive.main(["fit", missing, "--json"])
    record = json.loads(capsys.readouterr().out)
    assert status == 2 and record["ok"] is False and record["model"] == "dc_drive"
    (error,) = record["errors"]
    assert error == {"file": missing, "kind": "io", "line": None, "column": None,
                     "message": f"{missing}: No such file or directory", "notes": []}  # fmt: skip
    # mtt fit's record of the same failure has the same fields
    assert mtt_main(["fit", str(mtt.example("dc_drive")), "--data", missing, "--json"]) == 2
    (theirs,) = json.loads(capsys.readouterr().out)["errors"]
    assert theirs == error


def test_the_report_shows_an_estimated_offset_even_when_it_is_exactly_zero(dc_drive):
    """An estimated offset of exactly 0 (an offset column that the projection dropped, or a
    record without one) is still an estimate, and the report says it; an offset that was not
    estimated is not reported."""
    from dataclasses import replace

    from mtt.present.fits import fit_text

    class Source:
        note = "a record"

    t, u, y = record(1, None, t_end=20.0)
    fitted = quiet_fit(dc_drive, t, u, y)
    assert fitted.offset_fitted
    text = fit_text(dc_drive, [Source()], replace(fitted, offsets=(0.0,)))
    assert "  output offset at rest: 0\n" in text + "\n"
    fitted = quiet_fit(dc_drive, t, u, y, offset=False)
    assert not fitted.offset_fitted
    assert "output offset" not in fit_text(dc_drive, [Source()], fitted)
