"""`mtt compile`, `mtt simulate` and `mtt estimate`, and the paper's results through them."""

from __future__ import annotations

import csv
import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from mtt.cli.main import main

ROOT = Path(__file__).resolve().parent.parent
DC_DRIVE = str(ROOT / "models" / "dc_drive.bg")
ABSORBER = [str(ROOT / "models" / "absorber.bg"), "--keep", "tau,l"]
PAPER = ["--beta", "0.1", "--S0", "1e-4"]
ABSORBER_DATA = [*ABSORBER, "--t-end", "4", "--noise-uniform", "0.02", *PAPER]
RUN_KEYS = ["global_k", "global_cost", "ok", "stopped_at", "informed_until", "k_se", "ci", "k_ls",
            "warnings"]  # fmt: skip


def mtt(capsys, *args: str) -> tuple[int, str, str]:
    """Run `mtt ARGS` in this process: (exit status, stdout, stderr)."""
    try:
        status = main(list(args))
    except SystemExit as exit:  # argparse's own errors
        status = exit.code
    out, err = capsys.readouterr()
    return status, out, err


def estimates(capsys, *args: str) -> dict:
    status, out, err = mtt(capsys, "estimate", *args, "--json")
    assert status == 0, err
    return json.loads(out)


def test_compile_writes_the_committed_module(tmp_path, monkeypatch, capsys):
    (tmp_path / "models").mkdir()
    shutil.copy(ROOT / "models" / "absorber.bg", tmp_path / "models")
    monkeypatch.chdir(tmp_path)
    status, out, _ = mtt(capsys, "compile", "models/absorber.bg", "--keep", "tau,l")
    assert status == 0
    assert out.startswith("wrote generated/absorber.py: estimator of k for absorber")
    written = (tmp_path / "generated" / "absorber.py").read_bytes()
    assert written == (ROOT / "generated" / "absorber.py").read_bytes()
    status, _, _ = mtt(capsys, "compile", "models/absorber.bg", "--keep", "tau,l", "-o", "x.py")
    assert status == 0 and (tmp_path / "x.py").read_bytes() == written


def test_compile_errors_are_messages(tmp_path, capsys):
    model = tmp_path / "m.bg"
    model.write_text(
        "model m\nparam beta = 1\nunknown c = 1\nSe:v -> 1:a\n1:a -> R:beta\n"
        "1:a -> C:c\n1:a -> Df:i\n"
    )
    status, _, err = mtt(capsys, "compile", str(model), "--keep", "beta")
    assert status == 2
    assert "error[reserved_name]: the parameter 'beta' cannot be kept symbolic" in err
    status, _, err = mtt(capsys, "compile", str(model), "-o", "")
    assert status == 2 and "mtt compile: error: -o needs a file or a directory" in err
    status, _, err = mtt(capsys, "compile", str(tmp_path / "missing.bg"))
    assert status == 2 and "error[io]" in err


def test_parameters_without_a_value_are_asked_for(tmp_path, capsys):
    model = tmp_path / "rlc.bg"
    model.write_text((ROOT / "models" / "rlc.bg").read_text().replace("param r = 2", "param r"))
    status, _, err = mtt(capsys, "estimate", str(model), "--k0", "0.2")
    assert status == 2 and "the model gives no value for r: pass --set r=VALUE" in err
    result = estimates(capsys, str(model), "--k0", "0.2", "--set", "r=2", "--t-end", "3")
    assert abs(result["runs"][0]["k"] - 0.1) < 1e-3


def test_dc_drive_fig2_numbers(capsys):
    result = estimates(
        capsys, DC_DRIVE, "--t-end", "10", *PAPER, "--filter", "(1+s)^5", "--k0", "0", "5", "20"
    )
    assert list(result) == ["ok", "model", "unknown", "unknowns", "runs"] and result["ok"]
    assert (result["model"], result["unknown"]) == ("dc_drive", "k")
    for run, k0 in zip(result["runs"], (0.0, 5.0, 20.0), strict=True):
        assert list(run) == ["k0", "filter", "k", "minima", *RUN_KEYS]  # issue 8 added RUN_KEYS
        assert run["k0"] == k0 and run["filter"] == "(1+s)^5"
        assert abs(run["k"] - 10.0) < 0.1 and run["minima"] == [run["k"]]
        assert run["global_k"] == pytest.approx(run["k"], rel=1e-9) and run["ok"]
        assert abs(run["global_cost"]) < 1e-12 and run["stopped_at"] is None
        # exact data: the record's least-squares minimum is the true k, the estimate is held
        # off it by the prior S0 (by -2.5e-4 from k0 = 0), and the standard error is tiny
        assert abs(run["k_ls"] - 10.0) < 1e-5 and 0 < run["k_se"] < 1e-6
        assert run["ci"] == pytest.approx([run["k"] - 1.96 * run["k_se"],
                                           run["k"] + 1.96 * run["k_se"]])  # fmt: skip


def test_absorber_figs6_and_8_numbers(capsys):
    """Default noise seed: from 0.25..1 to 0.72, from 0 to the spurious minimum near -0.25."""
    result = estimates(capsys, *ABSORBER_DATA, "--k0", "0", "0.25", "0.5", "0.75", "1")
    runs = {run["k0"]: run for run in result["runs"]}
    assert -0.35 < runs[0.0]["k"] < -0.15
    for k0 in (0.25, 0.5, 0.75, 1.0):
        assert abs(runs[k0]["k"] - 0.72) < 0.03
        inside = [value for value in runs[k0]["minima"] if -1 <= value <= 1]
        assert len(inside) == 2
        assert abs(inside[0] + 0.25) < 0.05 and abs(inside[1] - 0.72) < 0.03


def test_absorber_fig7_numbers(tmp_path, capsys):
    """C(s) = (1 + sT)^4: all near 0.72 at t = 4; T = 0.5 reaches the neighbourhood first."""
    trajectories = tmp_path / "runs.csv"
    result = estimates(
        capsys, *ABSORBER_DATA, "--k0", "1", "--filter-T", "0.5", "1", "2",
        "--csv", str(trajectories),
    )  # fmt: skip
    assert [run["filter"] for run in result["runs"]] == [
        "(1 + 0.5 s)^4",
        "(1 + s)^4",
        "(1 + 2 s)^4",
    ]
    assert all(abs(run["k"] - 0.72) < 0.03 for run in result["runs"])
    with trajectories.open() as file:
        rows = list(csv.DictReader(file))
    assert list(rows[0]) == ["run", "k0", "filter", "t", "khat", "J2", "J3", "J4", "J5", "J6"]
    first = {}
    for row in rows:
        if abs(float(row["khat"]) - 0.72) < 0.03:
            first.setdefault(row["filter"], float(row["t"]))
    assert first["(1 + 0.5 s)^4"] < min(first["(1 + s)^4"], first["(1 + 2 s)^4"])


def test_simulated_data_round_trip_through_csv(tmp_path, capsys):
    data = tmp_path / "data.csv"
    status, out, _ = mtt(
        capsys, "simulate", DC_DRIVE, "--noise-uniform", "0.01", "--csv", str(data)
    )
    note = "1001 samples simulated with k = 10, input a unit step, noise uniform in [-0.01, 0.01]"
    assert status == 0 and out == f"wrote {data}: {note} (seed 0)\n"
    t, u, y = np.loadtxt(data, delimiter=",", skiprows=1).T
    assert t.size == 1001 and t[-1] == 10.0 and np.all(u == 1.0)
    # a simulated step is held (zoh); read back, the file is measured data (linear by default)
    measured = estimates(capsys, DC_DRIVE, "--data", str(data), "--k0", "5", "--hold", "zoh")
    simulated = estimates(capsys, DC_DRIVE, "--noise-uniform", "0.01", "--k0", "5")
    assert measured["runs"] == simulated["runs"]
    status, out, _ = mtt(capsys, "simulate", DC_DRIVE, "--t-end", "1", "--dt", "0.5")
    assert out.splitlines()[0] == "t,u,y" and len(out.splitlines()) == 4


def test_figures_and_tables(tmp_path, capsys):
    paths = {name: tmp_path / f"{name}.png" for name in ("plot", "cost", "data")}
    status, out, err = mtt(
        capsys, "estimate", DC_DRIVE, "--t-end", "5", "--k0", "5", "20",
        "--plot", str(paths["plot"]), "--cost-plot", str(paths["cost"]),
        "--data-plot", str(paths["data"]),
    )  # fmt: skip
    assert status == 0 and err == ""  # no progress bar off a terminal
    for path in paths.values():
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    lines = out.splitlines()
    assert lines[0] == "dc_drive: 501 samples simulated with k = 10, input a unit step"
    assert lines[1].split() == [
        "k0",
        "C(s)",
        "k",
        "at",
        "t",
        "=",
        "5",
        "local",
        "minima",
        "of",
        "J",
    ]


def test_a_stopped_run_is_reported_with_exit_status_1(capsys):
    status, out, err = mtt(capsys, "estimate", *ABSORBER, "--t-end", "4", "--k0", "0.2", "1")
    assert status == 1
    assert "warning: k0 = 0.2, C(s) = (1 + s)^4: J_2 reached zero at t = " in err
    assert "(stopped)" in out


@pytest.mark.parametrize(
    "args,message",
    [
        (["--k0", "1", "--filter", "(1+s"], "C(s) = '(1+s': expected ')', found the end"),
        (["--k0", "1", "--filter", "(1+x)^5"], "cannot read 'x)^5' at character 4"),
        (["--k0", "1", "--filter", "1/s"], "C(s) = '1/s': divide only by a non-zero number"),
        (
            ["--k0", "1", "--filter", "(1-s)^5"],
            "C(s) = '(1-s)^5' is not stable: it has a root at s = 1",
        ),
        (["--k0", "1", "--filter", "(1+s)^4"], "C(s) = '(1+s)^4' has degree 4; it must exceed"),
        (["--k0", "1", "--S0", "0"], "S0 must be > 0"),
        (["--k0", "1", "--beta", "-1"], "beta must be >= 0"),
        (["--k0", "nan"], "'nan' in 'nan' is not finite"),
        (["--k0", "1", "--dt", "0"], "need 0 < --dt <= --t-end"),
        (
            ["--k0", "1", "--noise-uniform", "-1"],
            "--noise-uniform must be from 0 to 1e+148, not -1",
        ),
        (["--k0", "1", "--cost-plot", "c.png", "--cost-range", "1", "0"], "needs A < B"),
        (["--k0", "1", "--data", "d.csv", "--k", "3"], "--data and --true do not go together"),
        (["--k0", "1", "--data", "missing.csv"], "missing.csv: No such file or directory"),
        (["--k0", "1", "--signal", "bad.csv"], "bad.csv:1: no column 'u' (the header names t, v)"),
        (["--k0", "1", "--data", "nan.csv"], "nan.csv:3: column 'y' holds 'nan', not a number"),
        (
            ["--k0", "1", "--data", "back.csv"],
            "back.csv:4: the times (column 't') must increase strictly: 1.0 (data row 3) follows",
        ),
        (["--k0", "1", "--data", "text.csv"], "text.csv:3: column 'u' holds 'one', not a number"),
        (["--k0", "1", "--set", "zz=1"], "error[undeclared_parameter]"),
        ([], "the following arguments are required: --k0"),
    ],
)
def test_user_errors_exit_2_with_a_message(args, message, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    Path("d.csv").write_text("t,u,y\n0,1,0\n1,1,1\n")
    Path("bad.csv").write_text("t,v\n0,1\n")
    Path("nan.csv").write_text("t,u,y\n0,1,0\n1,1,nan\n2,1,0\n")
    Path("back.csv").write_text("t,u,y\n0,1,0\n2,1,1\n1,1,0\n")
    Path("text.csv").write_text("t,u,y\n0,1,0\n1,one,1\n")
    status, _, err = mtt(capsys, "estimate", DC_DRIVE, *args)
    assert status == 2
    assert message in err
    assert "Traceback" not in err


def test_a_local_minimum_that_is_not_the_global_one_is_a_warning(capsys):
    """Absorber from k0 = 0: the paper's estimate ends at the spurious minimum."""
    status, out, err = mtt(capsys, "estimate", *ABSORBER_DATA, "--k0", "0", "1", "--json")
    assert status == 0
    runs = json.loads(out)["runs"]
    assert runs[0]["k"] == pytest.approx(-0.233, abs=1e-3) and runs[0]["ok"]
    assert runs[0]["global_k"] == pytest.approx(0.724, abs=1e-3) and runs[0]["global_cost"] < 0
    assert runs[1]["global_k"] == pytest.approx(runs[1]["k"], rel=1e-9)
    assert err.count("warning") == 1
    assert (
        "warning: k0 = 0, C(s) = (1 + s)^4: the estimate k = -0.233125 is a local minimum of "
        "J at t = 4, with J(-0.233125) - J(0.724187) = " in err
    )
    assert err.rstrip().endswith("the global minimum is at k = 0.724187")
    status, out, _ = mtt(capsys, "estimate", *ABSORBER_DATA, "--k0", "0")
    lines = out.splitlines()
    assert "0.724187 (not the estimate)" in lines[-4]
    # the least-squares standard error describes the global minimum's basin, not this one
    assert lines[-1] == "  k0 = 0, C(s) = (1 + s)^4: none (not at the global minimum)"
    assert runs[0]["k_se"] is None and runs[0]["ci"] is None
    assert runs[1]["ci"][0] < 0.72 < runs[1]["ci"][1] and runs[1]["k_se"] < 0.01


def test_a_settled_record_leaves_the_estimate_where_the_data_put_it(capsys):
    """A step held for 1000 s: after the response settles the data are rounding noise."""
    status, out, err = mtt(capsys, "estimate", DC_DRIVE, "--t-end", "1000", "--k0", "5", "--json")
    assert status == 0
    (run,) = json.loads(out)["runs"]
    assert abs(run["k"] - 10.0) < 1e-4 and run["ok"] and 100 < run["informed_until"] < 500
    assert "note: k0 = 5, C(s) = (1 + s)^5: the data stopped informing the estimate at t = " in err


def test_engines_and_bounds_from_the_command_line(capsys):
    moments = estimates(capsys, *ABSORBER_DATA, "--k0", "0.5", "1")
    ode = estimates(capsys, *ABSORBER_DATA, "--k0", "0.5", "1", "--engine", "ode", "--rtol", "1e-8")
    for a, b in zip(moments["runs"], ode["runs"], strict=True):
        assert a["k"] == pytest.approx(b["k"], rel=1e-5)
        assert a["global_k"] == pytest.approx(b["global_k"], rel=1e-5)
    bounded = estimates(capsys, *ABSORBER_DATA, "--k0", "1", "--bounds", "-1", "0")
    assert bounded["runs"][0]["global_k"] == pytest.approx(-0.232, abs=1e-3)
    status, _, err = mtt(capsys, "estimate", *ABSORBER_DATA, "--k0", "1", "--bounds", "1", "0")
    assert status == 2 and "argument --bounds: '1:0' in '1 0': LO must be below HI" in err
    spelled = estimates(capsys, *ABSORBER_DATA, "--k0", "1", "--bounds=-1:0")
    assert spelled["runs"][0]["global_k"] == bounded["runs"][0]["global_k"]


# mtt fit -------------------------------------------------------------------------------

PRBS = ["--signal", "prbs", "--period", "1", "--t-end", "200", "--dt", "0.02", "--hold", "zoh"]


def test_fit_of_simulated_noisy_data(tmp_path, capsys):
    plot = tmp_path / "fit.png"
    status, out, err = mtt(capsys, "fit", DC_DRIVE, *PRBS, "--noise-snr", "10", "--plot", str(plot),
                           "--dpi", "60")  # fmt: skip
    assert status == 0 and err == ""
    lines = out.splitlines()
    assert lines[0].startswith(
        "dc_drive: 10001 samples simulated with k = 10, input prbs, amplitude 1, period 1"
    )
    assert lines[0].endswith("white Gaussian noise at 10 dB SNR (seed 0)")
    k, se = (float(word) for word in lines[1].split()[2:5:2])
    assert lines[1].startswith("  k = ") and abs(k - 10) < 4 * se and 0.05 < se < 0.3
    assert plot.read_bytes()[:4] == b"\x89PNG"
    status, out, _ = mtt(
        capsys, "fit", DC_DRIVE, *PRBS, "--noise-snr", "10", "--json", "--method", "ls"
    )
    record = json.loads(out)
    assert record["ok"] and record["method"] == "ls" and record["iterations"] == 0
    assert set(record) >= {"k", "k_se", "ci", "fit_percent", "residual_rms", "warnings", "minima"}


def test_fit_combines_several_files_and_names_their_columns(tmp_path, capsys):
    paths = []
    for seed in (1, 2):
        path = tmp_path / f"run{seed}.csv"
        status, _, _ = mtt(capsys, "simulate", DC_DRIVE, *PRBS, "--t-end", "60", "--seed",
                           str(seed), "--noise-snr", "20", "--csv", str(path))  # fmt: skip
        text = path.read_text().replace("t,u,y", "time,volts,speed", 1)
        path.write_text(text)
        paths += ["--data", str(path)]
    status, out, err = mtt(capsys, "fit", DC_DRIVE, *paths, "--columns", "time,volts,speed",
                           "--hold", "zoh", "--json")  # fmt: skip
    assert status == 0, err
    record = json.loads(out)
    assert (
        record["ok"] and len(record["offsets"]) == 2 and abs(record["k"] - 10) < 4 * record["k_se"]
    )
    assert record["data"][1].endswith("run2.csv")
    status, out, err = mtt(capsys, "fit", DC_DRIVE, *paths, "--json")
    assert status == 2 and "run1.csv:1: no column 't' (the header names time, volts, speed)" in err
    assert json.loads(out)["ok"] is False
    status, _, err = mtt(capsys, "estimate", DC_DRIVE, *paths, "--k0", "1")
    assert status == 2 and "estimate takes one --data (2 given)" in err


def test_fit_warnings_go_to_stderr(capsys):
    status, out, err = mtt(capsys, "fit", DC_DRIVE, "--t-end", "10")
    assert status == 0 and "k = 10 " in out
    assert err.startswith("mtt fit: warning: the input is constant: it excites nothing that the")
    status, out, err = mtt(capsys, "fit", DC_DRIVE, "--t-end", "10", "--no-offset",
                           "--no-initial-state")  # fmt: skip
    assert status == 0 and err == ""
    status, out, err = mtt(capsys, "fit", DC_DRIVE, "--signal", "step", "--amplitude", "0")
    assert status == 1 and "no estimate: the data carry no information about k" in out
    assert "mtt fit: warning: the input is zero" in err


@pytest.mark.parametrize(
    "args,message",
    [
        (["--filter", "(1+s)^400"], "the exponent 400 must be a whole number from 0 to 24"),
        (["--filter", "(1+sqrt(-1)*s)^5"], "cannot read 'qrt(-1)*s)^5'"),
        (["--filter", "(1+1e-300*s)^5"], "its leading coefficient underflows to 0"),
        (["--filter", "(1+s)^5", "--filter-T", "2"], "--filter and --filter-T do not go together"),
        (["--set", "ra=1e400"], "error[out_of_range]: a coefficient of Theta, about 1.000e+401"),
        (["--keep", "ra", "--set", "ra=1e400"], "the value of ra, about 1.000e+400, is beyond"),
        # its first 40 digits alone, 1/1000..., read as a number in range
        (["--keep", "ra", "--set", "ra=1e-400"], "the value of ra, about 1.000e-400, is beyond"),
        (["--signal", "chirp"], "chirp: No such file or directory"),
        (["--signal", "step", "--period", "2"], "--period applies to prbs, square and multisine"),
        (["--columns", "a,b"], "--columns names the columns of --data files"),
        (["--dpi", "0", "--plot", "p.png"], "--dpi must be from 10 to 2400"),
        (
            ["--data", "header.csv"],
            "header.csv: no data: the file has a header row and nothing after it",
        ),
        (
            ["--data", "bom.csv", "--data", "dup.csv"],
            "dup.csv:1: the header names the column 'u' twice",
        ),
        (["--data", "under.csv"], "under.csv:2: column 'y' holds '1_0', not a number"),
        (["--data", "latin.csv"], "latin.csv: not UTF-8 text"),
        # in range for Theta, but the simulation overflowed: NaN samples, exit status 0
        (["--set", "ra=1e300"], "the simulated output overflows at t = 0.01"),
        # signals and noise too large for floating point (the last two were internal errors,
        # a CSV file of 1e300 a failure inside LAPACK)
        (["--amplitude", "1e308"], "u[0] is 1e+308: signals must stay within 1e+150 in size"),
        (["--data", "huge.csv"], "huge.csv:3: column 'y' holds 1e+300: signals must stay within"),
        (["--noise-snr", "-1e4"], "snr_db = -10000 makes noise of standard deviation inf"),
        (["--noise-uniform", "1.7e308"], "--noise-uniform must be from 0 to 1e+148"),
        (["--dt", "5e-324"], "--t-end / --dt = inf samples is too many"),  # internal errors,
        (["--signal", "square", "--period", "1e-308"], "has more than 16777216 periods"),  # too
        # a LinAlgError from inside LAPACK, its complaints on stderr
        (
            ["--signal", "prbs", "--beta", "1e18", "--method", "iv"],
            "beta = 1e+18 weighs the start of a record",
        ),
        (
            ["--signal", "prbs", "--beta", "0.1"],
            "beta = 0.1: the exact fit (--method pem) weighs every sample",
        ),
    ],
)
def test_fit_user_errors_exit_2(args, message, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    Path("header.csv").write_text("t,u,y\n")
    Path("bom.csv").write_bytes("\ufefft,u,y\n0,1,0\n1,1,1\n2,1,0\n".encode())
    Path("dup.csv").write_text("t,u,u\n0,1,0\n")
    Path("under.csv").write_text("t,u,y\n0,1,1_0\n")
    Path("latin.csv").write_bytes(b"t,u,y\n0,1,\xe9\n")
    Path("huge.csv").write_text("t,u,y\n0,1,0\n1,1,1e300\n2,1,0\n")
    status, _, err = mtt(capsys, "fit", DC_DRIVE, *args)
    assert status == 2 and message in err and "Traceback" not in err


def test_estimate_with_a_relative_prior_and_absurd_times(tmp_path, capsys):
    slow = [DC_DRIVE, "--filter-T", "10", "--k0", "5"]
    status, out, err = mtt(capsys, "estimate", *slow)
    assert status == 0 and "mtt estimate: warning: the data carry little information" in err
    record = estimates(capsys, *slow, "--S0-relative", "1e-4")
    assert record["runs"][0]["k"] == pytest.approx(10.0, rel=1e-4)
    scaled = tmp_path / "scaled.csv"
    t = np.linspace(0.0, 10.0, 101)
    scaled.write_text("t,u,y\n" + "".join(f"{v * 1e12:.17g},1,{v / 10:.17g}\n" for v in t))
    status, out, err = mtt(capsys, "estimate", DC_DRIVE, "--data", str(scaled), "--k0", "5")
    assert status == 1 and "the filter is too fast for the sampling" in err
    status, out, err = mtt(capsys, "fit", DC_DRIVE, "--data", str(scaled))
    assert status == 2 and "are the times in the model's unit (seconds)?" in err
    # times of 1e300 cannot be told apart by their steps: refused, said so
    scaled.write_text("t,u,y\n" + "".join(f"{v * 1e300:.17g},1,{v / 10:.17g}\n" for v in t))
    for command in (["estimate", "--k0", "5"], ["fit"]):
        status, out, err = mtt(capsys, command[0], DC_DRIVE, "--data", str(scaled), *command[1:])
        assert status == 2 and "scaled.csv:3: column 't' holds 1e+299: times must stay" in err


def test_a_model_named_as_a_python_module_is_refused(tmp_path, capsys):
    model = tmp_path / "numpy.bg"
    text = (ROOT / "models" / "dc_drive.bg").read_text()
    model.write_text(text.replace("model dc_drive", "model numpy"))
    status, _, err = mtt(capsys, "compile", str(model), "-o", str(tmp_path))
    assert (
        status == 2
        and "error[reserved_name]: the model name 'numpy' is the name of a Python" in err
    )
    model.write_text(text.replace("model dc_drive", "model json"))
    status, _, err = mtt(capsys, "fit", str(model))
    assert status == 2 and "the model name 'json'" in err


def test_json_results_say_ok(tmp_path, capsys):
    status, out, _ = mtt(capsys, "compile", DC_DRIVE, "-o", str(tmp_path), "--json")
    assert status == 0 and json.loads(out) == {
        "ok": True, "path": str(tmp_path / "dc_drive.py"), "model": "dc_drive", "unknown": "k",
        "unknowns": ["k"], "n": 4, "m": 2, "N": 1, "kept": [],
    }  # fmt: skip
    status, out, _ = mtt(capsys, "simulate", DC_DRIVE, "--t-end", "1", "--dt", "0.5", "--json")
    record = json.loads(out)
    assert status == 0 and record["ok"] and record["t"] == [0.0, 0.5, 1.0] and len(record["y"]) == 3
    status, out, _ = mtt(capsys, "simulate", DC_DRIVE, "--dt", "-1", "--json")
    assert status == 2 and json.loads(out)["ok"] is False


@pytest.mark.parametrize("command", ["simulate", "fit"])
def test_a_simulation_that_overflows_is_an_error_not_nan_in_json(capsys, command):
    # rlc at c = -0.001: poles at -2 +- sqrt(2004), the output beyond floats near t = 16.6
    rlc = str(ROOT / "models" / "rlc.bg")
    status, out, err = mtt(capsys, command, rlc, "--true", "-0.001", "--t-end", "1000", "--json")
    (error,) = json.loads(out)["errors"]
    assert status == 2 and "NaN" not in out and "Infinity" not in out
    assert error["message"].startswith("the simulated output overflows at t = 16.")
    assert "the model is unstable with c = -0.001, or its values are far from 1" in err


def test_figure_labels_in_physical_words_and_a_legend_beside_the_curves(monkeypatch, capsys):
    # issue 12 item 6: Fig. 5's axes say what the signals are (the model's words for its
    # source and detector), and Fig. 8's legend is outside the axes, over no curve
    from mtt.present import plots

    figures = {}
    monkeypatch.setattr(plots, "_save", lambda figure, path, dpi: figures.update({path: figure}))
    status, _, err = mtt(capsys, "estimate", *ABSORBER_DATA, "--k0", "1", "--filter-T", "0.5",
                         "1", "--data-plot", "fig5.png", "--cost-range", "-1", "1",
                         "--cost-plot", "fig8.png")  # fmt: skip
    assert status == 0, err
    top, bottom = figures["fig5.png"].axes
    assert top.get_ylabel().replace("\n", " ") == "solute feed flow (Sf:feed)"
    assert bottom.get_ylabel().replace("\n", " ") == "liquid product concentration (De:x_l)"
    assert bottom.get_xlabel() == "time t (s)"
    fig8 = figures["fig8.png"]
    fig8.canvas.draw()
    (legend,) = fig8.legends
    (ax,) = fig8.axes
    box, frame = legend.get_window_extent(), ax.get_window_extent()
    assert box.x0 >= frame.x1  # beside the axes, not over them
    assert [text.get_text() for text in legend.get_texts()][:2] == [
        "C(s) = (1 + 0.5 s)^4",
        "C(s) = (1 + s)^4",
    ]


def test_advice_names_the_options_and_held_test_signals_are_held(capsys, tmp_path):
    """On a command line the estimators' advice names options (--hold zoh), not the Python
    arguments (hold='zoh'); a simulated PRBS is held by default, so fitting it does not
    warn that it looks held, while its CSV, read back as measured data, does."""
    status, _, err = mtt(capsys, "fit", DC_DRIVE, "--signal", "prbs", "--t-end", "40",
                         "--noise-snr", "30")  # fmt: skip
    assert status == 0 and "looks held" not in err
    data = str(tmp_path / "prbs.csv")
    assert mtt(capsys, "simulate", DC_DRIVE, "--signal", "prbs", "--t-end", "40", "--csv",
               data)[0] == 0  # fmt: skip
    status, out, err = mtt(capsys, "fit", DC_DRIVE, "--data", data, "--json")
    advice = "pass --hold zoh; --hold linear reads each jump as a ramp"
    assert status == 0 and advice in err and "hold='" not in err
    assert any(advice in text for text in json.loads(out)["warnings"])
    import importlib.util

    spec = importlib.util.spec_from_file_location(
        "dc_drive_cli", ROOT / "generated" / "dc_drive.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert module.main(["fit", data]) == 0
    err = capsys.readouterr().err
    assert advice in err and "hold='" not in err
