"""The CLI starts fast because building its parser imports no heavy library.

Timing is measured in bench/startup.py; here the cause is held: which modules a command
leaves in sys.modules, in a fresh interpreter.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent

HEAVY = ("sympy", "scipy", "matplotlib", "numpy", "jinja2", "networkx", "lark")

PROBE = """
import json, sys
from mtt.cli.main import main
try:
    status = main(sys.argv[1:])
except SystemExit as exc:
    status = exc.code
print(json.dumps([status, sorted({name.partition('.')[0] for name in sys.modules})]))
"""


def _imported(*argv: str) -> set[str]:
    """The heavy top-level packages that `mtt ARGV` imports (it must succeed)."""
    done = subprocess.run(
        [sys.executable, "-c", PROBE, *argv], capture_output=True, text=True, check=True
    )
    status, modules = json.loads(done.stdout.splitlines()[-1])
    assert status == 0, done.stdout
    return set(modules) & set(HEAVY)


@pytest.mark.parametrize(
    "argv",
    [
        ("--help",),
        ("--version",),
        ("compile", "--help"),
        ("estimate", "--help"),
        ("tf", "--help"),
        ("draw", "--help"),
        ("identifiability", "--help"),
    ],
)
def test_the_parser_imports_no_heavy_library(argv):
    assert _imported(*argv) == set()


def test_check_imports_only_what_parsing_needs(tmp_path):
    model = tmp_path / "rc.bg"
    model.write_text("model rc\nparam r = 1\nunknown c = 2\nSe:u -> 1:s -> R:r\n1:s -> 0:a\n"
                     "0:a -> C:c\n0:a -> De:y\n")  # fmt: skip
    assert _imported("check", str(model)) == {"lark"}


@pytest.mark.parametrize("name", ["absorber_stages", "dc_motor"])
def test_check_of_the_examples_needs_neither_sympy_nor_networkx(name):
    # subsystems, modulated sources, several unknowns: all checked on the parser's own
    # expression trees, with causality and structure in plain Python
    assert _imported("check", "--json", str(ROOT / "models" / f"{name}.bg")) == {"lark"}
