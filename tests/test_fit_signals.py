"""Estimation from several inputs and outputs (issue 21 item 2): each channel's Theta over
the common A(s), hand-derived; records simulated by scipy's lsim of mtt's own state space
(not by the code under test); the fit with a measured disturbance against the fit that
leaves it in the noise; unknowns that two sensors determine together and one does not."""

from __future__ import annotations

import json
import warnings
from functools import cache
from pathlib import Path

import numpy as np
import pytest
from scipy import signal

import mtt

ROOT = Path(__file__).resolve().parent.parent
LOAD = str(ROOT / "models" / "dc_motor_load.bg")
SENSORS = str(ROOT / "models" / "dc_motor_sensors.bg")


@cache
def motor():
    return mtt.load(LOAD, input="Se:v,Se:tl", output="Df:speed,Df:current")


def record(model, k, inputs: int, seed: int, span: float = 60.0, dt: float = 0.02):
    """PRBS inputs held between samples, every output by lsim of the state space at k
    (exact for the hold), plus white noise at 20 dB on each output."""
    t = np.arange(0.0, span, dt)
    rng = np.random.default_rng(seed)
    U = np.repeat(rng.choice([-1.0, 1.0], size=(int(span) + 1, inputs)), int(1 / dt), 0)[: t.size]
    G = model.to_scipy(k)
    clean = signal.lsim((G.A, G.B, G.C, G.D), U, t, interp=False)[1]
    return t, U, clean + rng.standard_normal(clean.shape) * clean.std(0) / 10


def test_each_channel_has_its_theta_over_the_common_characteristic_polynomial():
    # la i' = v - ra i - km w, (jm + jl) w' = km i - b w + tl with ra = 1, la = 1/10, km = 1,
    # jm = 1, b = 1/10, times 100: A = 10 (1 + jl) s^2 + (101 + 100 jl) s + 110;
    # speed: 100 v + (10 s + 100) tl; current: (100 (1 + jl) s + 10) v - 100 tl
    Thetas = motor().estimator().theta_channels()
    a = [[110, 0], [101, 100], [10, 10]]
    expected = [
        [a + [[-100, 0], [0, 0]], a + [[-100, 0], [-10, 0]]],
        [a + [[-10, 0], [-100, -100]], a + [[100, 0], [0, 0]]],
    ]
    assert Thetas.tolist() == expected
    module = motor().estimator()
    assert (module.INPUTS, module.OUTPUTS) == (("Se:v", "Se:tl"), ("Df:speed", "Df:current"))
    assert module.theta().tolist() == expected[0][0]


def test_a_measured_disturbance_is_fitted_not_left_in_the_noise():
    t, U, Y = record(motor(), 10.0, 2, seed=3)
    module = motor().estimator()
    found = motor().fit(t, {"Se:v": U[:, 0], "Se:tl": U[:, 1]}, Y, hold="zoh", noise="white")
    assert found.ok and abs(found.k - 10.0) < 4 * found.k_se < 0.2
    assert np.allclose(found.noise_std, Y.std(0) / 10 / np.sqrt(1.01), rtol=0.1)
    assert np.all(found.fit_percent > 85)
    assert np.allclose(
        found.simulate(t, U, hold="zoh"), module.simulate_signals(t, U, found.k, hold="zoh")
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        alone = module.fit(t, U[:, 0], Y[:, 0], hold="zoh")  # the torque unmeasured
    assert alone.k_se > 20 * found.k_se


def test_times_in_another_unit_are_refused_as_for_one_signal():
    """Times scaled by 1e12 (every mode dies out between samples) gave k = 1.1e13 with ok
    True; the several-signal fit now says what the one-signal fit says."""
    t, U, Y = record(motor(), 10.0, 2, seed=3)
    module = motor().estimator()
    refused = r"all under 1/1e\+06 of a sampling interval: every mode dies out between samples"
    with pytest.raises(ValueError, match=refused + r": are the times in the model's unit"):
        module.fit_signals(t * 1e12, U, Y, hold="zoh")


def test_two_sensors_determine_what_neither_does_alone():
    model = mtt.load(SENSORS, output="Df:speed,Df:current")
    truth = [1.0, 1.0, 10.0, 0.1]
    t, U, Y = record(model, truth, 1, seed=5, span=40.0)
    found = model.fit(t, U, Y, hold="zoh", noise="white")
    assert found.ok and np.all(np.abs(found.k - truth) < 5 * found.k_se)
    speed = mtt.load(SENSORS, output="Df:speed")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        alone = speed.fit(t, U[:, 0], Y[:, 0], hold="zoh", noise="white")
    assert not alone.ok and not np.all(np.isfinite(alone.k_se))


def test_signals_are_checked_by_name_and_shape():
    t, U, Y = record(motor(), 10.0, 2, seed=1, span=5.0)
    with pytest.raises(mtt.MttError, match="shape"):
        motor().fit(t, U[:, 0], Y)
    with pytest.raises(mtt.MttError, match="missing"):
        motor().fit(t, {"Se:v": U[:, 0]}, Y)


def test_the_command_line_reads_a_column_per_signal(capsys, tmp_path):
    from mtt.cli.main import main

    t, U, Y = record(motor(), 10.0, 2, seed=2, span=30.0)
    path = tmp_path / "rig.csv"
    np.savetxt(path, np.column_stack([t, U, Y]), delimiter=",", header="t,v,tl,w,i", comments="")
    both = ["--input", "Se:v,Se:tl", "--output", "Df:speed,Df:current", "--data", str(path)]
    status = main(["fit", LOAD, *both, "--columns", "t,v,tl,w,i", "--hold", "zoh", "--json"])
    found = json.loads(capsys.readouterr().out)
    assert status == 0 and found["ok"] and list(found["signals"]) == ["Df:speed", "Df:current"]
    assert abs(found["unknowns"]["jl"]["k"] - 10.0) < 4 * found["unknowns"]["jl"]["k_se"]
    assert main(["fit", LOAD, *both]) == 2  # the default columns are the signals' labels
    assert "t,Se:v,Se:tl,Df:speed,Df:current" in capsys.readouterr().err


def test_a_record_that_does_not_determine_k_is_said_to_be_not_identifiable():
    # two sensors determine ra, km, j and b together, but only from an excited record: with
    # the voltage at rest the outputs are noise, and the exact prediction error is flat
    module = mtt.load(SENSORS, output="Df:speed,Df:current").estimator()
    t = np.arange(0.0, 40.0, 0.02)
    rng = np.random.default_rng(1)
    with pytest.warns(module.EstimationWarning, match="not identifiable from the signals Se:v"):
        found = module.fit_signals(t, np.zeros(t.size), rng.standard_normal((t.size, 2)),
                                   hold="zoh", noise="white")  # fmt: skip
    assert not found.ok and np.all(np.isinf(found.k_se)) and "not identifiable" in found.message


def test_compare_gives_each_outputs_fit_on_a_new_record():
    t, U, Y = record(motor(), 10.0, 2, seed=3)
    found = motor().fit(t, U, Y, hold="zoh", noise="white")
    t2, U2, Y2 = record(motor(), 10.0, 2, seed=4, span=30.0)
    Y2 = Y2 + [0.5, -0.2]  # another operating point: the offsets are estimated
    compared = found.compare(t2, U2, Y2)
    assert compared.samples == t2.size and np.allclose(compared.offset, [0.5, -0.2], atol=0.05)
    # noise at 20 dB: the noise-free part is 99.5 % of the variance, fit % near 90
    assert np.all(compared.fit_percent > 85) and np.all(compared.fit_percent < 95)
    residuals = Y2 - compared.fitted
    assert np.allclose(compared.residual_rms, np.sqrt(np.mean(residuals**2, 0)))
    assert len(found.fitted) == 1 and found.fitted[0].shape == Y.shape


def test_the_command_line_validates_plots_and_writes_several_signals(capsys, tmp_path):
    from mtt.cli.main import main

    paths = []
    for seed, span in ((2, 30.0), (6, 20.0)):
        t, U, Y = record(motor(), 10.0, 2, seed=seed, span=span)
        paths.append(tmp_path / f"rig{seed}.csv")
        np.savetxt(paths[-1], np.column_stack([t, U, Y]), delimiter=",",
                   header="t,Se:v,Se:tl,Df:speed,Df:current", comments="")  # fmt: skip
    both = ["--input", "Se:v,Se:tl", "--output", "Df:speed,Df:current", "--hold", "zoh"]
    fit = ["fit", LOAD, *both, "--data", str(paths[0]), "--validate", str(paths[1])]
    written = ["--plot", str(tmp_path / "fit.png"), "--csv", str(tmp_path / "fit.csv"),
               "--data-plot", str(tmp_path / "data.png")]  # fmt: skip
    assert main([*fit, *written]) == 0
    text = capsys.readouterr().out
    assert "Df:speed: fit" in text and "Df:current: fit" in text
    assert text.count(f"validation on {t.size} samples from {paths[1]}") == 2
    for name in ("fit.png", "data.png"):
        assert (tmp_path / name).read_bytes()[:4] == b"\x89PNG"
    table = np.genfromtxt(tmp_path / "fit.csv", delimiter=",", names=True)
    assert table.dtype.names[:4] == ("record", "t", "Sev", "Setl")
    assert np.allclose(table["Dfspeed"] - table["Dfspeed_fitted"], table["Dfspeed_residual"])
    assert main([*fit, "--json"]) == 0
    (held,) = json.loads(capsys.readouterr().out)["validation"]
    assert all(held["signals"][name]["fit_percent"] > 85 for name in ("Df:speed", "Df:current"))


@pytest.mark.parametrize(
    "flag", [["--method", "iv"], ["--method", "ls"], ["--beta", "0.5"], ["--seed", "3"]]
)
def test_the_command_line_refuses_what_it_does_not_do_with_several_signals(capsys, tmp_path, flag):
    from mtt.cli.main import main

    path = tmp_path / "rig.csv"
    path.write_text("t,Se:v,Se:tl,Df:speed,Df:current\n0,0,0,0,0\n")
    both = ["--input", "Se:v,Se:tl", "--output", "Df:speed,Df:current", "--data", str(path)]
    assert main(["fit", LOAD, *both, *flag, "--plot", str(tmp_path / "fit.png")]) == 2
    error = capsys.readouterr().err
    assert flag[0] in error and ("pem" in error or "simulates" in error)
    assert not list(tmp_path.glob("*.png"))


def test_the_api_and_the_command_line_read_several_signals_alike(capsys, tmp_path):
    """Model.read_csv reads a column per signal through mtt.data, as `mtt fit` does, and a
    missing column is the same located bad_data error in both (its file and line)."""
    from mtt.cli.main import main

    t, U, Y = record(motor(), 10.0, 2, seed=3, span=5.0)
    path = tmp_path / "rig.csv"
    header = "t,Se:v,Se:tl,Df:speed,Df:current"
    np.savetxt(path, np.column_stack([t, U, Y]), delimiter=",", header=header, comments="")
    found = motor().read_csv(path)
    assert found.u.shape == (t.size, 2) and found.y.shape == (t.size, 2)
    assert np.allclose(found.u, U) and found.note == f"{t.size} samples from {path}"
    renamed = motor().read_csv(path, columns=header.split(","))
    assert np.array_equal(renamed.y, found.y)
    with pytest.raises(mtt.MttError, match="no column 'v'") as caught:
        motor().read_csv(path, columns="t,v,tl,w,i")
    assert (caught.value.kind, caught.value.file, caught.value.line) == ("bad_data", str(path), 1)
    with pytest.raises(mtt.MttError, match="columns takes 5 different names"):
        motor().read_csv(path, columns="t,v")
    both = ["--input", "Se:v,Se:tl", "--output", "Df:speed,Df:current", "--data", str(path)]
    assert main(["fit", LOAD, *both, "--columns", "t,v,tl,w,i", "--json"]) == 2
    (error,) = json.loads(capsys.readouterr().out)["errors"]
    assert (error["kind"], error["file"], error["line"]) == ("bad_data", str(path), 1)
    assert "no column 'v'" in error["message"] and "--columns" in error["message"]


def _rig_files(tmp_path, seeds=((2, 30.0), (6, 20.0))) -> list[Path]:
    paths = []
    for seed, span in seeds:
        t, U, Y = record(motor(), 10.0, 2, seed=seed, span=span)
        paths.append(tmp_path / f"rig{seed}.csv")
        np.savetxt(paths[-1], np.column_stack([t, U, Y]), delimiter=",",
                   header="t,Se:v,Se:tl,Df:speed,Df:current", comments="")  # fmt: skip
    return paths


def test_the_generated_command_line_fits_every_signal(capsys, tmp_path):
    fitted, held = _rig_files(tmp_path)
    module = motor().estimator()
    assert module.main(["fit", str(fitted), "--hold", "zoh", "--validate", str(held)]) == 0
    text = capsys.readouterr().out
    assert text.startswith("jl = ") and "Df:current: fit" in text
    assert text.count(f"validation on {held}:") == 2
    assert module.main(["fit", str(fitted), "--hold", "zoh", "--json"]) == 0
    found = json.loads(capsys.readouterr().out)
    assert found["ok"] and abs(found["k"] - 10.0) < 4 * found["k_se"]
    assert list(found["signals"]) == ["Df:speed", "Df:current"]
    assert module.main(["fit", str(fitted), "--method", "ls"]) == 2
    assert "--method pem" in capsys.readouterr().err


def test_batch_fits_each_record_of_every_signal(tmp_path):
    from mtt.batch import estimate_many, fit_many

    paths = [str(path) for path in _rig_files(tmp_path)]
    batch = fit_many(motor(), paths, jobs=1, hold="zoh", noise="white")
    module = motor().estimator()
    for path, outcome in zip(paths, batch, strict=True):
        t, *columns = module.read_csv(path, ("t", *module.INPUTS, *module.OUTPUTS))
        alone = module.fit_signals(t, np.column_stack(columns[:2]), np.column_stack(columns[2:]),
                                   hold="zoh", noise="white")  # fmt: skip
        assert outcome.ok and outcome.result.k == alone.k and outcome.result.fitted == ()
    assert "fit % (Df:speed / Df:current)" in batch.table()
    pooled = fit_many(motor(), paths, jobs=1, pooled=True, hold="zoh", noise="white",
                      validate=paths[1:])  # fmt: skip
    (held,) = pooled.validation
    assert pooled.ok and abs(pooled.pooled.k - 10.0) < 4 * pooled.pooled.k_se
    assert np.all(held.comparison.fit_percent > 85)
    assert "validation on" in pooled.table() and "Df:current: fit" in pooled.table()
    with pytest.raises(mtt.MttError, match="exact prediction error only"):
        fit_many(motor(), paths, jobs=1, method="iv")
    with pytest.raises(mtt.MttError, match="follows one input and one output"):
        estimate_many(motor(), paths, jobs=1, k0=10.0)


def test_the_command_line_fits_a_pattern_of_records_of_every_signal(capsys, tmp_path):
    from mtt.cli.main import main

    _rig_files(tmp_path)
    both = ["--input", "Se:v,Se:tl", "--output", "Df:speed,Df:current", "--hold", "zoh"]
    status = main(["fit", LOAD, *both, "--data", str(tmp_path / "rig*.csv"), "--noise", "white",
                   "--csv", str(tmp_path / "table.csv")])  # fmt: skip
    assert status == 0
    text = capsys.readouterr().out
    assert "2 records, one fit each" in text and "2 of 2 records fitted" in text
    header, *rows = (tmp_path / "table.csv").read_text().splitlines()
    assert "fit_percent_Df:speed,fit_percent_Df:current,residual_rms_Df:speed" in header
    assert len(rows) == 2 and rows[0].startswith(str(tmp_path / "rig2.csv"))


def test_the_tracker_follows_every_signal():
    # the paper's recursion with each output's equation error A y_i - sum_j B_ij u_j
    module = motor().estimator()
    t, U, Y = record(motor(), 10.0, 2, seed=3)
    one = module.Tracker(k0=5.0, hold="zoh", scales=Y.std(0))
    for i in range(t.size):
        k = one.update(float(t[i]), U[i], Y[i])
    chunks = module.Tracker(
        k0=5.0, hold="zoh", scales=dict(zip(module.OUTPUTS, Y.std(0), strict=True))
    )
    for lo in range(0, t.size, 333):
        found = chunks.update(t[lo : lo + 333], U[lo : lo + 333], Y[lo : lo + 333])
    assert one.ok and found == pytest.approx(k, rel=1e-12) and abs(k - 10.0) < 0.1
    G = motor().to_scipy(10.0)  # noise-free: the interpolated outputs' error only
    clean = signal.lsim((G.A, G.B, G.C, G.D), U, t, interp=False)[1]
    exact = module.Tracker(k0=5.0, hold="zoh", scales=clean.std(0)).update(t, U, clean)
    assert exact == pytest.approx(10.0, rel=2e-4)
    with pytest.raises(ValueError, match="scales: give each output's typical size"):
        module.Tracker(k0=5.0)
    with pytest.raises(ValueError, match=r"y must have shape \(1, 2\)"):
        one.update(t[-1] + 1.0, U[-1], Y[-1, :1])
    assert one.k == k  # a refused sample leaves the Tracker as it was


def test_the_tracker_of_two_inputs_with_one_at_rest_is_the_single_channels():
    U = record(motor(), 10.0, 2, seed=7)[1]
    t = np.arange(U.shape[0]) * 0.02
    U[:, 1] = 0.0
    G = motor().to_scipy(10.0)
    speed = signal.lsim((G.A, G.B, G.C, G.D), U, t, interp=False)[1][:, 0]
    both = mtt.load(LOAD, input="Se:v,Se:tl", output="Df:speed").estimator()
    alone = mtt.load(LOAD, input="Se:v", output="Df:speed").estimator()
    k = both.Tracker(k0=5.0, hold="zoh").update(t, U, speed)
    single = alone.Tracker(k0=5.0, hold="zoh").update(t, U[:, 0], speed)
    assert k == pytest.approx(single, rel=1e-10)


def test_compare_estimates_each_outputs_initial_state():
    """On a noise-free record whose outputs start away from rest, each with its own free
    response (scipy's tf2ss of 1/A(s) made monic, A = 110 s^2 + 1101 s + 110 at jl = 10,
    hand-derived above), compare finds those initial states and offsets, and fits exactly."""
    t = np.arange(0.0, 20.0, 0.02)
    U = np.repeat(np.random.default_rng(5).choice([-1.0, 1.0], size=(21, 2)), 50, 0)[: t.size]
    G = motor().to_scipy(10.0)
    forced = signal.lsim((G.A, G.B, G.C, G.D), U, t, interp=False)[1]
    free = signal.StateSpace(*signal.tf2ss([110.0], [110.0, 1101.0, 110.0]))
    starts = np.array([[0.3, -2.0], [-0.5, 1.5]])
    Y = (
        forced
        + [0.5, -0.2]
        + np.column_stack([signal.lsim(free, np.zeros(t.size), t, X0=x0)[1] for x0 in starts])
    )
    found = motor().fit(t, U, forced, hold="zoh", noise="white", offset=False,
                        initial_state=False)  # fmt: skip
    assert abs(found.k - 10.0) < 1e-7
    compared = found.compare(t, U, Y)
    assert np.allclose(compared.initial_state, starts, atol=1e-5)
    assert np.allclose(compared.offset, [0.5, -0.2], atol=1e-6)
    assert np.all(compared.fit_percent > 99.99)
    module = motor().estimator()
    record = module.signals_comparison_record(compared)
    assert np.allclose(record["signals"]["Df:current"]["initial_state"], starts[1], atol=1e-5)
