"""`mtt simulate --x0`: a nonlinear model simulated from a given state (issue 19)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from mtt.cli.main import main

ROOT = Path(__file__).resolve().parent.parent
TANKS = str(ROOT / "models" / "two_tanks.bg")
STEP = ["--signal", "step", "--amplitude", "10", "--t-end", "600", "--dt", "50"]


def _run(capsys, *argv):
    status = main(["simulate", *argv])
    captured = capsys.readouterr()
    return status, captured.out, captured.err


@pytest.mark.parametrize("x0", ["1000,800", "q_lower=800,q_upper=1000"])
def test_the_tanks_start_from_the_state_given(capsys, x0):
    """In the order of the states or by name, against solve_ivp on the equations written
    by hand from the same state."""
    status, out, _ = _run(capsys, TANKS, *STEP, "--x0", x0, "--json")
    assert status == 0
    run = json.loads(out)
    t, y = np.array(run["t"]), np.array(run["y"])
    assert "from x0 = q_upper = 1000, q_lower = 800" in run["note"]

    def tanks(_, q):
        upper = 2.0 * math.sqrt(max(q[0], 0.0) / 50)
        return [10.0 - upper, upper - 2.5 * math.sqrt(max(q[1], 0.0) / 40)]

    hand = solve_ivp(tanks, (0.0, 600.0), [1000.0, 800.0], t_eval=t, rtol=1e-10, atol=1e-10)
    assert y[0] == 800.0 / 40
    assert np.allclose(y, hand.y[1] / 40, rtol=1e-6, atol=1e-8)


def test_a_state_not_named_starts_at_rest(capsys):
    status, out, _ = _run(capsys, TANKS, *STEP, "--x0", "q_lower=800", "--json")
    assert status == 0
    run = json.loads(out)
    assert run["y"][0] == 20.0 and "q_upper = 0, q_lower = 800" in run["note"]


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        ([TANKS, "--x0", "1000"], "--x0: 1 value for the model's 2 states: q_upper, q_lower: "
         "give one per state in that order, or by name (--x0 q_upper=...)"),
        ([TANKS, "--x0", "1,2,3"], "--x0: 3 values for the model's 2 states"),
        ([TANKS, "--x0", "q=1"], "--x0: q is not a state of the model (its 2 states: q_upper, "
         "q_lower)"),
        ([TANKS, "--x0", "-5,1"], "--x0: the model's equations have no value at q_upper = -5, "
         "q_lower = 1 (with the first input 1)"),
        ([TANKS, "--at", "u=10", "--x0", "1,1"], "--x0 sets the initial state of a nonlinear "
         "model's simulator"),
        ([str(ROOT / "models" / "dc_drive.bg"), "--x0", "1"], "--x0 sets the initial state"),
    ],
)  # fmt: skip
def test_a_bad_initial_state_is_a_message_naming_the_option(capsys, argv, message):
    status, out, err = _run(capsys, *argv, "--t-end", "10", "--dt", "1", "--json")
    assert status == 2 and message in err
    assert json.loads(out)["errors"][0]["message"].startswith("--x0")


@pytest.mark.parametrize("text", ["a,b", "1,nan", "q_upper=1,q_upper=2", "=1"])
def test_a_malformed_initial_state_is_an_argument_error(capsys, text):
    with pytest.raises(SystemExit) as stop:
        main(["simulate", TANKS, "--x0", text])
    assert stop.value.code == 2 and "argument --x0" in capsys.readouterr().err
