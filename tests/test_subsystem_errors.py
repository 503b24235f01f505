"""Every error kind of language version 2, inside a subsystem file two levels down.

test_subsystems.py places the kinds at the top level or one level down (and a few two
levels down); here each new kind (a subsystem statement's own errors and the structural
ones found by `mtt check`) is provoked in bottom.bg, used by middle.bg, used by top.bg, and
`mtt check --json` must report it at bottom.bg's exact line and column, with both notes.
"""

from __future__ import annotations

import json
import os

import pytest

from mtt.cli.main import main

TOP = 'model top\nsubsystem mid = "middle.bg"\nSe:v -> mid.in\nmid.out -> De:y\n'
MIDDLE = 'model middle\nsubsystem b = "bottom.bg"\nSS:in -> b.in\nb.out -> SS:out\n'
BOTTOM = "model bottom\nSS:in -> 0:n\n0:n -> C:c(1)\n0:n -> SS:out\n"  # lines 1-4
LEAF = "model leaf\nSS:p -> C:c(1)\n"  # its bond points out of SS:p
NOTES = ["in subsystem mid.b (middle.bg:2)", "in subsystem mid (top.bg:2)"]


@pytest.mark.parametrize(
    ("lines", "options", "kind", "line", "column"),
    [
        # NAME.PORT naming no SS of the subsystem: at the use
        (['subsystem leaf = "leaf.bg"', "0:n -> leaf.p", "leaf.q -> 0:n"], [], "bad_port", 7, 1),
        # bonded out of a port whose own bond points out of its SS: at the parent's arrow
        (['subsystem leaf = "leaf.bg"', "leaf.p -> 0:n"], [], "port_direction", 6, 8),
        # a missing file: at the subsystem statement
        (['subsystem x = "missing.bg"'], [], "io", 5, 11),
        # a flow detector across the source that reaches 0:n through both ports
        (["0:n -> Df:short"], ["--output", "De:y"], "causal_conflict", 5, 8),
        # an output in an island of the bottom file: at the detector
        (["0:w -> De:island", "0:w -> C:c2(1)"], ["--output", "De:mid.b.island"],
         "unreachable_output", 5, 8),
        # an unknown only in an island: at its declaration
        (["unknown k = 2", "Sf:u -> 0:z", "0:z -> R:lost(k)"], ["--input", "Se:v"],
         "no_dependence", 5, 9),
    ],
    ids=["bad_port", "port_direction", "io", "causal_conflict", "unreachable_output",
         "no_dependence"],
)  # fmt: skip
def test_an_error_two_levels_down_is_placed_in_its_file(
    tmp_path, capsys, lines, options, kind, line, column
):
    files = {"top.bg": TOP, "middle.bg": MIDDLE, "leaf.bg": LEAF,
             "bottom.bg": BOTTOM + "".join(f"{text}\n" for text in lines)}  # fmt: skip
    for name, text in files.items():
        (tmp_path / name).write_text(text, encoding="utf-8")
    assert main(["check", "--json", str(tmp_path / "top.bg"), *options]) == 2
    (error,) = json.loads(capsys.readouterr().out)["files"][0]["errors"]
    prefix = str(tmp_path) + os.sep
    assert (error["file"], error["kind"], error["line"], error["column"]) == (
        str(tmp_path / "bottom.bg"),
        kind,
        line,
        column,
    )
    assert [note.replace(prefix, "") for note in error["notes"]] == NOTES
