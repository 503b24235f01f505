"""Every command's --json: one object with `ok`, also when the command fails."""

from __future__ import annotations

import json

import pytest

import mtt
from mtt.cli.main import main

RLC = str(mtt.example("rlc"))


def run(capsys, *argv: str) -> tuple[int, str, str]:
    status = main(list(argv))
    out, err = capsys.readouterr()
    return status, out, err


@pytest.mark.parametrize(
    ("argv", "expected"),
    [
        (["show", RLC], {"model": "rlc", "input": "Se:v", "unknowns": ["c"]}),
        (["causality", RLC], {"dependent": [], "loops": []}),
        (["ss", RLC], {"states": ["p_l", "q_c"], "A": [["-4", "-1/c"], ["2", "0"]]}),
        (["tf", RLC], {"num": "2*c*s", "den": "c*s**2 + 4*c*s + 2"}),
        (["theta", RLC], {"theta": [["2", "0"], ["0", "4"], ["0", "1"], ["0", "0"], ["0", "-2"]]}),
    ],
)
def test_every_deriving_command_prints_one_json_object_with_ok(capsys, argv, expected):
    status, out, _ = run(capsys, *argv, "--json")
    record = json.loads(out)
    assert status == 0 and record["ok"] is True
    assert {key: record[key] for key in expected} == expected


def test_causality_json_names_the_stroke_end_of_every_bond(capsys):
    _, out, _ = run(capsys, "causality", RLC, "--json")
    strokes = {bond["number"]: bond["stroke"] for bond in json.loads(out)["bonds"]}
    # the inductor fixes the loop's flow: every other element receives it, imposes effort
    assert strokes == {1: "1:loop", 2: "1:loop", 3: "I:l", 4: "1:loop", 5: "1:loop"}


@pytest.mark.parametrize("command", ["show", "causality", "ss", "tf", "theta"])
def test_a_failing_command_prints_ok_false_with_located_errors(capsys, tmp_path, command):
    model = tmp_path / "bad.bg"
    model.write_text("model bad\nparam r = 1 +\nSe:v -> 1:j\n1:j -> R:r\n1:j -> Df:i\n")
    status, out, err = run(capsys, command, str(model), "--json")
    record = json.loads(out)
    assert status == 2 and record["ok"] is False
    (error,) = record["errors"]
    assert (error["file"], error["kind"], error["line"]) == (str(model), "syntax", 2)
    assert "error[syntax]" in err  # and the report for people, on stderr


def test_set_on_an_unknown_is_said_not_ignored(capsys):
    status, _, err = run(capsys, "tf", RLC, "--set", "c=2")
    assert status == 0
    assert "warning: --set c=...: c is an unknown, which stays symbolic here" in err


def test_set_with_a_name_for_a_value_says_what_a_value_is(capsys):
    with pytest.raises(SystemExit):
        main(["tf", RLC, "--set", "r=abc"])
    err = capsys.readouterr().err
    assert "unknown name 'abc' (a value here is a number or an expression of numbers)" in err
    assert "(use )" not in err


@pytest.mark.parametrize(
    ("argv", "says"),
    [
        (["tf", RLC, "--set", "r=abc"], "argument --set: bad value in 'r=abc'"),
        (["ss", RLC, "--bogus"], "unrecognized arguments: --bogus"),
        (["bode", RLC, "--k", "x"], "argument --k: expected numbers separated by commas"),
        (["simulate", RLC, "--hold", "cubic"], "argument --hold: invalid choice: 'cubic'"),
        (["compile"], "the following arguments are required: FILE"),
    ],
)
def test_a_bad_command_line_with_json_prints_ok_false_too(capsys, argv, says):
    with pytest.raises(SystemExit) as done:
        main([*argv, "--json"])
    out, err = capsys.readouterr()
    assert done.value.code == 2 and says in err and "usage: mtt" in err
    (error,) = json.loads(out)["errors"]
    assert json.loads(out)["ok"] is False
    assert error["kind"] == "usage" and error["message"].startswith(says)
    with pytest.raises(SystemExit) as done:  # without --json: the message alone, no JSON
        main(argv)
    out, err = capsys.readouterr()
    assert done.value.code == 2 and says in err and out == ""
