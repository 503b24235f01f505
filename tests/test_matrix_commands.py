"""Several inputs and outputs on the command line and in the API: the transfer matrix in
text, JSON and LaTeX, each channel's Theta, identifiability from several signals (and
which are needed), python-control and scipy systems, and a matrix of Bode diagrams.

The exact matrices themselves are tests/test_transfer_matrix.py's; here, that each way of
showing them says the same, and what the steps that take one input and one output say.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import sympy

import mtt
from mtt.cli.main import main

ROOT = Path(__file__).resolve().parent.parent
MOTOR = str(ROOT / "models" / "dc_motor_load.bg")
SENSORS = str(ROOT / "models" / "dc_motor_sensors.bg")
BOTH = ["--input", "Se:v,Se:tl", "--output", "Df:speed,Df:current"]
s, jl = sympy.symbols("s jl")


def run(capsys, *argv):
    status = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return status, out, err


def test_tf_prints_the_matrix_over_the_characteristic_polynomial(capsys):
    status, out, _ = run(capsys, "tf", MOTOR, *BOTH)
    assert status == 0
    lines = out.splitlines()
    assert lines[0] == (
        "model dc_motor_load: from Se:v, Se:tl to Df:speed, Df:current; unknown jl; symbolic none"
    )
    assert "  A (n = 2):  10*(jl + 1)*s**2 + (100*jl + 101)*s + 110" in lines
    assert "  from Se:tl to Df:speed:    B (m = 1):  10*s + 100" in lines
    assert "  from Se:tl to Df:current:  B (m = 0):  -100" in lines
    assert lines[-1] == "  every entry B/A is reduced: no factor in s cancels"


def test_tf_json_and_latex(capsys):
    status, out, _ = run(capsys, "tf", MOTOR, *BOTH, "--json")
    record = json.loads(out)
    assert status == 0 and record["ok"]
    assert record["inputs"] == ["Se:v", "Se:tl"] and record["outputs"] == ["Df:speed", "Df:current"]
    assert sympy.sympify(record["A"]) == sympy.expand(
        10 * (jl + 1) * s**2 + (100 * jl + 101) * s + 110
    )
    assert record["B"][1] == ["100*jl*s + 100*s + 10", "-100"]
    entry = record["entries"][1]  # by output, then input
    assert (entry["input"], entry["output"], entry["m"], entry["cancelled"]) == (
        "Se:tl", "Df:speed", 1, None,
    )  # fmt: skip
    assert record["n"] == 2 and record["order"] == 2
    status, out, _ = run(capsys, "tf", MOTOR, *BOTH, "--latex")
    assert out.startswith("G(s) = \\frac{1}{") and "\\begin{matrix}" in out


def test_a_reduced_entry_says_what_cancels(capsys):
    path = ROOT / "tests" / "data" / "matrices" / "parallel_rc.bg"
    status, out, _ = run(capsys, "tf", path, "--output", "Df:i1,Df:i2")
    assert status == 0
    assert "      reduced: the factor 2*c*s + 1 cancels: G = s / (s + 1)" in out.splitlines()
    assert out.splitlines()[-1] == "  2 of the 2 entries reduce"
    record = json.loads(run(capsys, "tf", path, "--output", "Df:i1,Df:i2", "--json")[1])
    assert [e["cancelled"] for e in record["entries"]] == ["2*c*s + 1", "s + 1"]


def test_theta_gives_each_channel_its_own(capsys):
    status, out, _ = run(capsys, "theta", MOTOR, *BOTH)
    assert status == 0
    blocks = out.strip().split("\n\nmodel ")
    assert len(blocks) == 4
    assert blocks[1].startswith("dc_motor_load: from Se:tl to Df:speed; unknown jl")
    record = json.loads(run(capsys, "theta", MOTOR, *BOTH, "--json")[1])
    channel = record["channels"][2]  # from Se:v to Df:current: 10 (10 (jl + 1) s + 1) / A
    assert (channel["input"], channel["output"]) == ("Se:v", "Df:current")
    assert channel["theta"] == [["110", "0"], ["101", "100"], ["10", "10"], ["-10", "0"],
                                ["-100", "-100"]]  # fmt: skip
    status, out, _ = run(capsys, "theta", MOTOR, *BOTH, "--latex")
    assert out.splitlines()[0].startswith("\\Theta_{\\mathrm{Se{:}v} \\to \\mathrm{Df{:}speed}} = ")


def test_ss_names_each_input_and_output(capsys):
    status, out, _ = run(capsys, "ss", MOTOR, *BOTH)
    assert status == 0
    assert "inputs u1 = Se:v, u2 = Se:tl; outputs y1 = Df:speed, y2 = Df:current" in out
    assert "  e1 = u1" in out.splitlines() and "  u = [u1, u2]" in out.splitlines()
    record = json.loads(run(capsys, "ss", MOTOR, *BOTH, "--json")[1])
    assert record["inputs"] == ["Se:v", "Se:tl"] and len(record["B"][0]) == 2
    assert len(record["C"]) == 2 and len(record["D"]) == 2 and len(record["D"][0]) == 2
    single = json.loads(run(capsys, "ss", MOTOR, "--json")[1])
    assert single["inputs"] == ["Se:v"] and single["input"] == "Se:v"


def test_check_and_show_name_every_input_and_output(capsys):
    status, out, _ = run(capsys, "check", MOTOR, *BOTH)
    assert status == 0 and "inputs Se:v and Se:tl, outputs Df:speed and Df:current" in out
    (record,) = json.loads(run(capsys, "check", MOTOR, *BOTH, "--json")[1])["files"]
    assert (record["input"], record["output"]) == ("Se:v,Se:tl", "Df:speed,Df:current")
    out = run(capsys, "show", MOTOR, *BOTH)[1]
    assert "inputs  Se:v and Se:tl" in out.splitlines()


def test_a_step_for_one_input_and_output_says_so(capsys, tmp_path):
    status, _, _ = run(capsys, "compile", MOTOR, *BOTH, "-o", tmp_path / "m.py")
    assert status == 0 and "def fit_signals(" in (tmp_path / "m.py").read_text()
    data = tmp_path / "data.csv"
    data.write_text("t,u,y\n0,0,0\n1,1,1\n2,1,1\n3,0,1\n")
    status, _, err = run(capsys, "estimate", MOTOR, *BOTH, "--data", str(data), "--k0", "5")
    assert status == 2 and "take one input and one output" in err and "fit_signals" in err
    model = mtt.load(MOTOR, input="Se:v,Se:tl")
    with pytest.raises(mtt.MttError) as caught:
        model.transfer_function  # noqa: B018
    assert caught.value.kind == "several_signals" and "Model.transfer_matrix" in str(caught.value)


def test_identifiable_from_both_outputs_together_and_from_neither_alone(capsys):
    """The target: ra, km, j and b from the speed and the current together, globally; from
    either alone, not at all, and the verdict says so."""
    status, out, _ = run(capsys, "identifiability", SENSORS, "--output", "Df:speed,Df:current")
    assert status == 0
    lines = out.splitlines()
    assert lines[1] == "globally identifiable: the transfer matrix determines ra, km, j, b"
    assert lines[2] == (
        "signals needed: all of them, from Se:v to Df:speed, Df:current: fewer determine less"
    )
    assert lines[4].startswith("  from Se:v to Df:speed:   not identifiable: determines km/j")
    assert lines[5].startswith("  from Se:v to Df:current: not identifiable: determines ra, j/b")
    record = json.loads(
        run(capsys, "identifiability", SENSORS, "--output", "Df:speed,Df:current", "--json")[1]
    )
    assert record["verdict"] == "global" and record["needed"] == []
    assert [(p["outputs"], p["verdict"], p["rank"]) for p in record["parts"]] == [
        (["Df:speed"], "none", 3), (["Df:current"], "none", 3),
    ]  # fmt: skip


def test_the_signals_needed_are_the_fewest_that_determine_as_much(capsys):
    status, out, _ = run(capsys, "identifiability", MOTOR, *BOTH)
    assert status == 0
    needed = next(line for line in out.splitlines() if line.startswith("signals needed"))
    # jl from any one entry: the four single channels are the smallest sets
    assert needed.count("; or ") == 3 and "from Se:tl to Df:current" in needed
    found = mtt.load(MOTOR, input=["Se:v", "Se:tl"], output="Df:speed").identifiability()
    assert found.verdict == "global" and len(found.needed) == 2
    assert [(part.inputs, part.result.verdict) for part in found.parts] == [
        (("Se:v",), "global"), (("Se:tl",), "global"),
    ]  # fmt: skip
    status, _, err = run(capsys, "check", "--identifiability", SENSORS,
                         "--output", "Df:speed,Df:current")  # fmt: skip
    assert status == 0 and "not_identifiable" not in err


def test_the_api_takes_lists_and_gives_the_matrix():
    model = mtt.load(MOTOR, input=["Se:v", "Se:tl"], output=("Df:speed", "Df:current"))
    assert model.inputs == ("Se:v", "Se:tl") and model.input == "Se:v,Se:tl"
    G = model.transfer_matrix
    assert G.shape == (2, 2) and G.outputs == ("Df:speed", "Df:current")
    assert G.B[0, 1] == 10 * s + 100
    assert sympy.cancel(G.G[1, 0] - G.B[1, 0] / G.A) == 0
    assert G.entry("Df:current", "Se:tl").num == -100
    assert G.theta(0, 1).rows == ("a0", "a1", "a2", "-b0", "-b1")
    B, A = G.at(10)
    assert A.tolist() == [110.0, 1101.0, 110.0] and B[1, 0].tolist() == [0.0, 1100.0, 10.0]
    with pytest.raises(mtt.MttError, match="not an input of the transfer matrix"):
        G.entry(0, "Se:x")
    single = mtt.load(MOTOR).transfer_matrix
    assert single.shape == (1, 1) and single.B[0, 0] == 100


def test_to_control_and_to_scipy_are_the_matrix_with_its_names():
    control = pytest.importorskip("control")
    model = mtt.load(MOTOR, input="Se:v,Se:tl", output="Df:speed,Df:current")
    w = np.logspace(-2, 2, 9)
    B, A = model.transfer_matrix.at(3.0)
    exact = np.array([[np.polyval(B[i, j], 1j * w) / np.polyval(A, 1j * w) for j in range(2)]
                      for i in range(2)])  # fmt: skip
    G = model.to_control(3.0)
    assert G.input_labels == ["Se:v", "Se:tl"] and G.output_labels == ["Df:speed", "Df:current"]
    assert G.name == "dc_motor_load"
    assert np.allclose(G(1j * w), exact, rtol=1e-10)
    S = model.to_control(3.0, form="ss")
    assert isinstance(S, control.StateSpace) and np.allclose(S(1j * w), exact, rtol=1e-9)
    scipy_ss = model.to_scipy(3.0)
    A_, B_, C_, D_ = scipy_ss.A, scipy_ss.B, scipy_ss.C, scipy_ss.D
    resolvent = [C_ @ np.linalg.solve(1j * x * np.eye(len(A_)) - A_, B_) + D_ for x in w]
    assert np.allclose(np.moveaxis(np.array(resolvent), 0, -1), exact, rtol=1e-9)
    sampled = model.to_control(3.0, dt=0.1)
    assert sampled.dt == 0.1 and sampled.input_labels == ["Se:v", "Se:tl"]
    assert model.to_scipy(3.0, dt=0.1).dt == 0.1
    # with the bond graph's own states, named, when E is invertible
    named = mtt.load(SENSORS, output="Df:speed,Df:current").to_control([1, 1, 10, 0.1], form="ss")
    assert named.state_labels == ["p_la", "p_j"]


def test_bode_draws_a_matrix_of_diagrams(capsys, tmp_path):
    figure = tmp_path / "bode.png"
    status, out, _ = run(capsys, "bode", MOTOR, *BOTH, "--k", "1,10", "-o", figure, "--dpi", 30)
    assert status == 0 and out.startswith(f"wrote {figure}: 2x2 Bode diagrams")
    assert figure.stat().st_size > 5_000
    record = json.loads(run(capsys, "bode", MOTOR, *BOTH, "--k", "1,10", "--json")[1])
    assert record["inputs"] == ["Se:v", "Se:tl"] and record["k"] == [1.0, 10.0]
    magnitude = np.array(record["magnitude_db"])
    assert magnitude.shape == (2, 2, 2, len(record["frequency"]))
    B, A = mtt.load(MOTOR, input="Se:v,Se:tl", output="Df:speed,Df:current").transfer_matrix.at(10)
    w = np.array(record["frequency"])
    expected = 20 * np.log10(abs(np.polyval(B[1, 1], 1j * w) / np.polyval(A, 1j * w)))
    assert np.allclose(magnitude[1, 1, 1], expected, atol=1e-9)
    path = ROOT / "tests" / "data" / "matrices" / "decoupled.bg"
    record = json.loads(run(capsys, "bode", path, "--input", "Se:v1,Se:v2",
                            "--output", "Df:i1,Df:i2", "--json")[1])  # fmt: skip
    assert record["magnitude_db"][0][1] == [[None] * len(record["frequency"])]  # a zero entry


def test_nonlinear_state_equations_take_one_input_and_one_output(capsys, tmp_path):
    text = (ROOT / "models" / "two_tanks.bg").read_text()
    path = tmp_path / "tanks.bg"
    path.write_text(text + "0:h1 -> De:top\noutput De:level\n")
    for extra in ([], ["--at", "u=10"]):
        status, _, err = run(capsys, "ss", path, "--output", "De:level,De:top", *extra)
        assert status == 2 and "error[several_signals]" in err
        assert "take one input and one output" in err
    assert run(capsys, "ss", path)[0] == 0
