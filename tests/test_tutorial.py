"""docs/tutorial.md runs end to end and prints what it shows; its notebook and figures are
the ones it makes (tests/tutorial.py is the runner)."""

from __future__ import annotations

import pytest
import tutorial
from tutorial import (
    NOTEBOOK,
    TUTORIAL,
    execute,
    figures,
    matches,
    notebook,
    report,
    run,
    shell_line,
    steps,
)

MARKDOWN = TUTORIAL.read_text("utf-8")


def test_the_tutorial_prints_what_it_shows(tmp_path):
    results = run(MARKDOWN, tmp_path)
    kinds = [result.step.kind for result in results]
    assert kinds.count("command") >= 12 and kinds.count("python") >= 5
    assert all(result.step.expected is not None for result in results if result.step.kind != "file")
    differences = [report(result) for result in results if not result.ok]
    assert not differences, "\n".join(differences)
    shown = figures(MARKDOWN)
    assert {"msd.svg", "fit.png", "estimate.png"} <= set(shown)
    for name in shown:  # every figure the page shows is committed, and the tutorial makes it
        assert (tmp_path / name).stat().st_size > 1000
        assert (TUTORIAL.parent / tutorial.IMAGES / name).is_file()


def test_the_notebook_is_made_from_the_tutorial():
    pytest.importorskip("nbformat", reason="the notebook's format (pip install '.[test]')")
    assert NOTEBOOK.read_text("utf-8") == notebook(MARKDOWN), "python tests/tutorial.py --notebook"


def test_the_notebook_runs_anywhere_and_its_commands_print_what_the_tutorial_shows(
    tmp_path, monkeypatch
):
    """Executed as a reader's Jupyter would (nbclient, a fresh kernel) with no venv on PATH:
    any cell that raises fails it, and each command prints what the tutorial shows."""
    pytest.importorskip("nbclient", reason="runs the notebook (pip install -e '.[test]')")
    monkeypatch.setenv("PATH", "/usr/bin:/bin")  # `mtt` is not on it: the notebook must not need it
    cells = dict(execute(NOTEBOOK, tmp_path))
    commands = [step for step in steps(MARKDOWN) if step.kind == "command"]
    printed = {step: next(out for src, out in cells.items() if src.endswith(shell_line(step.text)))
               for step in commands}  # fmt: skip
    differences = [
        f"{TUTORIAL.name}:{step.line}: {step.text}\n  expected:\n{step.expected}\n  got:\n{out}"
        for step, out in printed.items()
        if not matches(step.expected, out)
    ]
    assert not differences, "\n".join(differences)
    for name in figures(MARKDOWN):
        assert (tmp_path / name).stat().st_size > 1000


@pytest.mark.parametrize(
    ("expected", "actual", "same"),
    [
        ("mass = 2.59302 ± 0.00643", "mass = 2.59303 ± 0.00643", True),  # the last digit's unit
        ("mass = 2.59302 ± 0.00643", "mass = 2.59304 ± 0.00643", False),
        ("801 samples", "801  samples\n", True),
        ("801 samples", "802 samples", False),  # integers exactly
        ("fit 70.05 %", "fit 70.05 per cent", False),
        ("wrote ...: bond graph", "wrote msd.svg: bond graph", True),
        ("[0.3864, 0.0]", "[0.3864, 1e-17]", True),
        ("k = 1e-05", "k = 3e-05", False),
        ("ok", "ok\nand more", False),
    ],
)
def test_outputs_match_to_their_printed_precision(expected, actual, same):
    assert matches(expected, actual) is same


def test_a_changed_output_or_exit_status_is_reported(tmp_path):
    markdown = (
        "```bg file=typo.bg\nmodel m\nSe:v -> 1:j -> R:r\n1:j -> Df:i\n```\n"
        "```console\n$ mtt check typo.bg\ntypo.bg: ok\n```\n"
        "```python\nprint(6 * 7)\n```\n```output\n41\n```\n"
        "```python\nimport numpy\nnumpy.log(0.0)\n```\n"
    )
    results = [result for result in run(markdown, tmp_path) if result.step.kind != "file"]
    check, python, warning = results
    assert check.status == 2 and not check.ok
    assert "error[undeclared_parameter]" in report(check)
    assert python.output == "42\n" and not python.ok
    assert warning.output == "RuntimeWarning: divide by zero encountered in log\n"
    assert [step.kind for step in steps(markdown)] == ["file", "command", "python", "python"]
