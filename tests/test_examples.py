"""The example models ship with mtt: `mtt examples` lists them and copies them out."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

import mtt
from mtt.cli.main import main

ROOT = Path(__file__).resolve().parent.parent


def run(capsys, *argv):
    status = main(list(argv))
    out, err = capsys.readouterr()
    return status, out, err


def test_the_examples_are_the_models_directory():
    names = sorted(path.stem for path in (ROOT / "models").glob("*.bg"))
    assert mtt.example("dc_drive").read_text() == (ROOT / "models" / "dc_drive.bg").read_text()
    assert {"dc_drive", "absorber", "rlc"} <= set(names)


def test_examples_lists_each_model_with_its_description(capsys):
    status, out, _ = run(capsys, "examples", "--json")
    record = json.loads(out)
    assert status == 0 and record["ok"]
    described = {item["name"]: item["description"] for item in record["examples"]}
    assert described["rlc"] == "series RLC circuit"
    status, out, _ = run(capsys, "examples")
    assert "dc_drive" in out.split()
    line = next(line for line in out.splitlines() if line.startswith("dc_drive "))
    assert line.split(None, 1)[1].startswith("voltage-driven DC motor with a flexible shaft")


def test_examples_copy_into_a_new_directory_and_keep_edits(tmp_path, capsys, monkeypatch):
    target = tmp_path / "elsewhere" / "mine"
    (tmp_path / "work").mkdir()
    monkeypatch.chdir(tmp_path / "work")  # a new directory outside it: only with --parents
    status, _, err = run(capsys, "examples", "--copy", str(target))
    assert status == 2 and "--parents" in err and not target.parent.exists()
    status, out, _ = run(capsys, "examples", "--copy", str(target), "--parents")
    assert (
        status == 0 and (target / "absorber.bg").read_text() == mtt.example("absorber").read_text()
    )
    # with the subsystem files their models read: the copies work where they are
    assert (target / "parts" / "absorber_stage.bg").exists()
    assert run(capsys, "check", str(target / "absorber_stages.bg"))[0] == 0
    assert run(capsys, "examples", "--copy", str(target))[0] == 0  # the same files: nothing to do
    (target / "rlc.bg").write_text("# my edits\n")
    status, _, err = run(capsys, "examples", "--copy", str(target))
    assert status == 2 and "rlc.bg exists and differs from the example: not replaced" in err
    assert (target / "rlc.bg").read_text() == "# my edits\n"
    assert run(capsys, "examples", "--copy", str(target), "--force")[0] == 0
    assert (target / "rlc.bg").read_text() == mtt.example("rlc").read_text()
    assert main(["check", str(target / "rlc.bg")]) == 0


def test_an_unknown_example_names_those_there_are():
    with pytest.raises(mtt.MttError) as caught:
        mtt.example("nope")
    assert caught.value.kind == "io" and "dc_drive" in str(caught.value)


def test_the_api_lists_and_copies_the_examples_as_the_command_does(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    listed = mtt.examples()
    assert main(["examples", "--json"]) == 0
    shown = json.loads(capsys.readouterr().out)["examples"]
    assert [(e.name, e.description, str(e.path)) for e in listed] == [
        (e["name"], e["description"], e["file"]) for e in shown
    ]
    assert {"dc_drive", "absorber", "rlc"} <= {e.name for e in listed}
    written = mtt.copy_examples("mine")
    assert (tmp_path / "mine" / "dc_drive.bg").read_bytes() == mtt.example("dc_drive").read_bytes()
    assert len(written) >= len(listed) and mtt.copy_examples("mine") == []  # all there already
    (tmp_path / "mine" / "rlc.bg").write_text("mine")
    with pytest.raises(mtt.MttError, match="differs from the example: not replaced"):
        mtt.copy_examples("mine")
    assert mtt.copy_examples("mine", force=True) == [Path("mine", "rlc.bg")]
