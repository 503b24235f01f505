"""The deriving commands: `mtt causality`, `ss`, `tf` and `theta`, their options and errors.

A few tests run the real command line in a child process (exit codes, streams); the rest
call `mtt.cli.main` in this process, which is the same code and much faster.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import sympy

from mtt.cli.main import EXIT_MODEL_ERROR, EXIT_OK, main

ROOT = Path(__file__).resolve().parent.parent
MODELS = ROOT / "models"
SYSTEMS = Path(__file__).resolve().parent / "data" / "systems"

DC_DRIVE_THETA = [[10, 0], [10, 10], [1, 11], [0, 10], [0, 1], [-10, 0], [0, 0], [0, -10]]
JSON_KEYS = ["ok", "model", "input", "output", "unknown", "unknowns", "monomials", "degrees",
             "symbols", "names", "num", "den", "n", "m", "N", "theta", "order"]  # fmt: skip


def run(capsys, *argv) -> tuple[int, str, str]:
    """`mtt ARGV` in this process: exit status, stdout, stderr."""
    status = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return status, out, err


def table(text: str) -> list[list[str]]:
    """The rows of a printed Theta table (label, then the entries)."""
    rows = []
    for line in text.splitlines():
        cells = line.split()
        if (
            cells
            and (cells[0].startswith("a") or cells[0].startswith("-b"))
            and cells[0][-1:].isdigit()
        ):
            rows.append(cells[1:])
    return rows


def check_json_shape(record: dict) -> None:
    assert list(record) == JSON_KEYS
    assert isinstance(record["model"], str)
    assert record["unknown"] is None or isinstance(record["unknown"], str)
    assert all(isinstance(x, str) for x in record["symbols"])
    assert isinstance(record["num"], str) and isinstance(record["den"], str)
    assert all(isinstance(record[key], int) for key in ("n", "m", "N", "order"))
    assert len(record["theta"]) == record["n"] + record["m"] + 2
    assert all(len(row) == len(record["monomials"]) for row in record["theta"])
    assert record["unknowns"] == ([record["unknown"]] if record["unknown"] else record["unknowns"])
    assert all(len(monomial) == len(record["unknowns"]) for monomial in record["monomials"])
    assert set(record["degrees"]) == set(record["unknowns"])
    assert all(isinstance(e, str) for row in record["theta"] for e in row)
    assert "^" not in record["num"] + record["den"]  # sympy syntax: powers are **


# --- the real command line ---------------------------------------------------------------


def test_theta_dc_drive_prints_eq_25(mtt):
    done = mtt("theta", "models/dc_drive.bg")
    assert done.returncode == 0, done.stderr
    assert table(done.stdout) == [[str(x) for x in row] for row in DC_DRIVE_THETA]
    assert "n = 4, m = 2, N = 1" in done.stdout


def test_theta_absorber_keep_json_is_eq_27(mtt):
    done = mtt("theta", "models/absorber.bg", "--keep", "tau,l", "--json")
    assert done.returncode == 0, done.stderr
    record = json.loads(done.stdout)
    check_json_shape(record)
    assert record["symbols"] == ["tau", "l"]
    assert (record["n"], record["m"], record["N"], record["order"]) == (3, 0, 3, 3)
    assert record["theta"] == [
        ["l", "l", "l", "l"],
        ["3*l*tau", "4*l*tau", "3*l*tau", "0"],
        ["3*l*tau**2", "3*l*tau**2", "0", "0"],
        ["l*tau**3", "0", "0", "0"],
        ["0", "0", "0", "-1"],
    ]
    assert record["num"] == "k**3"


def test_tf_symbolic_rlc_json(mtt):
    done = mtt("tf", "models/rlc.bg", "--symbolic", "--json")
    assert done.returncode == 0, done.stderr
    record = json.loads(done.stdout)
    check_json_shape(record)
    assert record == {
        "ok": True,
        "model": "rlc",
        "input": "Se:v",
        "output": "Df:i",
        "unknown": "c",
        "unknowns": ["c"],
        "monomials": [[0], [1]],
        "degrees": {"c": 1},
        "symbols": ["r", "l"],
        "names": {"c": "c", "l": "l", "r": "r"},
        "num": "c*s",
        "den": "c*l*s**2 + c*r*s + 1",
        "n": 2,
        "m": 1,
        "N": 1,
        "theta": [["1", "0"], ["0", "r"], ["0", "l"], ["0", "0"], ["0", "-1"]],
        "order": 2,
    }


def test_derivation_error_exit_code_and_rendering(mtt, tmp_path):
    path = tmp_path / "bad.bg"
    path.write_text("model bad\nunknown k = 1\nSe:v -> 1:j\n1:j -> R:r(sqrt(k))\n1:j -> Df:i\n")
    done = mtt("tf", str(path))
    assert done.returncode == EXIT_MODEL_ERROR
    assert done.stdout == ""
    assert f"{path}:4:12: error[non_rational_unknown]:" in done.stderr
    assert " 4 | 1:j -> R:r(sqrt(k))" in done.stderr


# --- in process: tf ----------------------------------------------------------------------


def test_tf_dc_drive_text(capsys):
    status, out, _ = run(capsys, "tf", MODELS / "dc_drive.bg")
    assert status == EXIT_OK
    assert "numerator   (m = 2):  10*k*s**2 + 10" in out
    assert "denominator (n = 4):" in out
    assert "values substituted: ra = 1, ia = 1/10, jm = 1, km = 1, ks = 1" in out


@pytest.mark.parametrize(
    "args, num, den, symbols",
    [
        # eq. (24)
        (["models/dc_drive.bg"], "10*(k*s**2 + 1)",
         "(s**3 + 10*s**2 + 11*s + 10)*k*s + s**2 + 10*s + 10", []),
        # eq. (26)
        (["models/absorber.bg", "--keep", "tau,l"], "k**3",
         "l*((k + s*tau + 1)*(3*s*tau + 1)*k + (s*tau + 1)**3 + k**3)", ["tau", "l"]),
        # eq. (26) with tau = 2 and l = 1/2
        (["models/absorber.bg"], "2*k**3",
         "(k + 2*s + 1)*(6*s + 1)*k + (2*s + 1)**3 + k**3", []),
        # the options: --unknown, --keep (twice), --set
        (["models/rlc.bg", "--unknown", "r"], "2*s", "s**2 + 2*r*s + 20", []),
        (["models/rlc.bg", "--keep", "r", "--keep", "l"], "c*s", "c*l*s**2 + c*r*s + 1",
         ["r", "l"]),
        (["models/rlc.bg", "--set", "r=1.5", "--set", "l=1"], "2*c*s", "2*c*s**2 + 3*c*s + 2",
         []),
        (["models/rlc.bg", "--symbolic", "--set", "r=3"], "c*s", "c*l*s**2 + c*r*s + 1",
         ["r", "l"]),
    ],
)  # fmt: skip
def test_tf_json(capsys, args, num, den, symbols):
    status, out, _ = run(capsys, "tf", *[ROOT / a if a.endswith(".bg") else a for a in args],
                         "--json")  # fmt: skip
    assert status == EXIT_OK
    record = json.loads(out)
    check_json_shape(record)
    assert sympy.expand(sympy.sympify(record["num"]) - sympy.sympify(num)) == 0
    assert sympy.expand(sympy.sympify(record["den"]) - sympy.sympify(den)) == 0
    assert record["symbols"] == symbols


def test_tf_latex(capsys):
    status, out, _ = run(capsys, "tf", MODELS / "rlc.bg", "--symbolic", "--latex")
    assert status == EXIT_OK
    assert out.strip().startswith("G(s) = \\frac{c\\,s}{")


def test_theta_latex(capsys):
    status, out, _ = run(capsys, "theta", MODELS / "rlc.bg", "--latex")
    assert status == EXIT_OK
    assert out.strip().startswith("\\Theta = \\left[\\begin{matrix}2 & 0")


def test_theta_json_order_counts_integral_storage(capsys):
    # source_on_capacitor: the only storage is dependent, so the order is 0
    status, out, _ = run(capsys, "theta", SYSTEMS / "source_on_capacitor.bg", "--json")
    assert status == EXIT_OK
    record = json.loads(out)
    check_json_shape(record)
    assert (record["n"], record["m"], record["order"]) == (0, 1, 0)
    assert record["theta"] == [["1", "0"], ["0", "0"], ["0", "-1"]]


# --- causality and ss --------------------------------------------------------------------


def test_causality_lists_strokes_and_dependent_storage(capsys):
    status, out, _ = run(capsys, "causality", SYSTEMS / "parallel_caps.bg")
    assert status == EXIT_OK
    assert "    1  Sf:i |-> 0:n" in out
    assert "    3  0:n ->| C:c2" in out  # the junction imposes the dependent capacitor's effort
    assert "dependent storage (derivative causality): C:c2" in out
    assert "algebraic loops (resistors with an arbitrary causality): none" in out


def test_causality_lists_algebraic_loops(capsys):
    status, out, _ = run(capsys, "causality", SYSTEMS / "resistor_network.bg")
    assert status == EXIT_OK
    assert "algebraic loops (resistors with an arbitrary causality): R:r1" in out
    assert "dependent storage (derivative causality): none" in out


def test_ss_prints_equations_and_matrices(capsys):
    status, out, _ = run(capsys, "ss", MODELS / "rlc.bg")
    assert status == EXIT_OK
    assert "  x = [p_l, q_c]" in out
    for name in "EABCD":
        assert f"\n{name} =\n" in out
    assert "  e1 = u" in out and "  y = f5" in out


def test_ss_latex(capsys):
    status, out, _ = run(capsys, "ss", MODELS / "rlc.bg", "--symbolic", "--latex")
    assert status == EXIT_OK
    assert [line.split(" = ")[0] for line in out.strip().splitlines()] == list("EABCD")


# --- errors ------------------------------------------------------------------------------


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "m.bg"
    path.write_text(text)
    return path


def test_causal_conflict(capsys, tmp_path):
    path = write(tmp_path, "model two\ninput Se:a\nSe:a -> 0:n\nSe:b -> 0:n\n0:n -> De:v\n")
    for command in ("causality", "ss", "tf", "theta"):
        status, out, err = run(capsys, command, path)
        assert (status, out) == (EXIT_MODEL_ERROR, "")
        assert "error[causal_conflict]" in err and "Se:a" in err and "Se:b" in err
        assert f"{path}:4:1:" in err or f"{path}:3:1:" in err


def test_singular_model(capsys, tmp_path):
    path = write(
        tmp_path,
        "model cancel\nunknown c1 = 1\nSe:v -> 1:j\n1:j -> C:c1\n1:j -> C:c2(-c1)\n1:j -> Df:i\n",
    )
    status, out, err = run(capsys, "tf", path)
    assert (status, out) == (EXIT_MODEL_ERROR, "")
    assert err.startswith(f"{path}: error[singular_model]:")


def test_no_unknown(capsys, tmp_path):
    path = write(tmp_path, (MODELS / "rlc.bg").read_text().replace("unknown c", "param c"))
    status, out, err = run(capsys, "theta", path)
    assert (status, out) == (EXIT_MODEL_ERROR, "")
    assert "error[no_unknown]" in err
    status, out, _ = run(capsys, "tf", path)  # tf needs no unknown
    assert status == EXIT_OK and "unknown none" in out


@pytest.mark.parametrize(
    "option, named",
    [
        (["--keep", "r,nope"], "'nope'"),
        (["--set", "nope=1"], "'nope'"),
        (["--unknown", "nope"], "'nope'"),
    ],
)
def test_bad_parameter_names(capsys, option, named):
    status, out, err = run(capsys, "theta", MODELS / "rlc.bg", *option)
    assert (status, out) == (EXIT_MODEL_ERROR, "")
    assert "error[undeclared_parameter]" in err and named in err


@pytest.mark.parametrize("value", ["r", "r=", "r=sqrt(", "r=s", "=2"])
def test_malformed_set_is_a_usage_error(capsys, value):
    with pytest.raises(SystemExit) as caught:
        main(["tf", str(MODELS / "rlc.bg"), "--set", value])
    assert caught.value.code == 2
    assert "--set" in capsys.readouterr().err


# --- several unknowns ----------------------------------------------------------------------


def test_theta_of_two_unknowns_labels_the_monomials(capsys):
    status, out, _ = run(capsys, "theta", MODELS / "dc_motor.bg")
    assert status == EXIT_OK
    lines = out.splitlines()
    assert lines[0] == "model dc_motor: from Se:v to Df:speed; unknowns ra, jl; symbolic none"
    assert "total degree 2 (in ra 1, jl 1)" in out and "columns 1, ra, jl, ra*jl" in out
    assert lines[4].split() == ["1", "ra", "jl", "ra*jl"]
    assert table(out) == [["100", "10", "0", "0"], ["1", "100", "0", "100"],
                          ["10", "0", "10", "0"], ["-100", "0", "0", "0"]]  # fmt: skip


def test_theta_json_of_unknowns_chosen_on_the_command_line(capsys):
    status, out, _ = run(capsys, "theta", MODELS / "dc_motor.bg", "--unknown", "jl,ra", "--json")
    assert status == EXIT_OK
    record = json.loads(out)
    check_json_shape(record)
    assert (record["unknown"], record["unknowns"], record["N"]) == (None, ["jl", "ra"], 2)
    assert record["monomials"] == [[0, 0], [1, 0], [0, 1], [1, 1]]
    assert record["degrees"] == {"jl": 1, "ra": 1}
    assert record["theta"][1] == ["1", "0", "100", "100"]
    # one of them: the other keeps its value, and the record reads as version 1's
    status, out, _ = run(capsys, "theta", MODELS / "dc_motor.bg", "--unknown", "jl", "--json")
    record = json.loads(out)
    assert (record["unknown"], record["unknowns"], record["N"]) == ("jl", ["jl"], 1)
    assert (record["monomials"], record["degrees"]) == ([[0], [1]], {"jl": 1})


def test_compile_writes_an_estimator_of_every_unknown(capsys, tmp_path):
    target = tmp_path / "dc_motor.py"
    status, out, err = run(capsys, "compile", MODELS / "dc_motor.bg", "-o", target)
    assert (
        status == 0
        and out == f"wrote {target}: estimator of ra, jl for dc_motor (n = 2, m = 0, N = 2)\n"
    )
    assert "UNKNOWNS = ('ra', 'jl')" in target.read_text()
    assert run(capsys, "compile", MODELS / "dc_motor.bg", "-o", target, "--unknown", "jl")[0] == 0
    assert "UNKNOWN = 'jl'" in target.read_text()


# --- the input and output chosen on the command line --------------------------------------

SEVERAL_PORTS = SYSTEMS / "several_ports.bg"


@pytest.mark.parametrize(
    "options,expected",
    [
        # the file's choice, Se:v to De:vc: the divider r against g || C (r = 2)
        ([], "g / (2*c*g*s + g + 2)"),
        # the leak current into r || g || C, with the voltage sources shorted
        (["--input", "Sf:leak"], "2*g / (2*c*g*s + g + 2)"),
        # the loop current it drives back through r: -vc/r
        (["--input", "Sf:leak", "--output", "Df:current"], "-g / (2*c*g*s + g + 2)"),
        # the bias source drives the loop current through r and g || C
        (["--input", "Se:bias", "--output", "Df:current"], "(c*g*s + 1) / (2*c*g*s + g + 2)"),
    ],
)
def test_input_and_output_options_choose_the_transfer_function(capsys, options, expected):
    status, out, err = run(capsys, "tf", SEVERAL_PORTS, *options)
    assert status == EXIT_OK, err
    assert out.splitlines()[-1] == f"  G(s) = {expected}"


def test_input_and_output_options_apply_to_every_command(capsys):
    status, out, _ = run(capsys, "show", SEVERAL_PORTS, "--input", "Sf:leak")
    assert status == EXIT_OK and "input   Sf:leak" in out
    status, out, _ = run(capsys, "check", SEVERAL_PORTS, "--output", "Df:current")
    assert status == EXIT_OK and "input Se:v, output Df:current" in out
    status, out, _ = run(capsys, "theta", SEVERAL_PORTS, "--input", "Sf:leak", "--json")
    assert json.loads(out)["input"] == "Sf:leak"


@pytest.mark.parametrize(
    "options,kind,message",
    [
        (["--input", "Df:current"], "no_input", "Df:current (chosen with --input) is not a source"),
        (["--output", "Se:v"], "no_output", "Se:v (chosen with --output) is not a detector"),
        (["--output", "De:nope"], "undeclared_component",
         "De:nope (chosen with --output) does not exist"),
        (["--input", "Sf:v"], "undeclared_component",
         "Sf:v (chosen with --input) does not exist (it is Se:v)"),
    ],
)  # fmt: skip
def test_input_and_output_options_naming_the_wrong_component(capsys, options, kind, message):
    status, out, err = run(capsys, "tf", SEVERAL_PORTS, *options)
    assert (status, out) == (EXIT_MODEL_ERROR, "")
    assert err.strip() == f"{SEVERAL_PORTS}: error[{kind}]: {message}"


def test_input_option_needs_type_and_name(capsys):
    with pytest.raises(SystemExit) as done:
        main(["tf", str(SEVERAL_PORTS), "--input", "leak"])
    assert done.value.code == 2
    assert "argument --input: expected TYPE:NAME, not 'leak'" in capsys.readouterr().err
