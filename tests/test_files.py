"""Files written by mtt are handled as carefully as model text (issue 12, item 9)."""

from __future__ import annotations

import os
import stat
from pathlib import Path

import pytest

import mtt
from mtt import files
from mtt.cli.main import main

RLC = str(mtt.example("rlc"))


def test_a_missing_directory_is_created_inside_the_working_directory(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    files.write_atomic(Path("a") / "b" / "out.txt", "x\n")
    assert (tmp_path / "a" / "b" / "out.txt").read_text() == "x\n"


def test_a_missing_directory_elsewhere_needs_parents(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "work").mkdir()
    monkeypatch.chdir(tmp_path / "work")
    target = tmp_path / "a" / "b" / "out.txt"
    with pytest.raises(FileNotFoundError, match=f"the directory {tmp_path / 'a'} does not exist"):
        files.write_atomic(target, "x\n")
    assert not (tmp_path / "a").exists()
    files.write_atomic(target, "x\n", parents=True)
    assert target.read_text() == "x\n"


def test_a_symbolic_link_is_written_through(tmp_path):
    real = tmp_path / "real.py"
    real.write_text("old\n")
    link = tmp_path / "link.py"
    link.symlink_to(real)
    files.write_atomic(link, "new\n")
    assert link.is_symlink() and real.read_text() == "new\n"
    dangling = tmp_path / "dangling.py"
    dangling.symlink_to(tmp_path / "sub" / "made.py")
    files.write_atomic(dangling, "made\n", parents=True)
    assert (tmp_path / "sub" / "made.py").read_text() == "made\n" and dangling.is_symlink()


@pytest.mark.parametrize("kind", ["fifo", "directory"])
def test_anything_but_a_regular_file_is_refused_and_kept(tmp_path, kind):
    target = tmp_path / "special"
    if kind == "fifo":
        os.mkfifo(target)
    else:
        target.mkdir()
    with pytest.raises(OSError, match="not replaced"):
        files.write_atomic(target, "x")
    mode = os.stat(target).st_mode
    assert (stat.S_ISFIFO if kind == "fifo" else stat.S_ISDIR)(mode)
    assert [p.name for p in tmp_path.iterdir()] == ["special"]  # no temporary left


def test_an_empty_name_is_refused(tmp_path):
    with pytest.raises(ValueError, match="empty"):
        files.write_atomic("", "x")


def test_replacing_a_file_keeps_its_permissions(tmp_path):
    target = tmp_path / "tool.py"
    target.write_text("old\n")
    target.chmod(0o750)
    files.write_atomic(target, "new\n")
    assert stat.S_IMODE(os.stat(target).st_mode) == 0o750


def run(capsys, *argv):
    status = main(list(argv))
    out, err = capsys.readouterr()
    return status, out, err


def test_compile_into_a_directory_writes_model_py_there(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    for given in (str(tmp_path), "new/"):
        status, out, _ = run(capsys, "compile", RLC, "-o", given)
        assert status == 0 and "rlc.py" in out
    assert (tmp_path / "rlc.py").is_file() and (tmp_path / "new" / "rlc.py").is_file()


def test_compile_refuses_a_special_file_and_an_empty_name(tmp_path, capsys):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    status, _, err = run(capsys, "compile", RLC, "-o", str(fifo))
    assert status == 2 and f"{fifo}: not a regular file: not replaced" in err
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)
    status, _, err = run(capsys, "compile", RLC, "-o", "")
    assert status == 2 and "-o needs a file or a directory, not an empty name" in err


def test_model_compile_reports_file_errors_as_mtt_errors(tmp_path):
    model = mtt.load(RLC)
    assert model.compile(tmp_path) == tmp_path / "rlc.py"
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    with pytest.raises(mtt.MttError) as caught:
        model.compile(fifo)
    assert caught.value.kind == "io" and "not a regular file" in str(caught.value)


def test_draw_creates_the_directory_of_its_picture(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    status, _, _ = run(capsys, "draw", RLC, "-o", "figures/rlc.svg")
    assert status == 0 and (tmp_path / "figures" / "rlc.svg").is_file()
    (tmp_path / "work").mkdir()
    monkeypatch.chdir(tmp_path / "work")  # the directory asked for is outside it
    out = tmp_path / "elsewhere" / "rlc.svg"
    status, _, err = run(capsys, "draw", RLC, "-o", str(out))
    assert status == 2 and "--parents" in err and not out.parent.exists()
    status, _, _ = run(capsys, "draw", RLC, "-o", str(out), "--parents")
    assert status == 0 and out.is_file()


def test_draw_to_a_special_file_is_an_error_not_a_crash(tmp_path, capsys):
    fifo = tmp_path / "pipe.svg"
    os.mkfifo(fifo)
    status, _, err = run(capsys, "draw", RLC, "-o", str(fifo))
    assert status == 2 and "error[io]" in err and "not a regular file" in err


def test_a_device_such_as_dev_null_is_refused_and_kept(tmp_path, capsys):
    # `mtt compile -o /dev/null` as root replaced the device with a regular file: here a
    # device of the same numbers (1, 3) made in a temporary directory, never the real one
    device = tmp_path / "null"
    try:
        os.mknod(device, 0o666 | stat.S_IFCHR, os.makedev(1, 3))
    except PermissionError:
        pytest.skip("making a device needs root")
    link = tmp_path / "link.py"
    link.symlink_to(device)
    for target in (device, link):
        status, _, err = run(capsys, "compile", RLC, "-o", str(target))
        assert status == 2 and f"{target}: not a regular file: not replaced" in err
    status, _, err = run(capsys, "simulate", RLC, "--csv", str(device))
    assert status == 2 and "not a regular file" in err
    assert stat.S_ISCHR(os.stat(device).st_mode) and os.stat(device).st_rdev == os.makedev(1, 3)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link.py", "null"]  # no temporary


@pytest.mark.parametrize(
    "argv",
    [
        ["simulate", RLC, "--csv", ""],
        ["simulate", RLC, "--data-plot", ""],
        ["simulate", RLC, "--signal", ""],
        ["estimate", RLC, "--k0", "1", "--plot", ""],
        ["estimate", RLC, "--k0", "1", "--cost-plot", ""],
        ["estimate", RLC, "--k0", "1", "--csv", ""],
        ["fit", RLC, "--plot", ""],
        ["fit", RLC, "--csv", ""],
        ["examples", "--copy", ""],
    ],
)
def test_an_empty_file_name_is_refused_by_every_command(capsys, tmp_path, monkeypatch, argv):
    # it read as the option not given: `simulate --csv ''` printed the samples instead,
    # `examples --copy ''` copied into the working directory
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as caught:
        main(argv)
    flag = argv[argv.index("") - 1]
    assert caught.value.code == 2
    assert f"error: argument {flag}: an empty name" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []
