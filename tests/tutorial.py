"""Run docs/tutorial.md as a reader would, and write it as a Jupyter notebook.

The tutorial's fenced blocks that run, in the order they appear, in one directory:

    ```bg file=NAME     the block is written to the file NAME
    ```console          `$ COMMAND` lines (a trailing backslash continues one), each followed
                        by what it prints (stdout and stderr, as a terminal shows them);
                        `# exit status N` after a command: the status it ends with (else 0)
    ```python           code, run in one namespace shared by all the Python blocks
    ```output           what the Python block just above prints, then the warnings it
                        issues (`Category: message`, one a line: a notebook shows them;
                        not those Python hides by default, such as DeprecationWarning)

`mtt COMMAND ...` runs in this process (the command line's `main`, as the fuzz tests run it:
the libraries are imported once), `python ...` in a child process with this interpreter.
Expected output matches actual output when the text is the same up to whitespace, `...`
standing for anything, and each number is within one unit of its last printed digit (an
integer, exactly): a figure computed from a seeded simulation may differ in its last bits
from one platform to another, never by more.

From the command line (the project's root as the working directory):

    python tests/tutorial.py              run it in a temporary directory, report differences
    python tests/tutorial.py --show       print what every step prints
    python tests/tutorial.py --images     also copy the figures it writes to docs/images/tutorial/
    python tests/tutorial.py --notebook   write docs/tutorial.ipynb (needs nbformat)
"""

from __future__ import annotations

import argparse
import contextlib
import io
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import warnings
from collections.abc import Iterator
from dataclasses import dataclass
from decimal import Decimal
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
TUTORIAL = ROOT / "docs" / "tutorial.md"
NOTEBOOK = ROOT / "docs" / "tutorial.ipynb"
IMAGES = "images/tutorial/"  # figures the tutorial shows, relative to docs/

FENCE = re.compile(r"^```(?P<info>[^\n`]*)\n(?P<body>.*?)^```[ \t]*$", re.M | re.S)
NUMBER = r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?"
STATUS = re.compile(r"\s+# exit status (\d+)$")
# The warnings Python hides by default; a notebook shows every other one, and so does `run`.
HIDDEN = (DeprecationWarning, PendingDeprecationWarning, ImportWarning, ResourceWarning)


@dataclass(frozen=True)
class Step:
    """One thing the tutorial does: write a file, run a command or run Python code."""

    kind: str  # "file", "command" or "python"
    line: int  # where it starts in the tutorial (1-based)
    text: str  # the file's text, the command line, or the code
    expected: str | None = None  # what it prints (None: not shown, not checked)
    name: str = ""  # the file written (kind "file")
    status: int = 0  # the exit status a command ends with


@dataclass(frozen=True)
class Result:
    step: Step
    output: str
    status: int = 0

    @property
    def ok(self) -> bool:
        return self.status == self.step.status and (
            self.step.expected is None or matches(self.step.expected, self.output)
        )


@dataclass(frozen=True)
class Block:
    info: str  # the fence's info string: language, then attributes
    body: str
    line: int  # the line of the block's first line of text
    start: int  # offsets of the whole fenced block in the document
    end: int

    @property
    def language(self) -> str:
        return self.info.split()[0] if self.info.split() else ""

    def attribute(self, name: str) -> str | None:
        for word in self.info.split()[1:]:
            key, _, value = word.partition("=")
            if key == name:
                return value
        return None


def blocks(markdown: str) -> list[Block]:
    """The fenced code blocks of a Markdown document (fences at the start of a line)."""
    return [
        Block(
            info=found["info"].strip(),
            body=found["body"],
            line=markdown.count("\n", 0, found.start("body")) + 1,
            start=found.start(),
            end=found.end(),
        )
        for found in FENCE.finditer(markdown)
    ]


def _commands(block: Block) -> Iterator[Step]:
    """The `$ COMMAND` lines of a console block, each with the output that follows it."""
    lines = block.body.splitlines()
    index = 0
    while index < len(lines):
        if not lines[index].startswith("$ "):
            raise ValueError(f"tutorial line {block.line + index}: output before any command")
        first, command = index, lines[index][2:]
        while command.endswith("\\"):
            index += 1
            command = command[:-1].rstrip() + " " + lines[index].strip()
        index += 1
        output = []
        while index < len(lines) and not lines[index].startswith("$ "):
            output.append(lines[index])
            index += 1
        status = STATUS.search(command)
        yield Step(
            kind="command",
            line=block.line + first,
            text=STATUS.sub("", command).strip(),
            expected="\n".join(output),
            status=int(status[1]) if status else 0,
        )


def steps(markdown: str) -> list[Step]:
    """What the tutorial does, in order."""
    found: list[Step] = []
    for block in blocks(markdown):
        if block.language == "bg" and block.attribute("file"):
            name = block.attribute("file")
            found.append(Step("file", block.line, block.body, name=name))
        elif block.language == "console":
            found.extend(_commands(block))
        elif block.language == "python":
            found.append(Step("python", block.line, block.body))
        elif block.language == "output":
            if not found or found[-1].kind != "python" or found[-1].expected is not None:
                raise ValueError(f"tutorial line {block.line}: output after no Python block")
            last = found.pop()
            found.append(Step("python", last.line, last.text, expected=block.body))
    return found


def _pattern(expected: str) -> re.Pattern:
    """A regular expression for text that looks like `expected` (numbers as groups)."""
    parts = []
    for token in re.finditer(rf"(?P<number>{NUMBER})|(?P<space>\s+)|(?P<dots>\.\.\.)|.", expected):
        if token["number"]:
            parts.append(f"({NUMBER})")
        elif token["space"]:
            parts.append(r"\s+")
        elif token["dots"]:
            parts.append(r"[\s\S]*?")
        else:
            parts.append(re.escape(token[0]))
    return re.compile("".join(parts))


def _close(expected: str, actual: str) -> bool:
    """Within one unit of `expected`'s last printed digit; an integer exactly."""
    want, got = Decimal(expected), Decimal(actual)
    if re.fullmatch(r"[-+]?\d+", expected):
        return want == got
    unit = Decimal(1).scaleb(want.as_tuple().exponent)
    return abs(want - got) <= unit


def matches(expected: str, actual: str) -> bool:
    """Whether `actual` reads as `expected` (see the module's docstring)."""
    found = _pattern(expected.strip()).fullmatch(actual.strip())
    numbers = re.findall(NUMBER, expected.strip())
    return found is not None and all(map(_close, numbers, found.groups()))


def _run_mtt(argv: list[str]) -> tuple[str, int]:
    from mtt.cli.main import main

    captured = io.StringIO()
    with contextlib.redirect_stdout(captured), contextlib.redirect_stderr(captured):
        status = main(argv)
    return captured.getvalue(), status


def _run_command(step: Step) -> tuple[str, int]:
    argv = shlex.split(step.text)
    if argv[0] == "mtt":
        return _run_mtt(argv[1:])
    if argv[0] == "python":
        done = subprocess.run(
            [sys.executable, *argv[1:]], capture_output=True, text=True, timeout=120
        )
        return done.stdout + done.stderr, done.returncode
    raise ValueError(f"tutorial line {step.line}: only mtt and python commands run: {step.text}")


def _run_python(step: Step, namespace: dict) -> str:
    code = compile("\n" * (step.line - 1) + step.text, str(TUTORIAL), "exec")
    captured = io.StringIO()
    with warnings.catch_warnings(record=True) as caught, contextlib.redirect_stdout(captured):
        warnings.simplefilter("always")
        exec(code, namespace)  # noqa: S102 - the tutorial's own code, as a reader runs it
    shown = [w for w in caught if not issubclass(w.category, HIDDEN)]
    return captured.getvalue() + "".join(f"{w.category.__name__}: {w.message}\n" for w in shown)


def run(markdown: str, directory: Path) -> list[Result]:
    """Do every step of the tutorial in `directory` (the working directory meanwhile)."""
    import matplotlib

    matplotlib.use("Agg")  # the Python blocks' figures are written to files
    import matplotlib.pyplot as plt

    results, namespace = [], {"__name__": "__tutorial__"}
    with contextlib.chdir(directory):
        try:
            for step in steps(markdown):
                if step.kind == "file":
                    Path(step.name).write_text(step.text, encoding="utf-8")
                    results.append(Result(step, ""))
                elif step.kind == "command":
                    output, status = _run_command(step)
                    results.append(Result(step, output, status))
                else:
                    results.append(Result(step, _run_python(step, namespace)))
        finally:
            plt.close("all")
    return results


def figures(markdown: str) -> list[str]:
    """The names of the figures the tutorial shows from docs/images/tutorial/."""
    return re.findall(rf"\]\({re.escape(IMAGES)}([\w.-]+)\)", markdown)


def report(result: Result) -> str:
    """What differs, for a person: the step, the status, the expected and actual text."""
    step = result.step
    lines = [f"{TUTORIAL.name}:{step.line}: {step.kind} {step.text.splitlines()[0]}"]
    if result.status != step.status:
        lines.append(f"  exit status {result.status}, expected {step.status}")
    if step.expected is not None and not matches(step.expected, result.output):
        lines += ["  expected:", *("    " + x for x in step.expected.strip().splitlines())]
        lines += ["  got:", *("    " + x for x in result.output.strip().splitlines())]
    return "\n".join(lines)


# The notebook runs `mtt` and `python` with its kernel's interpreter, wherever that is (a
# kernel's PATH need not have the venv's bin directory).
SHELL_SETUP = "import sys  # the commands below run mtt with this notebook's Python, sys.executable"


def shell_line(command: str) -> str:
    """A tutorial command as a notebook's shell line: `mtt ARGS` as `python -m mtt ARGS`,
    `python ARGS` with the kernel's interpreter."""
    command = STATUS.sub("", command)
    program, _, rest = command.partition(" ")
    prefix = {"mtt": "{sys.executable} -m mtt", "python": "{sys.executable}"}[program]
    return f"!{prefix} {rest}"


def notebook(markdown: str) -> str:
    """The tutorial as a Jupyter notebook: its prose as Markdown cells, each model file as a
    `%%writefile` cell, each command as a `!` line of its own cell, each Python block as
    code; the outputs are left to the notebook to make. Deterministic: cells are numbered."""
    import nbformat

    cells, position = [], 0

    def prose(text: str) -> None:
        if text.strip():
            cells.append(nbformat.v4.new_markdown_cell(text.strip()))

    for block in blocks(markdown):
        if block.language == "output":
            prose(markdown[position : block.start])
        elif block.language == "bg" and block.attribute("file"):
            prose(markdown[position : block.start])
            name = block.attribute("file")
            cells.append(nbformat.v4.new_code_cell(f"%%writefile {name}\n{block.body}".strip()))
        elif block.language == "console":
            prose(markdown[position : block.start])
            if not any(cell.source == SHELL_SETUP for cell in cells):
                cells.append(nbformat.v4.new_code_cell(SHELL_SETUP))
            for step in _commands(block):  # a cell each: its output is the command's
                cells.append(nbformat.v4.new_code_cell(shell_line(step.text)))
        elif block.language == "python":
            prose(markdown[position : block.start])
            cells.append(nbformat.v4.new_code_cell(block.body.strip()))
        else:
            continue
        position = block.end
    prose(markdown[position:])
    for number, cell in enumerate(cells, 1):
        cell["id"] = f"cell-{number}"
    book = nbformat.v4.new_notebook(
        cells=cells,
        metadata={
            "kernelspec": {"display_name": "Python 3", "language": "python", "name": "python3"},
            "language_info": {"name": "python"},
        },
    )
    nbformat.validate(book)
    return nbformat.writes(book) + "\n"


def execute(path: Path, directory: Path) -> list[tuple[str, str]]:
    """Run the notebook at `path` in `directory` with a fresh kernel of this interpreter
    (its own kernel spec: a machine's `python3` may be another Python), as Jupyter runs it;
    nbclient raises CellExecutionError at the first cell that fails. Each code cell's
    source and the text it printed."""
    import json
    import os

    import nbclient
    import nbformat

    book = nbformat.reads(path.read_text("utf-8"), as_version=4)
    spec = directory / ".jupyter" / "kernels" / "mtt-tutorial"
    spec.mkdir(parents=True)
    argv = [sys.executable, "-m", "ipykernel_launcher", "-f", "{connection_file}"]
    (spec / "kernel.json").write_text(json.dumps({"argv": argv, "language": "python",
                                                  "display_name": "mtt"}))  # fmt: skip
    previous = os.environ.get("JUPYTER_PATH")
    os.environ["JUPYTER_PATH"] = str(directory / ".jupyter")
    try:
        where = {"metadata": {"path": str(directory)}}
        client = nbclient.NotebookClient(
            book, timeout=300, kernel_name="mtt-tutorial", resources=where
        )
        client.execute()
    finally:
        if previous is None:
            del os.environ["JUPYTER_PATH"]
        else:
            os.environ["JUPYTER_PATH"] = previous
    return [
        (cell.source, "".join(o.get("text", "") for o in cell.outputs if o.output_type == "stream"))
        for cell in book.cells
        if cell.cell_type == "code"
    ]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--show", action="store_true", help="print what every step prints")
    parser.add_argument("--images", action="store_true", help="update docs/images/tutorial/")
    parser.add_argument("--notebook", action="store_true", help="write docs/tutorial.ipynb")
    args = parser.parse_args(argv)
    markdown = TUTORIAL.read_text("utf-8")
    if args.notebook:
        NOTEBOOK.write_text(notebook(markdown), encoding="utf-8")
        print(f"wrote {NOTEBOOK.relative_to(ROOT)}")
    with tempfile.TemporaryDirectory() as directory:
        results = run(markdown, Path(directory))
        if args.images:
            target = TUTORIAL.parent / IMAGES
            target.mkdir(parents=True, exist_ok=True)
            for name in figures(markdown):
                shutil.copyfile(Path(directory) / name, target / name)
                print(f"wrote {(target / name).relative_to(ROOT)}")
    for result in results:
        if args.show and result.step.kind != "file":
            print(f"--- {TUTORIAL.name}:{result.step.line}: {result.step.text.splitlines()[0]}")
            print(result.output, end="" if result.output.endswith("\n") else "\n")
        elif not result.ok:
            print(report(result))
    failed = sum(not result.ok for result in results)
    print(f"tutorial: {len(results) - failed} steps as shown, {failed} not")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
