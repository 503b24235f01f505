"""Shared helpers: read model text without touching the disk, and run the `mtt` command."""

from __future__ import annotations

import os

# BLAS on one thread, before numpy loads it: the estimators' many small matrix products and
# exponentials stall for a scheduler quantum each when OpenBLAS's threads compete with other
# processes (see bench/README.md); results are the same, within rounding.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

from mtt.language.bondgraph import BondGraph, Selection, build
from mtt.language.diagnostics import ModelError, Source
from mtt.language.parse import ParsedModel, parse

pytest_plugins = ["estimators"]  # the generated modules and their paper data, as fixtures

ROOT = Path(__file__).resolve().parent.parent
DATA = Path(__file__).resolve().parent / "data"
MODELS = sorted((ROOT / "models").glob("*.bg"))


def _selection(unknown: str | None) -> Selection:
    return Selection(None if unknown is None else tuple(unknown.split(",")))


class Models:
    """Parse and build model text held in a string, reported as `test.bg`."""

    @staticmethod
    def parse(text: str) -> ParsedModel:
        return parse(Source("test.bg", text))

    @staticmethod
    def build(text: str, unknown: str | None = None) -> BondGraph:
        return build(parse(Source("test.bg", text)), _selection(unknown))

    @staticmethod
    def failure(text: str, unknown: str | None = None) -> ModelError:
        """The ModelError that reading `text` raises (the test fails if there is none)."""
        with pytest.raises(ModelError) as caught:
            build(parse(Source("test.bg", text)), _selection(unknown))
        return caught.value


@pytest.fixture
def models() -> Models:
    return Models()


@dataclass(frozen=True)
class Run:
    returncode: int
    stdout: str
    stderr: str


def _environment() -> dict[str, str]:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    env.pop("MTT_DEBUG", None)  # tracebacks must not appear unless asked for
    return env


def run_mtt(*args: str, cwd: Path = ROOT) -> Run:
    """`python -m mtt ARGS` in a child process (the real command line, exit code and streams)."""
    (run,) = run_mtt_together([list(args)], cwd=cwd)
    return run


def run_mtt_together(commands: list[list[str]], cwd: Path = ROOT) -> list[Run]:
    """Several `python -m mtt` commands at once (each child spends most of its time starting)."""
    children = [
        subprocess.Popen(
            [sys.executable, "-m", "mtt", *args],
            cwd=cwd,
            env=_environment(),
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        for args in commands
    ]
    runs = []
    for child in children:
        try:
            stdout, stderr = child.communicate(timeout=60)
        except subprocess.TimeoutExpired:
            child.kill()
            raise
        runs.append(Run(child.returncode, stdout, stderr))
    return runs


@pytest.fixture(scope="session")
def mtt():
    return run_mtt


@pytest.fixture(scope="session")
def mtt_together():
    return run_mtt_together
