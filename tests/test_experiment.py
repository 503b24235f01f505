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
RUN_KEYS = ["global_k", "global_cost", "ok", "stopped_at", "informed_until"]


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
    assert list(result) == ["model", "unknown", "runs"]
    assert (result["model"], result["unknown"]) == ("dc_drive", "k")
    for run, k0 in zip(result["runs"], (0.0, 5.0, 20.0), strict=True):
        assert list(run) == ["k0", "filter", "k", "minima", *RUN_KEYS]  # issue 8 added RUN_KEYS
        assert run["k0"] == k0 and run["filter"] == "(1+s)^5"
        assert abs(run["k"] - 10.0) < 0.1 and run["minima"] == [run["k"]]
        assert run["global_k"] == pytest.approx(run["k"], rel=1e-9) and run["ok"]
        assert abs(run["global_cost"]) < 1e-12 and run["stopped_at"] is None


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
    status, _, _ = mtt(capsys, "simulate", DC_DRIVE, "--noise-uniform", "0.01", "--csv", str(data))
    assert status == 0
    t, u, y = np.loadtxt(data, delimiter=",", skiprows=1).T
    assert t.size == 1001 and t[-1] == 10.0 and np.all(u == 1.0)
    measured = estimates(capsys, DC_DRIVE, "--data", str(data), "--k0", "5")
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
        (["--k0", "1", "--filter", "(1+s"], "<expression>:1:4: error[syntax]"),
        (["--k0", "1", "--filter", "(1+x)^5"], "unknown name 'x'"),
        (["--k0", "1", "--filter", "1/s"], "--filter '1/s' is not a polynomial in s"),
        (["--k0", "1", "--filter", "(1-s)^5"], "C(s) is not stable: it has a root at s = 1"),
        (["--k0", "1", "--filter", "(1+s)^4"], "C(s) has degree 4; it must exceed"),
        (["--k0", "1", "--S0", "0"], "S0 must be > 0"),
        (["--k0", "1", "--beta", "-1"], "beta must be >= 0"),
        (["--k0", "nan"], "k0 must be finite"),
        (["--k0", "1", "--dt", "0"], "need 0 < --dt <= --t-end"),
        (["--k0", "1", "--noise-uniform", "-1"], "--noise-uniform must be >= 0"),
        (["--k0", "1", "--cost-plot", "c.png", "--cost-range", "1", "0"], "needs A < B"),
        (["--k0", "1", "--data", "d.csv", "--k", "3"], "--data and --k do not go together"),
        (["--k0", "1", "--data", "missing.csv"], "missing.csv: No such file or directory"),
        (["--k0", "1", "--signal", "bad.csv"], "bad.csv: no column 'u'"),
        (["--k0", "1", "--data", "nan.csv"], "y[1] is nan: every value must be finite"),
        (["--k0", "1", "--data", "back.csv"], "t must be strictly increasing"),
        (["--k0", "1", "--data", "text.csv"], "text.csv:3: expected numbers in columns t, u, y"),
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
    assert "0.724187 (not the estimate)" in out.splitlines()[-1]


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
    assert status == 2 and "bounds must be (lo, hi) with lo < hi, not (1.0, 0.0)" in err
