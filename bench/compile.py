"""Time each stage of the compiler on the paper's models and on RC ladders of growing size.

Run: .venv/bin/python bench/compile.py [--sizes 5 10 20 40] [--stages 10 20 40 80 160]
                                       [--baseline-max 40] [--repeat 3]
                                       [--symbolic 4 6 8 10 12] [--abcd-max 8] [--wide]

Prints, per model, the best wall time of each stage (text -> parse tree -> bond graph ->
causal bond graph -> equations -> transfer function -> Theta), their total, and the total
of the first runs (caches cold, as in a fresh `mtt` process: the targets of issues 3 and
10 are checked on it). The ladders come two ways: written out in one file (--sizes), and
assembled from one section file used as a subsystem (--stages). Baselines, in this
process: the transfer stage done the textbook way (sympy Matrix inverse and cancel) for
small models, and by fraction-free elimination over the polynomials (the transfer stage
before it evaluated and interpolated the determinants) for the assembled ladders up to
--baseline-max sections (now the sparse fraction-free elimination the transfer stage
falls back to for many symbols). Then the growth exponent of the total time with the
number of sections (the slope of log time against log size).

--symbolic (issue 23): RC ladders with every parameter symbolic, derived to the transfer
function and to Theta (budget raised to 200000 terms), against the plain sympy product of
the sections' ABCD matrices (each product expanded, then k / (A k + B)) in the same
process up to --abcd-max sections, checked equal to it exactly; the growth exponent of
the time against the size of the result (terms). --wide: a 0-junction with 200 parallel
resistors (an algebraic loop of 400 variables) and 1000 instances of a one-bond part.
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from pathlib import Path

import sympy

from mtt.derivation import deadline, determinants
from mtt.derivation.budget import Budget
from mtt.derivation.causality import assign
from mtt.derivation.equations import derive
from mtt.derivation.parameters import ParameterChoice, parametrise
from mtt.derivation.pipeline import read_source
from mtt.derivation.theta import theta_matrix
from mtt.derivation.transfer import LAPLACE, transfer_function
from mtt.language.bondgraph import build
from mtt.language.parse import parse
from mtt.present import report

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


def symbolic_ladder(sections: int) -> str:
    lines = ["model sladder", "unknown k"]
    lines += [f"param {kind}{i}" for i in range(1, sections + 1) for kind in "rc"]
    lines.append("Se:v -> 1:s1")
    for i in range(1, sections + 1):
        lines += [f"1:s{i} -> R:r{i}(r{i})", f"1:s{i} -> 0:n{i}", f"0:n{i} -> C:c{i}(c{i})"]
        lines += [f"0:n{i} -> 1:s{i + 1}"] if i < sections else []
    lines += [f"0:n{sections} -> R:load(k)", f"0:n{sections} -> De:out"]
    return "\n".join(lines) + "\n"


def abcd(sections: int):
    """The plain sympy way: the product of the sections' ABCD matrices, expanded at each
    step, and V_out / V_in = k / (A k + B) for the load k; (numerator, denominator)."""
    s, k = sympy.symbols("s k")
    chain = sympy.eye(2)
    for i in range(1, sections + 1):
        r, c = sympy.symbols(f"r{i} c{i}")
        chain = (
            chain * sympy.Matrix([[1, r], [0, 1]]) * sympy.Matrix([[1, 0], [c * s, 1]])
        ).expand()
    return k, sympy.expand(chain[0, 0] * k + chain[0, 1])


def derive_symbolic(path: Path, budget: Budget) -> dict[str, float]:
    timings: dict[str, float] = {}
    start = time.process_time()
    graph = build(parse(read_source(path)))
    equations = derive(assign(graph), parametrise(graph, ParameterChoice()), budget)
    tf = transfer_function(equations)
    timings["transfer"] = time.process_time() - start
    start = time.process_time()
    theta = theta_matrix(tf)
    timings["theta"] = time.process_time() - start
    timings["total"] = timings["transfer"] + timings["theta"]
    start = time.process_time()
    report.tf_text(theta)  # what `mtt tf` prints
    timings["text"] = time.process_time() - start
    return timings, tf, theta


def symbolic_table(sizes: list[int], abcd_max: int) -> None:
    budget = Budget(max_terms=200_000)
    rows = []
    print(
        "\nfully symbolic RC ladders (every r_i, c_i and the load k symbolic), seconds of "
        "processor time (one thread: the same work on an idle and a busy machine):"
    )
    print(f"{'sections':>9}{'terms':>9}{'transfer':>10}{'theta':>9}{'total':>9}{'text':>9}"
          f"{'ABCD':>9}{'total/ABCD':>11}  exact")  # fmt: skip
    with tempfile.TemporaryDirectory() as tmp:
        for n in sizes:
            path = Path(tmp) / f"sladder{n}.bg"
            path.write_text(symbolic_ladder(n), encoding="utf-8")
            timings, tf, theta = derive_symbolic(path, budget)
            terms = len(tf.num) + len(tf.den)
            cells = f"{n:>9}{terms:>9}{timings['transfer']:>10.3f}{timings['theta']:>9.3f}"
            cells += f"{timings['total']:>9.3f}{timings['text']:>9.3f}"
            if n <= abcd_max:
                start = time.process_time()
                num, den = abcd(n)
                product = time.process_time() - start
                same = sympy.expand(theta.num * den - theta.den * num) == 0
                ratio = timings["total"] / product
                cells += f"{product:>9.3f}{ratio:>10.3f}x  {'yes' if same else 'NO'}"
            print(cells)
            rows.append((terms, timings["total"]))
    if len(rows) > 2:
        xs = [math.log(t) for t, _ in rows]
        ys = [math.log(s) for _, s in rows]
        mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
        slope = sum((x - mx) * (y - my) for x, y in zip(xs, ys, strict=True)) / sum(
            (x - mx) ** 2 for x in xs
        )
        print(f"  growth: total time ~ terms^{slope:.2f} (terms of the result, over the rows)")


def wide_table() -> None:
    """One junction, many bonds: an algebraic loop of hundreds of variables, and a thousand
    subsystems of one bond."""
    print("\nwide junctions, seconds (derivation to Theta; target < 2 s each):")
    with tempfile.TemporaryDirectory() as tmp:
        lines = ["model wide", "unknown k = 2", "param r = 3", "Se:v -> 1:s", "1:s -> I:l(k)"]
        lines += ["1:s -> 0:n", *(f"0:n -> R:r{i}(r)" for i in range(200)), "0:n -> De:out"]
        (Path(tmp) / "wide.bg").write_text("\n".join(lines) + "\n", encoding="utf-8")
        (Path(tmp) / "part.bg").write_text("model part\nparam r = 1\nSS:in -> R:r(r)\n")
        lines = ["model many", "unknown k = 2"]
        lines += [f'subsystem p{i} = "part.bg"' for i in range(1000)]
        lines += ["Se:v -> 1:s", "1:s -> I:l(k)", "1:s -> 0:n"]
        lines += [f"0:n -> p{i}.in" for i in range(1000)] + ["0:n -> De:out"]
        (Path(tmp) / "many.bg").write_text("\n".join(lines) + "\n", encoding="utf-8")
        for name, label in (("wide", "200 parallel resistors"), ("many", "1000 one-bond parts")):
            path = Path(tmp) / f"{name}.bg"
            start, cpu = time.perf_counter(), time.process_time()
            _, _, theta = derive_symbolic(path, Budget())
            took, cpu = time.perf_counter() - start, time.process_time() - cpu
            read, _ = best(lambda path=path: build(parse(read_source(path))), 1)
            print(
                f"  {label:<24}{took:>8.2f} s (processor {cpu:.2f} s; {took / read:.1f}x "
                f"reading it, {read:.2f} s)   G(s) = {theta.num} / ({theta.den})"
            )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[5, 10, 20, 40])
    parser.add_argument("--stages", type=int, nargs="+", default=[10, 20, 40, 80, 160])
    parser.add_argument("--baseline-max", type=int, default=40)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--symbolic", type=int, nargs="*", default=[4, 6, 8, 10, 12])
    parser.add_argument("--abcd-max", type=int, default=8)
    parser.add_argument("--wide", action="store_true", help="also the wide junctions")
    args = parser.parse_args()
    with deadline.budget(math.inf):  # the work is measured here, not cut short
        if args.symbolic:
            symbolic_table(args.symbolic, args.abcd_max)
        if args.wide:
            wide_table()

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
