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


@pytest.mark.parametrize(
    "flag",
    [
        ["--validate", "held.csv"],
        ["--plot", "fit.png"],
        ["--csv", "fit.csv"],
        ["--data-plot", "data.png"],
        ["--method", "iv"],
        ["--beta", "0.5"],
        ["--seed", "3"],
    ],
)
def test_the_command_line_refuses_what_it_does_not_do_with_several_signals(capsys, tmp_path, flag):
    from mtt.cli.main import main

    path = tmp_path / "rig.csv"
    path.write_text("t,Se:v,Se:tl,Df:speed,Df:current\n0,0,0,0,0\n")
    both = ["--input", "Se:v,Se:tl", "--output", "Df:speed,Df:current", "--data", str(path)]
    assert main(["fit", LOAD, *both, *flag]) == 2
    assert flag[0] in capsys.readouterr().err
    assert not list(tmp_path.glob("*.png")) and not (tmp_path / "fit.csv").exists()


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
