"""Validation on held-out records through the command lines and mtt.batch (issue 18 item 3):
`mtt fit --validate`, the generated module's own `fit --validate`, `fit_many(validate=...)`.

The held-out record is written here with scipy.signal.lsim from a non-zero initial state
and an offset (independently of the modules); the figures are checked against the module's
`Fit.compare` on the same arrays.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from inprocess import run_mtt
from scipy import signal

from mtt.batch import fit_many
from mtt.language.diagnostics import MttError

ROOT = Path(__file__).resolve().parent.parent
MODEL = str(ROOT / "models" / "dc_drive.bg")
SIMULATED = ["--signal", "prbs", "--period", "1", "--t-end", "60", "--dt", "0.02", "--hold", "zoh",
             "--noise-snr", "20"]  # fmt: skip
OFFSET = 0.4


def write(path: Path, t, u, y, names=("t", "u", "y")) -> Path:
    np.savetxt(path, np.c_[t, u, y], delimiter=",", header=",".join(names), comments="",
               fmt="%.17g")  # fmt: skip
    return path


@pytest.fixture(scope="module")
def held_out(dc_drive, tmp_path_factory) -> Path:
    """40 s of the DC drive from a non-zero state, 0.4 above, at 20 dB (seed 11)."""
    t = 0.02 * np.arange(2001)
    levels = np.random.default_rng(11).choice([-1.0, 1.0], 42)
    u = levels[np.floor(t + 1e-9).astype(int)]
    system = signal.StateSpace(*signal.tf2ss(*dc_drive.transfer_function(10.0)))
    clean = signal.lsim(system, u, t, X0=[0.5, -0.2, 0.3, 1.0], interp=False)[1]
    y = clean + OFFSET + 0.1 * np.std(clean) * np.random.default_rng(12).standard_normal(t.size)
    return write(tmp_path_factory.mktemp("held_out") / "val.csv", t, u, y)


def test_mtt_fit_validate_prints_writes_and_plots(capsys, held_out, dc_drive, tmp_path):
    plot = tmp_path / "fit.png"
    status, out, err = run_mtt(capsys, "fit", MODEL, *SIMULATED, "--validate", str(held_out),
                           "--plot", str(plot), "--dpi", "50")  # fmt: skip
    assert status == 0, err
    line = out.splitlines()[-1]
    assert line.startswith(f"  validation on 2001 samples from {held_out}: fit ")
    assert line.endswith("(its initial state and output offset estimated by least squares)")
    assert plot.read_bytes()[:4] == b"\x89PNG"
    status, _, err = run_mtt(capsys, "fit", MODEL, "--data", str(held_out), "--data-plot",
                             str(tmp_path / "data.png"), "--dpi", "50")  # fmt: skip
    assert status == 0, err  # --data-plot draws the record fitted (it was ignored)
    assert (tmp_path / "data.png").read_bytes()[:4] == b"\x89PNG"
    status, out, _ = run_mtt(capsys, "fit", MODEL, *SIMULATED, "--validate", str(held_out),
                         "--validate", str(held_out), "--json")  # fmt: skip
    record = json.loads(out)
    first, second = record["validation"]
    assert first == second and first["data"] == f"2001 samples from {held_out}"
    assert f"fit {first['fit_percent']:.4g} %" in line
    # the same figures as the module's compare at the fit's k
    t, u, y = dc_drive.read_csv(held_out, ("t", "u", "y"))
    expected = dc_drive._compare(t, u, y, record["k"], hold="zoh", known={})
    assert first["fit_percent"] == pytest.approx(expected.fit_percent, abs=1e-9)
    assert first["residual_rms"] == pytest.approx(expected.residual_rms, rel=1e-9)
    assert first["offset"] == pytest.approx(OFFSET, abs=0.02) and len(first["initial_state"]) == 4
    assert first["fit_percent"] > 85 and first["samples"] == 2001


def test_validate_reads_renamed_columns_and_names_bad_files(capsys, held_out, tmp_path):
    t, u, y = np.loadtxt(held_out, delimiter=",", skiprows=1).T
    renamed = write(tmp_path / "renamed.csv", t, u, y, ("time", "volts", "speed"))
    data = write(tmp_path / "data.csv", t, u, y, ("time", "volts", "speed"))
    status, out, err = run_mtt(capsys, "fit", MODEL, "--data", str(data), "--columns",
                               "time,volts,speed", "--hold", "zoh", "--validate",
                               str(renamed))  # fmt: skip
    assert status in (0, 1) and f"validation on 2001 samples from {renamed}" in out, err
    missing = tmp_path / "missing.csv"
    status, out, err = run_mtt(capsys, "fit", MODEL, *SIMULATED, "--validate", str(missing))
    assert status == 2 and out == "" and f"{missing}: No such file or directory" in err
    backwards = write(tmp_path / "backwards.csv", t[::-1], u, y)
    status, _, err = run_mtt(capsys, "fit", MODEL, *SIMULATED, "--validate", str(backwards))
    assert status == 2 and "must increase strictly" in err


def test_the_generated_module_validates_too(held_out, tmp_path):
    data = tmp_path / "data.csv"
    np.savetxt(data, np.loadtxt(held_out, delimiter=",", skiprows=1)[:1500], delimiter=",",
               header="t,u,y", comments="", fmt="%.17g")  # fmt: skip
    run = subprocess.run(
        [sys.executable, str(ROOT / "generated" / "dc_drive.py"), "fit", str(data), "--hold",
         "zoh", "--validate", str(held_out), "--json"],
        capture_output=True, text=True, check=False,
    )  # fmt: skip
    (validation,) = json.loads(run.stdout)["validation"]
    assert validation["data"] == str(held_out) and validation["fit_percent"] > 85


def test_fit_many_validates_each_fit_and_the_pooled_one(dc_drive, held_out):
    records = []
    for seed in (1, 2):
        t = 0.02 * np.arange(1501)
        u = dc_drive.input_signal("prbs", t, period=1.0, seed=seed)
        y = dc_drive.with_noise(dc_drive.simulate(t, u, 10.0, hold="zoh"), 20.0, seed=seed)
        records.append((f"run {seed}", (t, u, y)))
    each = fit_many(dc_drive, records, jobs=1, hold="zoh", validate=[str(held_out)])
    t, u, y = dc_drive.read_csv(held_out, ("t", "u", "y"))
    for outcome in each:
        (validation,) = outcome.validation
        assert validation.name == str(held_out) and validation.comparison.fitted is None
        direct = outcome.result.compare(t, u, y)
        assert validation.comparison.fit_percent == direct.fit_percent
        assert outcome.record()["validation"][0]["fit_percent"] == direct.fit_percent
    pooled = fit_many(dc_drive, records, jobs=1, pooled=True, hold="zoh",
                                validate={"held out": (t, u, y)})  # fmt: skip
    (validation,) = pooled.validation
    assert validation.name == "held out"
    assert validation.comparison.fit_percent == pooled.pooled.compare(t, u, y).fit_percent
    with pytest.raises(MttError, match="validate: nowhere.csv"):
        fit_many(dc_drive, records, jobs=1, validate=["nowhere.csv"])


def test_mtt_fit_validate_over_a_pattern(capsys, dc_drive, held_out, tmp_path):
    for seed in (3, 4):
        t = 0.02 * np.arange(1501)
        u = dc_drive.input_signal("prbs", t, period=1.0, seed=seed)
        y = dc_drive.with_noise(dc_drive.simulate(t, u, 10.0, hold="zoh"), 20.0, seed=seed)
        write(tmp_path / f"run_{seed}.csv", t, u, y)
    pattern = str(tmp_path / "run_*.csv")
    status, out, err = run_mtt(capsys, "fit", MODEL, "--data", pattern, "--hold", "zoh",
                           "--validate", str(held_out))  # fmt: skip
    assert status == 0, err
    header, first = out.splitlines()[1:3]
    assert f"fit %  fit % on {held_out}  warnings" in header
    assert len(first.split()) == 5  # file, k, k_se, fit %, fit % on the held-out record
    status, out, err = run_mtt(capsys, "fit", MODEL, "--data", pattern, "--hold", "zoh", "--pooled",
                           "--jobs", "2", "--validate", str(held_out), "--json")  # fmt: skip
    assert status == 0, err
    assert json.loads(out)["validation"][0]["data"] == str(held_out)
