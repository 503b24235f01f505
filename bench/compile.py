"""Time each stage of the compiler on the paper's models and on RC ladders of growing size.

Run: .venv/bin/python bench/compile.py [--sizes 5 10 20 40] [--repeat 3]

Prints, per model, the best wall time of each stage (text -> parse tree -> bond graph ->
causal bond graph -> equations -> transfer function -> Theta), the targets of issue 3,
and, as the in-process baseline, the transfer stage done the generic way
(sympy Matrix inverse and cancel) for the sizes where that finishes in reasonable time.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import sympy

from mtt.derivation.causality import assign
from mtt.derivation.equations import derive
from mtt.derivation.parameters import ParameterChoice, parametrise
from mtt.derivation.pipeline import read_source
from mtt.derivation.theta import theta_matrix
from mtt.derivation.transfer import LAPLACE, transfer_function
from mtt.language.bondgraph import build
from mtt.language.parse import parse

ROOT = Path(__file__).resolve().parent.parent
TARGETS = {"dc_drive": 0.5, "absorber": 0.5, "ladder20": 2.0}
NAIVE_MAX_STATES = 10


def ladder(stages: int) -> str:
    """An RC ladder: a voltage source, `stages` series R / shunt C sections, the last C unknown."""
    lines = [f"model ladder{stages}", "param r = 1", "param c = 1/2", "unknown k = 2", ""]
    lines.append("Se:v -> 1:s1")
    for i in range(1, stages + 1):
        capacitor = f"C:c{i}(k)" if i == stages else f"C:c{i}(c)"
        lines += [f"1:s{i} -> R:r{i}(r)", f"1:s{i} -> 0:n{i}", f"0:n{i} -> {capacitor}"]
        if i < stages:
            lines.append(f"0:n{i} -> 1:s{i + 1}")
    lines.append(f"0:n{stages} -> De:out")
    return "\n".join(lines) + "\n"


def best(function, repeat: int):
    times, result = [], None
    for _ in range(repeat):
        start = time.perf_counter()
        result = function()
        times.append(time.perf_counter() - start)
    return min(times), result


def stages(path: Path, choice: ParameterChoice, repeat: int) -> dict[str, float]:
    timings = {}
    timings["read+parse"], parsed = best(lambda: parse(read_source(path)), repeat)
    timings["bond graph"], graph = best(lambda: build(parsed), repeat)
    timings["causality"], causal = best(lambda: assign(graph), repeat)
    timings["equations"], equations = best(
        lambda: derive(causal, parametrise(graph, choice)), repeat
    )
    timings["transfer"], tf = best(lambda: transfer_function(equations), repeat)
    timings["theta"], _ = best(lambda: theta_matrix(tf), repeat)
    timings["total"] = sum(timings.values())
    if len(equations.states) <= NAIVE_MAX_STATES:
        timings["naive transfer"], _ = best(lambda: naive_transfer(equations), 1)
    return timings


def naive_transfer(equations) -> sympy.Expr:
    """The textbook way: invert sE - A as a sympy Matrix, then cancel."""
    m = equations.matrices()
    G = m["C"] * (LAPLACE * m["E"] - m["A"]).inv() * m["B"] + m["D"]
    return sympy.cancel(sympy.together(G[0, 0]))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[5, 10, 20, 40])
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()

    cases = [
        ("dc_drive", ROOT / "models" / "dc_drive.bg", ParameterChoice()),
        ("absorber", ROOT / "models" / "absorber.bg", ParameterChoice()),
        ("absorber --keep tau,l", ROOT / "models" / "absorber.bg",
         ParameterChoice(keep=frozenset({"tau", "l"}))),
    ]  # fmt: skip
    with tempfile.TemporaryDirectory() as tmp:
        for size in args.sizes:
            path = Path(tmp) / f"ladder{size}.bg"
            path.write_text(ladder(size), encoding="utf-8")
            cases.append((f"ladder{size}", path, ParameterChoice()))
        results = {name: stages(path, choice, args.repeat) for name, path, choice in cases}

    columns = ["read+parse", "bond graph", "causality", "equations", "transfer", "theta",
               "total", "naive transfer"]  # fmt: skip
    print(f"{'model':<24}" + "".join(f"{c:>16}" for c in columns) + f"{'target':>10}")
    for name, timings in results.items():
        cells = "".join(
            f"{timings[c] * 1e3:>13.1f} ms" if c in timings else f"{'-':>16}" for c in columns
        )
        target = TARGETS.get(name)
        verdict = "" if target is None else ("ok" if timings["total"] < target else "MISSED")
        print(f"{name:<24}{cells}{verdict:>10}")

    print("\nspeed-up of the transfer stage over the naive sympy Matrix inverse + cancel:")
    for name, timings in results.items():
        if "naive transfer" in timings:
            ratio = timings["naive transfer"] / timings["transfer"]
            print(f"  {name:<24} {ratio:8.1f}x")

    ladders = [n for n in results if n.startswith("ladder")]
    if len(ladders) > 1:
        first = results[ladders[0]]["total"]
        print(f"\ngrowth of the total time relative to {ladders[0]}:")
        for name in ladders:
            print(f"  {name:<12} {results[name]['total'] / first:8.1f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
