"""The `mtt check` / `mtt show` command line: exit codes, output formats, no tracebacks.

The real command runs in child processes (`python -m mtt`), a few of them, each doing as
much as it can; finer points of the output are checked in-process through `main`.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from mtt import __version__
from mtt.cli.main import main

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / "tests" / "data"
MODELS = sorted((ROOT / "models").glob("*.bg"))
ERROR_FILES = sorted((DATA / "errors").glob("*.bg"))

RECORD_KEYS = {
    "file",
    "ok",
    "errors",
    "warnings",
    "model",
    "components",
    "bonds",
    "parameters",
    "unknown",
    "input",
    "output",
    "ports",
}
DIAGNOSTIC_KEYS = {"file", "kind", "line", "column", "message", "notes"}


def relative(path: Path) -> str:
    return str(path.relative_to(ROOT))


def assert_record_shape(record: dict) -> None:
    """The documented shape of one `check --json` object, key by key and type by type."""
    assert set(record) == RECORD_KEYS
    assert isinstance(record["file"], str)
    assert isinstance(record["ok"], bool)
    for key in ("errors", "warnings"):
        assert isinstance(record[key], list)
        for item in record[key]:
            assert set(item) == DIAGNOSTIC_KEYS
            assert isinstance(item["kind"], str) and isinstance(item["file"], str)
            assert isinstance(item["notes"], list)
            assert isinstance(item["message"], str) and item["message"]
            assert (item["line"] is None) == (item["column"] is None)
            for place in ("line", "column"):
                assert item[place] is None or (type(item[place]) is int and item[place] >= 1)
    assert record["model"] is None or isinstance(record["model"], str)
    assert type(record["components"]) is int and type(record["bonds"]) is int
    assert isinstance(record["parameters"], dict)
    for name, value in record["parameters"].items():
        assert isinstance(name, str)
        assert value is None or isinstance(value, str)
    assert isinstance(record["unknown"], list)
    assert all(isinstance(name, str) for name in record["unknown"])
    for key in ("input", "output"):
        assert record[key] is None or (isinstance(record[key], str) and ":" in record[key])
    assert record["ok"] == (record["errors"] == [])


# the real command, in child processes ----------------------------------------------


@pytest.fixture(scope="module")
def runs(tmp_path_factory, mtt_together) -> dict:
    """Every child-process command of this module, started together (startup dominates)."""
    work = tmp_path_factory.mktemp("cli")
    marker = work / "pwned_x"
    evil = work / "evil.bg"
    evil.write_text(
        "model evil\n"
        f"param p = __import__('os').system('touch {marker}')\n"
        f"Se:v -> 1:j -> R:r(eval(\"__import__('os').system('touch {marker}')\"))\n"
        "1:j -> Df:i\n"
        "param q = 1e999999999\n"
        "param w = 10^10^10\n",
        encoding="utf-8",
    )
    json_files = [*map(relative, MODELS), *map(relative, ERROR_FILES), "no/such/file.bg"]
    commands = {
        "json": ["check", "--json", *json_files, str(evil)],
        "check_good": ["check", *map(relative, MODELS), "tests/data/valid/active_elements.bg"],
        "check_bad": ["check", "models/rlc.bg", *map(relative, ERROR_FILES), "no/such/file.bg"],
        "show": ["show", "models/rlc.bg"],
        "version": ["--version"],
    }
    results = dict(zip(commands, mtt_together(list(commands.values())), strict=True))
    records = json.loads(results["json"].stdout)["files"]
    return {
        **results,
        "records": {record["file"]: record for record in records},
        "json_files": [*json_files, str(evil)],
        "marker": marker,
    }


def test_check_json_prints_one_document_with_a_record_per_file_in_order(runs):
    run = runs["json"]
    assert run.returncode == 2  # some files have errors
    assert run.stderr == ""
    document = json.loads(run.stdout)  # one document, not a JSON object per line
    assert set(document) == {"ok", "files"} and document["ok"] is False
    assert [record["file"] for record in document["files"]] == runs["json_files"]
    for record in document["files"]:
        assert_record_shape(record)


def test_check_json_on_the_shipped_models(runs):
    records = runs["records"]
    for path in MODELS:
        assert records[relative(path)]["ok"] is True
        assert records[relative(path)]["errors"] == []
    assert records["models/rlc.bg"] == {
        "file": "models/rlc.bg",
        "ok": True,
        "errors": [],
        "warnings": [],
        "model": "rlc",
        "components": 6,
        "bonds": 5,
        "parameters": {"r": "2", "l": "1/2", "c": "1/10"},
        "unknown": ["c"],
        "input": "Se:v",
        "output": "Df:i",
        "ports": [],
    }
    drive = records["models/dc_drive.bg"]
    assert (drive["input"], drive["output"], drive["unknown"]) == ("Se:v", "Df:vm", ["k"])
    assert (drive["components"], drive["bonds"]) == (12, 11)


def test_check_json_on_every_error_file_and_a_missing_one(runs):
    records = [runs["records"][relative(path)] for path in ERROR_FILES]
    records.append(runs["records"]["no/such/file.bg"])
    for record in records:
        assert record["ok"] is False
        assert record["errors"]
    by_file = {Path(r["file"]).stem: r for r in records}
    assert by_file["file"]["errors"] == [
        {
            "file": by_file["file"]["file"],
            "kind": "io",
            "line": None,
            "column": None,
            "message": "cannot read the file: No such file or directory",
            "notes": [],
        }
    ]
    assert by_file["file"]["model"] is None
    assert by_file["self_bond"]["errors"] == [
        {
            "file": by_file["self_bond"]["file"],
            "kind": "self_bond",
            "line": 6,
            "column": 5,
            "message": "a bond from 1:j to itself",
            "notes": [],
        }
    ]
    assert by_file["no_input_none"]["errors"][0]["line"] is None
    # what a file that parses but fails validation still tells
    unknowns = by_file["unconnected_unknowns"]
    assert unknowns["model"] == "unknowns"
    assert unknowns["parameters"] == {"r": "2", "a": "1", "b": "2", "c": None}
    assert unknowns["unknown"] == ["a", "b", "c"]
    assert (unknowns["components"], unknowns["bonds"]) == (5, 3)
    assert (unknowns["input"], unknowns["output"]) == (None, None)
    # a file that does not parse tells nothing about its content
    syntax = by_file["syntax"]
    assert (syntax["model"], syntax["components"], syntax["bonds"]) == (None, 0, 0)
    assert [(e["kind"], e["line"], e["column"]) for e in syntax["errors"]] == [
        ("syntax", 5, 15),
        ("syntax", 7, 6),
    ]


def test_check_text_exit_codes_and_no_traceback(runs):
    good, bad = runs["check_good"], runs["check_bad"]
    assert good.returncode == 0
    assert good.stdout.splitlines()[-1].startswith(
        "tests/data/valid/active_elements.bg: ok: model active, 4 components, 3 bonds"
    )
    assert (
        "models/rlc.bg: ok: model rlc, 6 components, 5 bonds, input Se:v, output Df:i, unknown c"
        in good.stdout.splitlines()
    )
    assert "warning[bond_direction]" in good.stderr  # warnings do not fail a check

    assert bad.returncode == 2
    assert "Traceback" not in bad.stderr and "internal error" not in bad.stderr
    assert bad.stdout.startswith("models/rlc.bg: ok")  # the valid file is still checked
    assert "tests/data/errors/self_bond.bg:6:5: error[self_bond]: " in bad.stderr
    assert "no/such/file.bg: error[io]: cannot read the file" in bad.stderr
    assert "tests/data/errors/several_kinds.bg: 9 errors" in bad.stderr


def test_show_and_version(runs):
    show, version = runs["show"], runs["version"]
    assert show.returncode == 0
    assert show.stderr == ""
    assert show.stdout.splitlines()[:2] == ["model rlc: series RLC circuit", "file models/rlc.bg"]
    assert "  c  = 1/10  unknown  capacitance [F]" in show.stdout.splitlines()
    assert show.stdout.splitlines()[-3:] == ["input   Se:v", "output  Df:i", "unknown c"]

    assert (version.returncode, version.stdout.strip()) == (0, f"mtt {__version__}")


def test_show_of_a_missing_file(capsys):
    assert main(["show", "no/such/file.bg"]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.strip() == (
        "no/such/file.bg: error[io]: cannot read the file: No such file or directory"
    )


def test_program_text_in_a_model_is_never_run(runs):
    record = runs["records"][runs["json_files"][-1]]
    assert [(e["kind"], e["line"]) for e in record["errors"]] == [
        ("syntax", 2),
        ("syntax", 3),
        ("syntax", 5),
        ("syntax", 6),
    ]
    assert not runs["marker"].exists()


# finer points, in-process ------------------------------------------------------------


def test_show_lists_parameters_components_numbered_bonds_and_ports(capsys):
    assert main(["show", str(DATA / "valid" / "everything.bg")]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0] == "model everything: a tour of the .bg language"
    assert "parameters" in out
    table = {line.split()[0]: line for line in out[out.index("parameters") + 1 :] if line}
    assert table["ra"].split()[1:4] == ["=", "3/20", "known"]
    assert "(no value: symbolic)" in table["n"]
    assert table["m"].split()[1:4] == ["=", "10", "unknown"]
    assert "components (14)" in out
    assert any(line.split()[:1] == ["I"] and "la(2*l), m(m)" in line for line in out)
    assert any(line.split()[:1] == ["1"] and line.endswith("a, c") for line in out)
    assert "bonds (13, tail -> head is the direction of positive power)" in out
    bonds = out[out.index("bonds (13, tail -> head is the direction of positive power)") + 1 :]
    assert [line.split() for line in bonds[:3]] == [
        ["1", "Se:v", "->", "1:a"],
        ["2", "1:a", "->", "TF:n"],
        ["3", "TF:n", "->", "0:b"],
    ]
    assert bonds[12].split() == ["13", "Sf:u", "->", "0:b"]
    assert out[-3:] == ["input   Se:v", "output  De:x", "unknown m"]


def test_show_unknown_option_and_model_errors(capsys):
    several = str(DATA / "valid" / "several_unknowns.bg")
    assert main(["show", several]) == 0
    assert capsys.readouterr().out.splitlines()[-1] == "unknown a, b, c"
    assert main(["show", several, "--unknown", "b"]) == 0
    assert capsys.readouterr().out.splitlines()[-1] == "unknown b"


def test_check_unknown_option(capsys):
    several = str(DATA / "valid" / "several_unknowns.bg")
    assert main(["check", several]) == 0
    assert capsys.readouterr().out.strip().endswith(", unknowns a, b, c")
    assert main(["check", several, "--unknown", "c"]) == 0
    assert capsys.readouterr().out.strip().endswith(", unknown c")
    assert main(["check", "--json", several, "--unknown", "c"]) == 0
    assert json.loads(capsys.readouterr().out)["files"][0]["unknown"] == ["c"]
    assert main(["check", "--json", several, "--unknown", "nope"]) == 2
    (record,) = json.loads(capsys.readouterr().out)["files"]
    assert [(e["kind"], e["line"]) for e in record["errors"]] == [("undeclared_parameter", None)]


def test_a_utf8_byte_order_mark_is_ignored(tmp_path, capsys):
    model = tmp_path / "bom.bg"
    model.write_bytes(b"\xef\xbb\xbfmodel m\nunknown a = 1\nSe:v -> 1:j -> R:a\n1:j -> Df:i\n")
    assert main(["check", str(model)]) == 0
    assert "ok: model m" in capsys.readouterr().out


def test_check_text_output_renders_source_and_caret(capsys):
    assert main(["check", str(DATA / "errors" / "bad_argument.bg")]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    lines = captured.err.splitlines()
    head = f"{DATA / 'errors' / 'bad_argument.bg'}:5:6: error[bad_argument]: "
    assert lines[0] == head + "Se:v takes no argument: it is an effort source"
    assert lines[1] == " 5 | Se:v(1) -> 1:j(2) -> R:r(3)"
    assert lines[2] == "   |      ^"
    assert lines[-1] == f"{DATA / 'errors' / 'bad_argument.bg'}: 3 errors"


def test_check_json_warnings_are_listed(capsys):
    assert main(["check", "--json", str(DATA / "valid" / "active_elements.bg")]) == 0
    document = json.loads(capsys.readouterr().out)  # one file: the same shape as several
    assert set(document) == {"ok", "files"} and document["ok"] is True
    (record,) = document["files"]
    assert_record_shape(record)
    assert record["ok"] is True
    assert [(w["kind"], w["line"], w["column"]) for w in record["warnings"]] == [
        ("bond_direction", 5, 1),
        ("bond_direction", 6, 8),
    ]


def test_help_lists_the_commands(capsys):
    with pytest.raises(SystemExit) as done:
        main(["--help"])
    assert done.value.code == 0
    out = capsys.readouterr().out
    assert out.startswith("usage: mtt")
    assert "check" in out and "show" in out
    with pytest.raises(SystemExit) as done:
        main(["check", "--help"])
    assert done.value.code == 0
    assert "--json" in capsys.readouterr().out


def test_usage_errors_exit_with_argparse_status(capsys):
    with pytest.raises(SystemExit) as done:
        main([])
    assert done.value.code == 2
    assert "usage: mtt" in capsys.readouterr().err
    with pytest.raises(SystemExit) as done:
        main(["check"])  # no file
    assert done.value.code == 2
