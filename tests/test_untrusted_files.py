"""The user's files and untrusted models (issue 22, items 1 and 2): no command replaces a
file it read, whatever the path, link or hard link that names it, and writes nothing
when one would; a model reaches no file outside its directory tree (and the shipped
parts) unless the user includes it; what is not a regular file is never read; a file
that is not a model is named, never quoted; a long line is quoted only around its place."""

from __future__ import annotations

import json
import os
import shutil

import pytest

import mtt
from mtt import files
from mtt.cli.main import main
from mtt.language.diagnostics import QUOTE_WIDTH

PART = "model part\nSS:p -> R:r(1)\n"
TOP = (
    'model top\nunknown c = 1\nsubsystem s = "{}"\n'
    "Se:v -> 1:a\n1:a -> C:c\n1:a -> Df:y\n1:a -> s.p\n"
)
SECRET = "TOKEN=abc123\nPASSWORD=hunter2\n"


def run(capsys, *argv) -> tuple[int, str, str]:
    status = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return status, out, err


@pytest.fixture
def work(tmp_path, monkeypatch):
    """A working directory holding the RLC model (m.bg) and its simulated data (d.csv)."""
    monkeypatch.chdir(tmp_path)
    shutil.copy(mtt.example("rlc"), tmp_path / "m.bg")
    t = [i / 100 for i in range(101)]
    y = mtt.load("m.bg").simulate(t, [1.0] * len(t))
    rows = "".join(f"{a!r},1.0,{b!r}\n" for a, b in zip(t, y.tolist(), strict=True))
    (tmp_path / "d.csv").write_text("t,u,y\n" + rows)
    return tmp_path


def snapshot(directory) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(directory.iterdir()) if p.is_file()}


@pytest.mark.parametrize(
    ("argv", "link"),
    [
        (["compile", "m.bg", "-o", "m.bg"], None),
        (["simulate", "m.bg", "--csv", "m.bg", "--data-plot", "new.png"], None),
        (["draw", "m.bg", "-o", "pic.svg"], "m.bg"),  # pic.svg: a symbolic link to the model
        (["bode", "m.bg", "-o", "pic.svg"], "m.bg"),
        (["compile", "m.bg", "-o", "hard.py"], "hard"),  # hard.py: a hard link to the model
        (["fit", "m.bg", "--data", "d.csv", "--csv", "d.csv"], None),
        (["fit", "m.bg", "--data", "d*.csv", "--csv", "d.csv"], None),
        (["estimate", "m.bg", "--data", "d.csv", "--k0", "1", "--plot", "d.csv"], None),
        (["simulate", "m.bg", "--signal", "d.csv", "--csv", "./d.csv"], None),
    ],
)
def test_no_command_replaces_a_file_it_reads(work, capsys, argv, link):
    if link == "hard":
        os.link(work / "m.bg", work / "hard.py")
    elif link:
        (work / "pic.svg").symlink_to(work / link)
    before = snapshot(work)
    status, out, err = run(capsys, *argv, "--json")
    assert status == 2, err
    (error,) = json.loads(out.splitlines()[-1])["errors"]
    assert error["kind"] == "io" and "nothing was written" in error["message"]
    assert "would replace it" in err
    assert snapshot(work) == before  # the input, and no other output either


def test_a_subsystem_file_is_an_input_too(work, capsys):
    (work / "part.bg").write_text(PART)
    (work / "top.bg").write_text(TOP.format("part.bg"))
    status, _, err = run(capsys, "compile", "top.bg", "-o", "part.bg")
    assert status == 2 and "read by this command as a model file" in err
    assert (work / "part.bg").read_text() == PART


def test_the_api_never_compiles_over_the_model(work):
    model = mtt.load("m.bg")
    with pytest.raises(mtt.MttError, match="would replace it") as caught:
        model.compile("m.bg")
    assert caught.value.kind == "io" and (work / "m.bg").read_text().startswith("#")
    (work / "x.py").write_text("kept")
    with pytest.raises(files.FileClash):
        files.write_atomic("./x.py", "", inputs=[work / "x.py"])
    assert (work / "x.py").read_text() == "kept"


def test_a_nonlinear_models_simulator_is_never_written_over_it(tmp_path, capsys, monkeypatch):
    # compile without --at writes the simulator: the same check as for an estimator
    monkeypatch.chdir(tmp_path)
    shutil.copy(mtt.example("two_tanks"), "t.bg")
    before = snapshot(tmp_path)
    status, _, err = run(capsys, "compile", "t.bg", "-o", "t.bg")
    assert status == 2 and "read by this command as a model file" in err
    with pytest.raises(mtt.MttError, match="would replace it"):
        mtt.load("t.bg").compile("t.bg")
    assert snapshot(tmp_path) == before


# --- what a model may read ------------------------------------------------------------------


@pytest.fixture
def tree(tmp_path, monkeypatch):
    """model/ (the model's directory) beside outside/ (a part and a file of secrets)."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "model").mkdir()
    (tmp_path / "outside").mkdir()
    (tmp_path / "outside" / "part.bg").write_text(PART)
    (tmp_path / "outside" / "secret").write_text(SECRET)
    return tmp_path


def check(capsys, *argv) -> tuple[int, dict, str]:
    status, out, err = run(capsys, "check", "--json", *argv)
    (record,) = json.loads(out)["files"]  # one file's record
    return status, record, err


@pytest.mark.parametrize("reference", ["../outside/part.bg", "link.bg"])
def test_a_subsystem_outside_the_model_tree_needs_include(tree, capsys, reference):
    (tree / "model" / "link.bg").symlink_to(tree / "outside" / "part.bg")
    (tree / "model" / "top.bg").write_text(TOP.format(reference))
    status, record, _ = check(capsys, "model/top.bg")
    (error,) = record["errors"]
    assert status == 2 and (error["kind"], error["line"], error["column"]) == ("io", 3, 11)
    assert "outside the model's directory" in error["message"] and "--include" in error["message"]
    status, record, _ = check(capsys, "model/top.bg", "--include", "outside")
    assert status == 0 and record["ok"]
    assert mtt.load("model/top.bg", include=tree / "outside").name == "top"
    with pytest.raises(mtt.MttError, match="outside the model's directory"):
        mtt.load("model/top.bg")


def test_the_shipped_parts_are_always_reachable(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    shipped = mtt.example("absorber_stages").parent / "parts" / "absorber_stage.bg"
    (tmp_path / "stage.bg").symlink_to(shipped)
    text = mtt.example("absorber_stages").read_text().replace("parts/absorber_stage.bg", "stage.bg")
    (tmp_path / "m.bg").write_text(text)
    assert check(capsys, "m.bg")[0] == 0


@pytest.mark.parametrize("target", ["secret", "/proc/self/environ"])
def test_a_file_that_is_not_a_model_is_named_never_quoted(tree, capsys, monkeypatch, target):
    monkeypatch.setenv("MTT_TEST_TOKEN", "hunter3")
    link = tree / "model" / "s.bg"
    link.symlink_to(tree / "outside" / target if target == "secret" else target)
    (tree / "model" / "top.bg").write_text(TOP.format("s.bg"))
    for include in ([], ["--include", "/"]):  # refused as outside, then as not a model
        status, out, err = run(capsys, "check", "model/top.bg", *include)
        assert status == 2 and err.count("error[io]") == 1
        for secret in ("abc123", "hunter2", "hunter3", "TOKEN"):
            assert secret not in out + err


def test_a_file_without_a_model_line_is_one_error_at_the_statement(tree, capsys):
    (tree / "model" / "notes.bg").write_text(SECRET * 40)
    (tree / "model" / "top.bg").write_text(TOP.format("notes.bg"))
    status, record, _ = check(capsys, "model/top.bg")
    (error,) = record["errors"]
    assert (error["kind"], error["file"], error["line"]) == ("io", "model/top.bg", 3)
    assert "is not a model file" in error["message"] and "abc123" not in json.dumps(record)


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs named pipes")
@pytest.mark.parametrize("role", ["model", "data", "signal"])
def test_a_pipe_is_refused_at_once(work, capsys, role):
    os.mkfifo(work / "pipe.bg")  # reading it would block for ever
    argv = {
        "model": ["check", "pipe.bg"],
        "data": ["fit", "m.bg", "--data", "pipe.bg"],
        "signal": ["simulate", "m.bg", "--signal", "pipe.bg"],
    }[role]
    status, _, err = run(capsys, *argv)
    assert status == 2 and "not a regular file" in err


def test_system_files_are_refused_before_they_are_read(work, capsys):
    status, _, err = run(capsys, "fit", "m.bg", "--data", "/dev/zero")
    assert status == 2 and "/dev/zero: is a system file" in err
    (work / "env.bg").symlink_to("/proc/self/environ")
    status, _, err = run(capsys, "check", "env.bg")
    assert status == 2 and "a system file" in err


def test_a_diagnostic_quotes_only_the_place_in_a_long_line(tmp_path, capsys):
    line = "param p = " + "1 + " * 2000 + "q"
    (tmp_path / "long.bg").write_text(f"model m\n{line}\nSe:v -> C:c\n")
    status, _, err = run(capsys, "check", tmp_path / "long.bg")
    quoted = [text for text in err.splitlines() if text.startswith(" 2 | ")]
    assert status == 2 and quoted and all(len(text) <= QUOTE_WIDTH + 12 for text in quoted)
    caret = err.splitlines()[err.splitlines().index(quoted[0]) + 1]
    assert quoted[0].endswith("+ q") and caret.index("^") < len(quoted[0])


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs named pipes")
@pytest.mark.parametrize("there", ["directory", "fifo", "latin-1"])
def test_examples_copy_never_replaces_what_is_not_an_example(tmp_path, capsys, there):
    destination = tmp_path / "rlc.bg"
    if there == "directory":
        destination.mkdir()
    elif there == "fifo":
        os.mkfifo(destination)
    else:
        destination.write_bytes(b"\xff\xfe model")
    status, _, err = run(capsys, "examples", "--copy", tmp_path, "--force")
    replaced = there == "latin-1"  # a regular file: --force replaces it
    assert status == (0 if replaced else 2) and ("error[io]" in err) != replaced
    if not replaced:
        assert sorted(p.name for p in tmp_path.iterdir()) == ["rlc.bg"]  # nothing copied


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs named pipes")
def test_a_generated_module_for_a_batch_is_read_as_a_file_too(tmp_path):
    from mtt.batch.api import estimator

    os.mkfifo(tmp_path / "pipe.py")
    with pytest.raises(mtt.MttError, match="not a regular file") as caught:
        estimator(tmp_path / "pipe.py")
    assert caught.value.kind == "io"


@pytest.mark.parametrize(
    ("text", "line", "message"),
    [
        ("t,u,y\n0,1,0\n\n1,1,1e300\n", 4, "column 'y' holds 1e+300: signals must stay within"),
        ("t,u,y\n0,1,0\n1e308,1,1\n", 3, "column 't' holds 1e+308: times must stay within 1e+15"),
        ("t,u,y\n0,1,0\n2,1,1\n1,1,0\n", 4, "the times (column 't') must increase strictly"),
        ("a,b,c\n0,1,0\n", 1, "no column 't' (the header names a, b, c): name the time"),
        ("t;u;y\n0;1;0\n1;1e300;1\n", 3, "column 'u' holds 1e+300"),
    ],
)
def test_what_is_wrong_in_a_csv_file_is_reported_at_its_line(work, capsys, text, line, message):
    (work / "bad.csv").write_text(text)
    status, out, err = run(capsys, "fit", "m.bg", "--data", "bad.csv", "--json")
    (error,) = json.loads(out)["errors"]
    assert status == 2 and f"bad.csv:{line}: {message}" in err
    assert (error["file"], error["line"], error["kind"]) == ("bad.csv", line, "bad_data")
