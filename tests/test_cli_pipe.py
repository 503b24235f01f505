"""A reader that closes the pipe early (`mtt ... | head`) ends the command quietly, with no
traceback and no error line: in mtt's commands and in a generated module's command line."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent


def _to_closed_pipe(arguments: list[str], cwd: Path) -> subprocess.CompletedProcess:
    read, write = os.pipe()
    os.close(read)  # the reader is gone before the command writes
    try:
        return subprocess.run(
            [sys.executable, *arguments], stdout=write, stderr=subprocess.PIPE, text=True,
            cwd=cwd, timeout=120,
        )  # fmt: skip
    finally:
        os.close(write)


@pytest.fixture(scope="module")
def data(tmp_path_factory) -> Path:
    t = np.arange(0.0, 5.0, 0.01)  # short: what is tested is the pipe, not the fit
    u = np.where((t // 2) % 2 == 0, 1.0, -1.0)  # a square wave; the output need not fit
    y = np.sin(t)
    path = tmp_path_factory.mktemp("pipe") / "run.csv"
    path.write_text("t,u,y\n" + "".join(f"{a},{b},{c}\n" for a, b, c in zip(t, u, y, strict=True)))
    return path


@pytest.mark.parametrize(
    "arguments",
    [
        ["-m", "mtt", "theta", "--json", "models/dc_motor.bg"],
        ["-m", "mtt", "estimate", "models/dc_drive.bg", "--k0", "1", "--t-end", "2", "--json"],
        ["-m", "mtt", "fit", "models/dc_drive.bg", "--data", "DATA", "--hold", "zoh", "--json"],
        ["generated/dc_drive.py", "fit", "DATA", "--hold", "zoh", "--json"],
    ],
)
def test_a_closed_pipe_ends_the_command_quietly(arguments, data):
    done = _to_closed_pipe([str(data) if a == "DATA" else a for a in arguments], ROOT)
    # warnings about the made-up record may come, and fit's status 1 (its ok is False: the
    # model does not fit it); no traceback, no error
    assert done.returncode in ((0, 1) if "fit" in arguments else (0,))
    assert "Traceback" not in done.stderr and "error:" not in done.stderr, done.stderr
