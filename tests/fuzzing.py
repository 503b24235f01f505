"""Random and mutated model text, and what the `mtt` commands make of it (issue 12, item 7).

`random_model(rng)` writes a model as an attacker or a careless user might: odd names,
hostile numbers, deep expressions, components of every type (and of none), signals,
subsystems (with a part file, a missing one, one outside the directory), `input` and
`output` statements right or wrong, comments, descriptions, CRLF, a byte order mark, and
program text that must never run. `mutated(rng, text)` damages a model's text a few
characters or lines at a time. `run(files, directory)` runs the commands a user runs on the
result, in this process, and tells how each ended: every outcome must be a result or an
`MttError` (exit 2), never an internal error (exit 3), within `HANG` seconds of processor
time (what else runs on the machine does not count), with no
marker file created by text from the model. Used by tests/test_fuzz.py (a fixed budget)
and tests/fuzz_campaign.py (as many as you like).
"""

from __future__ import annotations

import contextlib
import importlib.util
import io
import json
import os
import random
import signal
import time
from dataclasses import dataclass
from pathlib import Path

from mtt.cli.main import main

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = sorted((ROOT / "models").glob("*.bg")) + sorted((ROOT / "tests" / "data").rglob("*.bg"))
HANG = 2.0  # processor seconds for all the commands on one model
MARKER = "pwned"  # a file that program text in a model would create if it ran

TYPES = ["Se", "Sf", "MSe", "MSf", "De", "Df", "R", "C", "I", "TF", "GY", "0", "1", "SS", "Q", "r"]
NAMES = ["k", "r", "c", "l", "q", "x", "n", "m", "N", "t", "u", "y", "e", "f", "s", "pi", "a1"]
ODD_NAMES = ["lambda", "class", "__import__", "numpy", "sys", "_", "sqrt", "k0", "S0", "C", "theta"]
NUMBERS = ["0", "1", "2", "0.5", ".25", "5.", "1e-3", "1.5E+2", "10", "3", "0.1", "7"]
HOSTILE_NUMBERS = [
    "1e999999999", "1e-999999999", "9" * 4500, "1e3999", "1e4001", "0.0", "1e400", "1e-400",
    "10^400", "2^2^2^2^2", "1_0", "0x10", "1e", "nan", "inf", "1e99999999999999999999",
]  # fmt: skip
FUNCTIONS = ["sqrt", "exp", "log", "sin", "cos", "tan", "eval", "e", "f", "exp"]
PAYLOADS = [
    '__import__("os").system("touch {marker}")',
    "exec(open('{marker}','w'))",
    "().__class__.__bases__[0]",
    "lambda: 1",
    '"{marker}"',
    "eval('1')",
]
JUNK = [
    "->", "(", ")", "^", "**", "-", "+", "*", "/", ":", ".", ",", "=", "#", '"', "e(", "f(",
    "sqrt(", "pi", "\ufeff", "\t", "\r", "\x00", "\u2028", "é", "1e9999", "model", "param",
    "unknown", "input", "output", "subsystem", "SS:", "MSf:", "TF:", "0:", "1:", " ", "\n",
]  # fmt: skip
COMMANDS = [
    ["check", "--json"],
    ["show"],
    ["causality", "--json"],
    ["ss"],
    ["tf", "--json"],
    ["theta", "--latex"],
    ["compile", "--json"],
]
# what the campaign runs besides: every parameter symbolic, values set on the command line
MORE_COMMANDS = [
    ["tf", "--symbolic"],
    ["theta", "--keep", "p,q", "--set", "w=sqrt(2)"],
    ["ss", "--set", "p=1e300", "--unknown", "q"],
]


def _name(rng: random.Random, pool: list[str], odd: float = 0.05) -> str:
    return rng.choice(ODD_NAMES) if rng.random() < odd else rng.choice(pool)


def expression(
    rng: random.Random, names: list[str], depth: int = 3, signals=(), hostile: float = 0.05
) -> str:
    """A random expression over `names` (and signals of `signals`, for MSe/MSf); a leaf is
    a hostile number or program text with probability `hostile`."""
    roll = rng.random()
    if depth <= 0 or roll < 0.3:
        leaf = rng.random()
        if leaf < hostile * 0.7:
            return rng.choice(HOSTILE_NUMBERS)
        if leaf < hostile:
            return rng.choice(PAYLOADS).format(marker=MARKER)
        if leaf < 0.45:
            return rng.choice(NUMBERS)
        if signals and leaf < 0.65:
            return f"{rng.choice('ef')}({rng.choice(signals)})"
        return _name(rng, names, hostile) if names else rng.choice(NUMBERS)
    inner = lambda: expression(rng, names, depth - 1, signals, hostile)  # noqa: E731
    if roll < 0.6:
        return f"{inner()} {rng.choice(['+', '-', '*', '/', '^', '**'])} {inner()}"
    if roll < 0.7:
        return f"-{inner()}"
    if roll < 0.8:
        return f"({inner()})"
    if roll < 0.95 or rng.random() > hostile * 4:
        functions = FUNCTIONS if rng.random() < hostile * 4 else FUNCTIONS[:5]
        return f"{rng.choice(functions)}({inner()})"
    return rng.choice(["-" * 300 + "k", "(" * 60 + "1" + ")" * 60, "+".join(["k"] * 120)])


@dataclass
class Files:
    """A model file and the part files it may read, by name relative to the directory."""

    model: str
    parts: dict[str, str]


def random_model(rng: random.Random) -> Files:
    """A random model: one in four hostile (odd numbers, program text, unknown types and
    functions), the others mostly well formed, so that every stage gets its share."""
    hostile = 0.15 if rng.random() < 0.25 else 0.0
    names = rng.sample(NAMES if hostile else NAMES[:12] + NAMES[16:], rng.randint(1, 6))
    types = TYPES if hostile else TYPES[:13]
    lines: list[str] = []
    if not hostile or rng.random() < 0.8:
        descriptions = ["", ' "a model"', ' "é ü"', ' "#"'] + (
            ['"quote \\" inside"'] if hostile else []
        )
        description = rng.choice(descriptions)
        lines.append(
            f"model {_name(rng, ['m', 'rc', 'drive', 'numpy', 'model', 'x1'])}{description}"
        )
    for name in names:
        keyword = "unknown" if rng.random() < 0.3 else "param"
        value = (
            f" = {expression(rng, names, rng.randint(0, 3), hostile=hostile)}"
            if rng.random() < 0.75
            else ""
        )
        lines.append(f"{keyword} {name}{value}")
    junctions = [f"{rng.choice('01')}:j{i}" for i in range(rng.randint(1, 5))]
    for a, b in zip(junctions, junctions[1:], strict=False):
        lines.append(
            f"{a} -> {b}"
            if rng.random() < 0.8
            else f"{a} -> {rng.choice(['TF', 'GY'])}:t{a[2:]}({expression(rng, names, 1)}) -> {b}"
        )
    components = []
    for i in range(rng.randint(1, 7)):
        kind = rng.choice(types)
        plain = f"{'j' if kind in '01' else kind.lower()}{i}"
        name = plain if not hostile or rng.random() < 0.8 else rng.choice(["j0", "x", "pi", "a.b"])
        components.append(name)
        argument = ""
        if kind in ("MSe", "MSf") or rng.random() < 0.6:
            signals = [c for c in components if c != name] + [j[2:] for j in junctions]
            modulated = kind in ("MSe", "MSf")
            argument = f"({expression(rng, names, 2, signals if modulated else (), hostile)})"
        junction = rng.choice(junctions)
        inward = kind in ("R", "C", "I", "De", "Df") or rng.random() < 0.3
        bond = (
            f"{junction} -> {kind}:{name}{argument}"
            if inward
            else f"{kind}:{name}{argument} -> {junction}"
        )
        lines.append(bond if rng.random() < 0.95 else f"{kind}:{name}{argument}")
    lines.append(f"Se:source -> {rng.choice(junctions)}")
    lines.append(f"{rng.choice(junctions)} -> {rng.choice(['De', 'Df'])}:sensor")
    if rng.random() < 0.3:
        lines.append(
            f"input {rng.choice(['Se:source', f'{rng.choice(types)}:{rng.choice(components)}'])}"
        )
    if rng.random() < 0.3:
        lines.append(f"output {rng.choice(types)}:{rng.choice(components + ['sensor'])}")
    parts: dict[str, str] = {}
    if rng.random() < 0.15:
        file = rng.choice(
            [
                "part.bg",
                "part.bg",
                "missing.bg",
                "/etc/passwd",
                "../part.bg",
                "part.txt",
                "model.bg",
            ]
        )
        binding = rng.choice(
            ["", f" (r = {expression(rng, names, 1, hostile=hostile)})", " (zz = 1)"]
        )
        lines.append(f'subsystem sub = "{file}"{binding}')
        lines.append(f"{rng.choice(junctions)} -> sub.{rng.choice(['p', 'q', 'v'])}")
        parts["part.bg"] = "model part\nparam r = 2\nSS:p -> 1:a\n1:a -> R:r\n1:a -> C:c(1)\n"
    head = 1 if lines and lines[0].startswith("model") else 0
    body = lines[head:]
    rng.shuffle(body)
    lines[head:] = body
    if rng.random() < 0.1:
        lines.insert(rng.randint(0, len(lines)), "# " + rng.choice(PAYLOADS).format(marker=MARKER))
    text = "\n".join(lines) + rng.choice(["\n", "", "\n\n"])
    if rng.random() < 0.05:
        text = text.replace("\n", "\r\n")
    if rng.random() < 0.05:
        text = "\ufeff" + text
    return Files(text, parts)


def valid_model(rng: random.Random, expressions: bool = False) -> str:
    """A well-formed model (it may still be causally conflicting or singular): junctions,
    two-ports, one source, one sensor and one-ports whose values hold the unknown k, other
    parameters and irrational constants; sometimes a modulated source. With `expressions`,
    the parameters' values and the arguments are random expressions (each value naming only
    parameters declared before it), some parameters have no value, and there may be a
    second unknown."""
    values = ["p", "k", "1/k", "k*p + 1", "2*q", "sqrt(2)", "pi/3", "k/sqrt(3) + 1", "log(3)*k"]
    params = ["param p = 2", "param q = 3/2", "unknown k = 3"]
    if expressions:
        names = ["k"]
        for name in ("p", "q", "w", "z"):
            roll = rng.random()
            value = "" if roll < 0.2 else f" = {expression(rng, names, rng.randint(0, 3), (), 0)}"
            params.append(f"{'unknown' if roll > 0.9 else 'param'} {name}{value}")
            names.append(name)
        params = ["unknown k = 3", *params[3:]]
        values = [expression(rng, names, rng.randint(0, 3), (), 0) for _ in range(8)]
    junctions = [f"{rng.choice('01')}:j{i}" for i in range(rng.randint(2, 5))]
    lines = ["model valid", *params]
    lines += [f"{a} -> {b}" for a, b in zip(junctions, junctions[1:], strict=False)]
    for i in range(rng.randint(0, 2)):
        a, b = rng.sample(junctions, 2)
        lines.append(f"{a} -> {rng.choice(['TF', 'GY'])}:t{i}({rng.choice(values)}) -> {b}")
    lines.append(f"{rng.choice(['Se', 'Sf'])}:u -> {rng.choice(junctions)}")
    lines.append(f"{rng.choice(junctions)} -> {rng.choice(['De', 'Df'])}:y")
    for i in range(rng.randint(1, 5)):
        lines.append(f"{rng.choice(junctions)} -> {rng.choice('RCI')}:e{i}({rng.choice(values)})")
    if rng.random() < 0.3:
        junction = rng.choice(junctions)
        kind, signal = ("MSf", "e") if junction[0] == "0" else ("MSe", "f")
        lines.append(
            f"{kind}:m(({rng.choice(values)})*{signal}({junction[2:]})) -> {rng.choice(junctions)}"
        )
    return "\n".join(lines) + "\n"


def mutated(rng: random.Random, text: str) -> str:
    """`text` damaged by one to four edits: characters or tokens inserted, deleted or
    replaced, lines repeated, dropped or swapped, numbers made hostile."""
    for _ in range(rng.randint(1, 4)):
        roll = rng.random()
        at = rng.randint(0, len(text))
        lines = text.split("\n")
        if roll < 0.25:
            text = text[:at] + rng.choice(JUNK) + text[at:]
        elif roll < 0.4:
            text = text[:at] + text[at + rng.randint(1, 8) :]
        elif roll < 0.5 and len(lines) > 1:
            i = rng.randrange(len(lines))
            lines.insert(rng.randrange(len(lines)), lines[i])
            text = "\n".join(lines)
        elif roll < 0.6 and len(lines) > 1:
            del lines[rng.randrange(len(lines))]
            text = "\n".join(lines)
        elif roll < 0.7 and len(lines) > 1:
            i, j = rng.randrange(len(lines)), rng.randrange(len(lines))
            lines[i], lines[j] = lines[j], lines[i]
            text = "\n".join(lines)
        elif roll < 0.85:
            digits = [i for i, ch in enumerate(text) if ch.isdigit()]
            if digits:
                i = rng.choice(digits)
                text = text[:i] + rng.choice(HOSTILE_NUMBERS + NUMBERS) + text[i + 1 :]
        else:
            names = rng.sample(NAMES, 3)
            text = text[:at] + expression(rng, names, 3) + text[at:]
    return text


def example(rng: random.Random) -> Files:
    """A shipped or test model, mutated (keeping the part files it reads)."""
    path = rng.choice(EXAMPLES)
    parts = {
        str(p.relative_to(path.parent)): p.read_text(encoding="utf-8")
        for p in path.parent.rglob("*.bg")
        if p != path and len(p.relative_to(path.parent).parts) <= 2
    }
    return Files(mutated(rng, path.read_text(encoding="utf-8")), parts)


class Hang(Exception):
    """The commands used more than 4 `HANG` seconds of processor time."""


@dataclass(frozen=True)
class Outcome:
    """How each command ended: its exit status, and its messages when it was a bug."""

    statuses: tuple[int, ...]
    seconds: float
    bugs: tuple[str, ...]  # stderr of each command that ended in an internal error
    executed: bool  # a marker file appeared: text from the model ran
    kinds: tuple[str, ...] = ()  # the kinds of error the first command (check) reported

    @property
    def ok(self) -> bool:
        return not self.bugs and not self.executed and self.seconds <= HANG


def _raise_hang(signum, frame):
    raise Hang


def run(files: Files, directory: Path, commands=COMMANDS) -> Outcome:
    """Run `commands` on the model (written with its parts into `directory`, which must be
    empty), each as `mtt COMMAND FILE` in this process; a hang raises `Hang`."""
    for name, text in files.parts.items():
        (directory / name).parent.mkdir(parents=True, exist_ok=True)
        (directory / name).write_text(text, encoding="utf-8")
    model = directory / "model.bg"
    model.write_bytes(files.model.encode("utf-8", "surrogatepass"))
    statuses, bugs, kinds = [], [], ()
    # a hang guard in processor seconds (a loaded machine stretches the wall clock, not
    # these); slowness beyond HANG is measured, and reported by tests/fuzz_campaign.py
    previous = signal.signal(signal.SIGPROF, _raise_hang)
    signal.setitimer(signal.ITIMER_PROF, HANG * 4)
    start, cwd = time.process_time(), os.getcwd()
    os.environ["MTT_DEBUG"] = "1"  # an internal error's traceback, to report
    try:
        os.chdir(directory)  # a payload that ran would create the marker here
        for command in commands:
            argv = [command[0], str(model), *command[1:]]
            if command[0] == "compile":
                argv += ["-o", str(directory / "out.py")]
            out, err = io.StringIO(), io.StringIO()
            with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
                status = main(argv)
            statuses.append(status)
            if command == ["check", "--json"] and out.getvalue().strip():
                (record,) = json.loads(out.getvalue().splitlines()[0])["files"]
                kinds = tuple(sorted({e["kind"] for e in record["errors"]}))
            if status not in (0, 2):
                bugs.append(f"mtt {' '.join(command)}: {err.getvalue()}")
        if (directory / "out.py").exists():  # the generated estimator runs: import it
            spec = importlib.util.spec_from_file_location("fuzzed_estimator", directory / "out.py")
            spec.loader.exec_module(importlib.util.module_from_spec(spec))
    finally:
        signal.setitimer(signal.ITIMER_PROF, 0)
        signal.signal(signal.SIGPROF, previous)
        os.environ.pop("MTT_DEBUG", None)
        os.chdir(cwd)
    seconds = time.process_time() - start
    executed = (directory / MARKER).exists() or (ROOT / MARKER).exists()
    return Outcome(tuple(statuses), seconds, tuple(bugs), executed, kinds)
