"""What `fit` and `estimate` say of records that cannot give a good estimate: data out of
floating point's range, records too short for the automatic filter, an input that excites
too little, a record whose estimate a point far outside its interval fits better, and two
values of one unknown that the data cannot tell apart."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from mtt.cli.main import main

ROOT = Path(__file__).resolve().parent.parent
DC_DRIVE = str(ROOT / "models" / "dc_drive.bg")


def said(module, function, *args, **options) -> tuple[object, list[str]]:
    """The result and the EstimationWarnings issued (which the result lists, in order)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = function(*args, **options)
    texts = [str(w.message) for w in caught if issubclass(w.category, module.EstimationWarning)]
    assert texts == list(result.warnings)
    return result, texts


def prbs_record(module, t_end: float, snr_db: float | None, seed: int = 1, period: float = 0.2):
    t = np.arange(0.0, t_end + 1e-9, 0.01)
    u = module.input_signal("prbs", t, period=period)
    y = module.simulate(t, u, 10.0, hold="zoh")
    return t, u, y if snr_db is None else module.with_noise(y, snr_db, seed=seed)


@pytest.mark.parametrize(
    "scale,options,message",
    [
        (1e-200, {"C": "(1+s)^5"}, r"^the record spans 1e-199 time units with samples 1e-202 "
         r"apart, and the model's time constants at k = 10 are 0\.112 to 9\.99, all over 1e\+06 "
         r"times the record: it sees none of them move: are the times in the model's unit"),
        (1e-30, {}, r"^the record spans 1e-29 time units .* are the times in the model's unit"),
        (1e-300, {"C": "(1+s)^5", "method": "ls"}, r"are the times in the model's unit"),
        (1e12, {}, r"all under 1/1e\+06 of a sampling interval: every mode dies out between "
         r"samples: are the times in the model's unit \(seconds\)\?$"),
    ],
)  # fmt: skip
def test_times_out_of_scale_are_clear_errors(dc_drive, scale, options, message):
    """Times in the wrong unit made the moments overflow: numpy's LinAlgError ('SVD did not
    converge') escaped from fit, and the command line printed it after LAPACK's own lines.
    The moments are now exact in any unit: the fit says so from the model's time constants
    against the record's (it had relied on the moments overflowing)."""
    t, u, y = prbs_record(dc_drive, 10.0, None)
    with pytest.raises(ValueError, match=message):
        dc_drive.fit(t * scale, u, y, hold="zoh", **options)


def test_times_far_too_long_are_said(dc_drive):
    """Times 1e10 too long: the moments overflow and the error asks about the unit, or,
    where the filter's cascade keeps them finite, the fit says the record is short."""
    t, u, y = prbs_record(dc_drive, 10.0, None)
    try:
        fitted, texts = said(dc_drive, dc_drive.fit, t * 1e10, u, y, hold="zoh", offset=False,
                             initial_state=False)  # fmt: skip
    except ValueError as error:
        assert "are the times in the model's unit (seconds)?" in str(error)
    else:
        assert any(text.startswith("the record is short: it spans 1e+11") for text in texts)


def test_a_model_file_without_the_unknowns_value_fits_without_k0(dc_drive, monkeypatch):
    """The time-scale check looks at the model where the fit starts; with neither k0 nor a
    value in the model file there is no such point, and the fit goes on (it raised a
    TypeError from K(None))."""
    monkeypatch.setattr(dc_drive, "TRUE_VALUE", None)
    t, u, y = prbs_record(dc_drive, 40.0, 40.0)
    for C in ("auto", "(1+s)^5"):
        found = dc_drive.fit(t, u, y, hold="zoh", C=C)
        assert found.ok and abs(found.k - 10) < 4 * found.k_se


def test_values_out_of_range_are_clear_errors(dc_drive, tmp_path, capsys):
    t, u, y = prbs_record(dc_drive, 10.0, 20.0)
    for arguments, message in [
        ((t, u, y * 1e120), r"^y reaches at most 9\.09e\+119 in magnitude: .* would overflow"),
        ((t, u, y * 1e200), r"^y\[767\] is 9\.09402e\+199: signals must stay within 1e\+150"),
        ((t, u * 1e-200, y), r"^u reaches at most 1e-200 in magnitude: .* would underflow"),
        (([t, t], [u, u], [y, y * 1e-300]), r"^y\[1\] reaches at most 9\.09e-301 in magnitude"),
    ]:
        with pytest.raises(ValueError, match=message):
            dc_drive.fit(*arguments, hold="zoh")
    path = tmp_path / "scaled.csv"
    rows = zip((t * 1e-200).tolist(), u.tolist(), y.tolist(), strict=True)
    path.write_text("t,u,y\n" + "".join(f"{a!r},{b!r},{c!r}\n" for a, b, c in rows))
    status = main(["fit", DC_DRIVE, "--data", str(path), "--filter", "(1+s)^5"])
    err = capsys.readouterr().err
    assert status == 2 and "are the times in the model's unit" in err and "SVD" not in err


def test_the_automatic_filter_on_a_record_too_short_warns(dc_drive):
    """Three samples: C='auto' cannot keep its time constant within 10 sampling intervals
    and a tenth of the record; estimate gave 8.3e-6 for 10 without a word."""
    t, u, y = prbs_record(dc_drive, 0.02, None)
    run, texts = said(dc_drive, dc_drive.estimate, t, u, y, k0=5.0, C="auto")
    assert abs(run.k - 10.0) > 5 and len(texts) == 1
    assert texts[0].startswith("the record is too short for C='auto': it spans 2 sampling")
    fitted, texts = said(dc_drive, dc_drive.fit, t, u, y, method="ls", offset=False,
                         initial_state=False)  # fmt: skip
    assert any(text.startswith("the record is too short for C='auto'") for text in texts)
    t, u, y = prbs_record(dc_drive, 1.0, None)  # 100 intervals: the filter fits
    assert said(dc_drive, dc_drive.estimate, t, u, y, k0=5.0, C="auto")[1] == []


def test_an_input_that_excites_too_little_warns_and_exact_data_do_not(dc_drive):
    t = np.arange(0.0, 200.0, 0.01)
    u = np.sin(t)  # one frequency: the filtered input's moments are singular
    y = dc_drive.simulate(t, u, 10.0)
    for method in ("iv", "ls"):
        fitted, texts = said(dc_drive, dc_drive.fit, t, u, dc_drive.with_noise(y, 30.0),
                             method=method)  # fmt: skip
        assert texts and texts[0].startswith("the input does not excite the system enough")
    t, u, y = prbs_record(dc_drive, 100.0, None)
    # noise-free, least squares: the regressors' moments are singular along theta(k) only;
    # its cost is exact for the interpolated output, and the exact output error sees it
    fitted, texts = said(dc_drive, dc_drive.fit, t, u, y, hold="zoh", method="ls")
    assert fitted.k == pytest.approx(10.0, rel=1e-5) and not fitted.ok
    assert len(texts) == 1 and texts[0].startswith("the model file's value, k = 10, fits the")
    fitted, texts = said(dc_drive, dc_drive.fit, t, u, y, hold="zoh")  # the exact fit
    assert fitted.ok and fitted.k == pytest.approx(10.0, rel=1e-9) and texts == []


def test_a_short_noisy_record_is_not_presented_as_a_precise_estimate(dc_drive):
    """3 s of a DC drive whose slow time constant is 11 s, at 10 dB: the offset and initial
    state absorb the slow dynamics and the steps end near k = 0 with a tiny k_se (it was
    reported without a warning); the model file's k = 10 fits better, and the fit says so.
    The exact fit finds where the prediction error is least, far away, and says that the
    record determines k not at all: ok False (k_se beyond k, or what the nuisances leave of
    the information about k at the level of rounding, where k_se is rounding too)."""
    t, u, y = prbs_record(dc_drive, 3.0, 10.0)
    fitted, texts = said(dc_drive, dc_drive.fit, t, u, y, hold="zoh", method="iv")
    assert not fitted.ok and abs(fitted.k) < 0.01 and fitted.k_se < 1e-3
    assert "the model file's value, k = 10, fits the data better" in texts[0]
    assert "standard errors from the estimate: the record determines" in texts[0]
    fitted, texts = said(dc_drive, dc_drive.fit, t, u, y, hold="zoh")
    assert not fitted.ok
    assert (fitted.k_se > abs(fitted.k) and texts[0].startswith("k is poorly determined")) or (
        fitted.absorbed > 1 - 1e-10 and "is at the level of rounding: neither" in texts[0]
    )
    fitted, texts = said(dc_drive, dc_drive.fit, t, u, y, hold="zoh", method="ls")
    assert any("estimate: least squares is biased by output noise, or" in w for w in texts)
    t, u, y = prbs_record(dc_drive, 5.0, 10.0, seed=2)  # k = 5.8 +- 4.2: the profile is open
    fitted, texts = said(dc_drive, dc_drive.fit, t, u, y, hold="zoh")
    assert not fitted.ok and fitted.intervals == ("profile",)
    assert 1 < fitted.ci[0] < 10 and fitted.ci[1] == np.inf
    assert texts[0].startswith("the record does not bound k above: its profile likelihood rises")
    assert any(text.startswith("k is poorly determined by these data: k_se = ") for text in texts)
    t, u, y = prbs_record(dc_drive, 100.0, 10.0, period=1.0)  # a long record: nothing to say
    fitted, texts = said(dc_drive, dc_drive.fit, t, u, y, hold="zoh")
    assert texts == [] and fitted.k == pytest.approx(10.0, abs=3 * fitted.k_se)


GYRATOR = """\
model gyro "an RC load seen through an unknown gyrator"

unknown k = 2 "gyrator modulus"
param r = 3 "load resistance [ohm]"
param c = 0.5 "load capacitance [F]"

Se:v -> 1:a
1:a -> GY:k -> 0:b
0:b -> R:r
0:b -> C:c
1:a -> Df:i
"""


def test_two_values_of_one_unknown_the_data_cannot_tell_apart(tmp_path):
    """Through a gyrator, k and -k give the same transfer function 6 / (k^2 (3 s + 2)):
    both minima are found, and the fit says the data cannot choose; bounds can."""
    import mtt

    path = tmp_path / "gyro.bg"
    path.write_text(GYRATOR)
    module = mtt.load(Path(path)).estimator()
    t = np.linspace(0.0, 20.0, 2001)
    u = module.input_signal("prbs", t, period=0.5)
    y = module.with_noise(module.simulate(t, u, 2.0, hold="zoh"), 20.0, seed=1)
    fitted, texts = said(module, module.fit, t, u, y, hold="zoh")
    assert fitted.minima == pytest.approx([-abs(fitted.k), abs(fitted.k)], rel=1e-2)
    assert abs(fitted.k) == pytest.approx(2.0, abs=3 * fitted.k_se)
    assert len(texts) == 1 and texts[0].startswith(
        f"another local minimum of the prediction error, k = {-fitted.k:.6g} (from "
    )
    fitted, texts = said(module, module.fit, t, u, y, hold="zoh", bounds=(0.5, 5.0))
    assert fitted.k > 0 and texts == []


def test_the_command_line_says_when_no_minimum_lies_within_the_bounds(capsys):
    args = ["fit", DC_DRIVE, "--signal", "prbs", "--period", "1", "--t-end", "100",
            "--dt", "0.02", "--hold", "zoh", "--noise-snr", "20", "--bounds", "0:9"]  # fmt: skip
    status = main(args)
    out, err = capsys.readouterr()
    assert status == 1 and "  k = 9 ± " in out and "  not ok: k = 9 is at the upper bound" in out
    assert "local minima of the least-squares cost (the starts): none within the bounds" in out
    assert "mtt fit: warning: k = 9 is at the upper bound" in err


def test_a_constant_output_is_a_warning_not_a_silent_nan(dc_drive):
    """The input varies, the output does not (a wrong column, a sensor off): fit_percent is
    NaN, and the fit says why: not ok (the estimate answers rounding error)."""
    t = np.arange(0.0, 100.0, 0.02)
    u = dc_drive.input_signal("prbs", t, period=1.0)
    for method in ("pem", "iv", "ls"):
        fitted, texts = said(dc_drive, dc_drive.fit, t, u, np.ones_like(t), hold="zoh",
                             method=method)  # fmt: skip
        assert np.isnan(fitted.fit_percent) and not fitted.ok
        # no noise in a constant output: its residuals are the misfit (was AR(2))
        assert method != "pem" or fitted.noise.kind == "white"
        assert any(
            text.startswith("the output is constant: nothing in it responds") for text in texts
        )
    t, u, y = prbs_record(dc_drive, 100.0, 20.0, period=1.0)
    fitted, texts = said(dc_drive, dc_drive.fit, t, u, y, hold="zoh")
    assert 85 < fitted.fit_percent < 95 and texts == []


def test_errors_in_one_of_several_files_name_the_file(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    good = "t,u,y\n" + "".join(f"{i / 100},{(-1) ** (i // 50)},{i / 1000}\n" for i in range(500))
    Path("good.csv").write_text(good)
    Path("late.csv").write_text("t,u,y\n0,1,0\n\n0.02,1,0\n0.01,1,0\n0.03,1,0\n")
    Path("short.csv").write_text("t,u,y\n0,1,0\n0.01,1,0\n0.02,1,0\n")
    for data, message in [
        ("late.csv", "late.csv:5: the times (column 't') must increase strictly: 0.01 (data row 3) "
         "follows 0.02 (data row 2)"),
        ("short.csv", "record 1 (short.csv) has 3 samples: too few to determine k"),
    ]:  # fmt: skip
        status = main(["fit", DC_DRIVE, "--data", "good.csv",
                       "--data", data])  # fmt: skip
        err = capsys.readouterr().err
        assert status == 2 and f"mtt fit: error: {message}" in err
    status = main(["estimate", DC_DRIVE, "--data", "late.csv",
                   "--k0", "1"])  # fmt: skip
    assert status == 2 and "late.csv:5: the times (column 't') must" in capsys.readouterr().err


def test_the_independence_check_reads_an_input_changed_in_place_afresh(dc_drive):
    """The fit keeps the input's autocorrelations between its points: an input array
    changed in place (here reversed, so its sum and mean stay) must not be taken for the
    one it was."""
    rng = np.random.default_rng(3)
    u, errors = np.sin(0.05 * np.arange(400.0)) + 0.1 * np.arange(400.0) % 1, rng.normal(size=400)
    before = dc_drive._independence(errors, u)
    u[:] = u[::-1].copy()
    assert dc_drive._independence(errors, u) == dc_drive._independence(errors, u.copy())
    assert dc_drive._independence(errors, u) != before
