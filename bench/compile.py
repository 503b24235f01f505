"""Time each stage of the compiler on the paper's models and on RC ladders of growing size.

Run: .venv/bin/python bench/compile.py [--sizes 5 10 20 40] [--stages 10 20 40 80 160]
                                       [--baseline-max 40] [--repeat 3]

Prints, per model, the best wall time of each stage (text -> parse tree -> bond graph ->
causal bond graph -> equations -> transfer function -> Theta), their total, and the total
of the first runs (caches cold, as in a fresh `mtt` process: the targets of issues 3 and
10 are checked on it). The ladders come two ways: written out in one file (--sizes), and
assembled from one section file used as a subsystem (--stages). Baselines, in this
process: the transfer stage done the textbook way (sympy Matrix inverse and cancel) for
small models, and by fraction-free elimination over the polynomials (the transfer stage
before it evaluated and interpolated the determinants) for the assembled ladders up to
--baseline-max sections. Then the growth exponent of the total time with the number of
sections (the slope of log time against log size).
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from pathlib import Path

import sympy

from mtt.derivation import determinants
from mtt.derivation.causality import assign
from mtt.derivation.equations import derive
from mtt.derivation.parameters import ParameterChoice, parametrise
from mtt.derivation.pipeline import read_source
from mtt.derivation.theta import theta_matrix
from mtt.derivation.transfer import LAPLACE, transfer_function
from mtt.language.bondgraph import build
from mtt.language.parse import parse

ROOT = Path(__file__).resolve().parent.parent
TARGETS = {"dc_drive": 0.5, "absorber": 0.5, "ladder20": 2.0, "stages80": 3.0}
NAIVE_MAX_STATES = 10
COLUMNS = ["read+parse", "bond graph", "causality", "equations", "transfer", "theta", "total",
           "first run"]  # fmt: skip

SECTION = """model section "one RC section of a ladder: series R, shunt C"
param r = 1
param c = 1/2
SS:in -> 1:s
1:s -> R:r
1:s -> 0:n
0:n -> C:c
0:n -> SS:out
"""


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


def assembled_ladder(stages: int) -> str:
    """The same ladder from `section.bg` used `stages` times, the last capacitance set to k."""
    lines = [f"model stages{stages}", "unknown k = 2"]
    for i in range(1, stages + 1):
        lines.append(f'subsystem s{i} = "section.bg"' + (" (c = k)" if i == stages else ""))
    lines.append("Se:v -> s1.in")
    lines += [f"s{i}.out -> s{i + 1}.in" for i in range(1, stages)]
    lines.append(f"s{stages}.out -> De:out")
    return "\n".join(lines) + "\n"


FIRST: dict[str, float] = {}  # each stage's first run (caches cold), for the current model


def best(function, repeat: int, stage: str | None = None):
    times, result = [], None
    for _ in range(repeat):
        start = time.perf_counter()
        result = function()
        times.append(time.perf_counter() - start)
    if stage:
        FIRST[stage] = times[0]
    return min(times), result


def stages(path: Path, choice: ParameterChoice, repeat: int) -> tuple[dict[str, float], object]:
    timings = {}
    timings["read+parse"], parsed = best(lambda: parse(read_source(path)), repeat, "a")
    timings["bond graph"], graph = best(lambda: build(parsed), repeat, "b")
    timings["causality"], causal = best(lambda: assign(graph), repeat, "c")
    timings["equations"], equations = best(
        lambda: derive(causal, parametrise(graph, choice)), repeat, "d"
    )
    timings["transfer"], tf = best(lambda: transfer_function(equations), repeat, "e")
    timings["theta"], _ = best(lambda: theta_matrix(tf), repeat, "f")
    timings["total"] = sum(timings.values())
    timings["first run"] = sum(FIRST.values())
    return timings, equations


def naive_transfer(equations) -> sympy.Expr:
    """The textbook way: invert sE - A as a sympy Matrix, then cancel."""
    m = equations.matrices()
    G = m["C"] * (LAPLACE * m["E"] - m["A"]).inv() * m["B"] + m["D"]
    return sympy.cancel(sympy.together(G[0, 0]))


def eliminated_transfer(equations):
    """The transfer stage without evaluation: the fraction-free solve over the polynomials."""
    keep, determinants.MAX_POINTS = determinants.MAX_POINTS, 0
    try:
        return transfer_function(equations)
    finally:
        determinants.MAX_POINTS = keep


def table(results: dict[str, dict[str, float]], extra: list[str]) -> None:
    columns = COLUMNS + extra
    print(f"{'model':<24}" + "".join(f"{c:>14}" for c in columns) + f"{'target':>10}")
    for name, timings in results.items():
        cells = "".join(
            f"{timings[c] * 1e3:>11.1f} ms" if c in timings else f"{'-':>14}" for c in columns
        )
        target = TARGETS.get(name)
        verdict = "" if target is None else ("ok" if timings["first run"] < target else "MISSED")
        print(f"{name:<24}{cells}{verdict:>10}")


def growth(results: dict[str, dict[str, float]], sizes: list[int], label: str) -> None:
    """Slopes of log(total time) against log(sections), pairwise and fitted."""
    names = [f"{label}{n}" for n in sizes]
    print(f"\ngrowth of the total time with the number of sections ({label}N):")
    for (a, na), (b, nb) in zip(zip(sizes, names), zip(sizes[1:], names[1:])):  # noqa: B905
        ratio = results[nb]["total"] / results[na]["total"]
        print(
            f"  {a:>4} -> {b:<4} {ratio:6.2f}x   exponent {math.log(ratio) / math.log(b / a):5.2f}"
        )
    if len(sizes) > 2:
        xs = [math.log(n) for n in sizes]
        ys = [math.log(results[n]["total"]) for n in names]
        mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
        slope = sum((x - mx) * (y - my) for x, y in zip(xs, ys, strict=True)) / sum(
            (x - mx) ** 2 for x in xs
        )
        print(f"  fitted over {sizes[0]}..{sizes[-1]}: time ~ N^{slope:.2f}")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[5, 10, 20, 40])
    parser.add_argument("--stages", type=int, nargs="+", default=[10, 20, 40, 80, 160])
    parser.add_argument("--baseline-max", type=int, default=40)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()

    cases = [
        ("dc_drive", ROOT / "models" / "dc_drive.bg", ParameterChoice()),
        ("absorber", ROOT / "models" / "absorber.bg", ParameterChoice()),
        ("absorber --keep tau,l", ROOT / "models" / "absorber.bg",
         ParameterChoice(keep=frozenset({"tau", "l"}))),
    ]  # fmt: skip
    results, equations = {}, {}
    with tempfile.TemporaryDirectory() as tmp:
        (Path(tmp) / "section.bg").write_text(SECTION, encoding="utf-8")
        for size in args.sizes:
            path = Path(tmp) / f"ladder{size}.bg"
            path.write_text(ladder(size), encoding="utf-8")
            cases.append((f"ladder{size}", path, ParameterChoice()))
        for size in args.stages:
            path = Path(tmp) / f"stages{size}.bg"
            path.write_text(assembled_ladder(size), encoding="utf-8")
            cases.append((f"stages{size}", path, ParameterChoice()))
        for name, path, choice in cases:
            results[name], equations[name] = stages(path, choice, args.repeat)

    for name, eq in equations.items():
        if len(eq.states) <= NAIVE_MAX_STATES:
            results[name]["naive"], _ = best(lambda eq=eq: naive_transfer(eq), 1)
        if name.startswith("stages") and int(name[6:]) <= args.baseline_max:
            results[name]["elimination"], _ = best(lambda eq=eq: eliminated_transfer(eq), 1)
    table(results, ["naive", "elimination"])

    print("\nspeed-up of the transfer stage over the baselines (same process):")
    for name, timings in results.items():
        ratios = [
            f"{timings[b] / timings['transfer']:8.1f}x over {b}"
            for b in ("naive", "elimination")
            if b in timings
        ]
        if ratios:
            print(f"  {name:<24}" + "   ".join(ratios))
    if len(args.sizes) > 1:
        growth(results, args.sizes, "ladder")
    if len(args.stages) > 1:
        growth(results, args.stages, "stages")
    return 0


if __name__ == "__main__":
    sys.exit(main())
