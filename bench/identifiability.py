"""Time of `mtt identifiability` on the shipped models and the textbook cases (issue 11:
under 5 s each), against the derivation of Theta in the same process.

Run: .venv/bin/python bench/identifiability.py [--repeat 3]

For each case: the verdict, the number of solutions (or the combinations the data
determine), the time of the first run (sympy's caches cold, as in a fresh `mtt`
process), the best of `--repeat` runs, and the best as a multiple of deriving Theta.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from mtt.derivation.identifiability import expression_text, identifiability
from mtt.derivation.parameters import ParameterChoice
from mtt.derivation.pipeline import theta_for

ROOT = Path(__file__).resolve().parent.parent
CASES = ROOT / "tests" / "data" / "identifiability"
TARGET = 5.0  # seconds
RUNS = [  # (label, file, unknowns, kept)
    ("absorber", "models/absorber.bg", None, ()),
    ("absorber --keep tau,l", "models/absorber.bg", None, ("tau", "l")),
    ("absorber_stages", "models/absorber_stages.bg", None, ()),
    ("dc_drive", "models/dc_drive.bg", None, ()),
    ("dc_motor", "models/dc_motor.bg", None, ()),
    ("rlc", "models/rlc.bg", None, ()),
    ("rlc3", "models/rlc3.bg", None, ()),
    *((f"tests: {p.stem}", str(p.relative_to(ROOT)), None, ()) for p in sorted(CASES.glob("*.bg"))),
    ("series_resistors r1,r2,l", str(CASES / "series_resistors.bg"), ("r1", "r2", "l"), ()),
    ("dc_motor jm,jl", "models/dc_motor.bg", ("jm", "jl"), ()),
    ("dc_motor ra,jl,km", "models/dc_motor.bg", ("ra", "jl", "km"), ()),
    ("dc_motor all 6", "models/dc_motor.bg", ("ra", "jl", "km", "la", "jm", "b"), ()),
    ("dc_drive all 6", "models/dc_drive.bg", ("ra", "ia", "jm", "km", "ks", "k"), ()),
    ("absorber tau,l,k", "models/absorber.bg", ("tau", "l", "k"), ()),
]


def best(action, repeat: int) -> tuple[float, float, object]:
    """(first, best) wall time of `action()` over `repeat` runs, and its result."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        result = action()
        times.append(time.perf_counter() - start)
    return times[0], min(times), result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3, help="runs per case (default 3)")
    args = parser.parse_args()
    header = ("case", "verdict", "solutions or combinations", "first", "best", "x Theta")
    print(f"| {' | '.join(header)} |")
    print(f"|{'|'.join('---' for _ in header)}|")
    slowest = 0.0
    for label, file, unknowns, kept in RUNS:
        choice = ParameterChoice(unknowns=unknowns, keep=frozenset(kept))
        _, derive, theta = best(lambda: theta_for(ROOT / file, choice), args.repeat)  # noqa: B023
        first, fastest, result = best(lambda: identifiability(theta), args.repeat)  # noqa: B023
        slowest = max(slowest, first)
        found = (
            str(result.solutions)
            if result.solutions
            else ", ".join(expression_text(c) for c in result.combinations) or "nothing"
        )
        print(
            f"| {label} | {result.verdict} | {found} | {first:.3f} s | {fastest:.3f} s "
            f"| {fastest / derive:.1f} |"
        )
    verdict = "met" if slowest < TARGET else "NOT met"
    print(f"\nslowest first run: {slowest:.2f} s (target < {TARGET:g} s each: {verdict})")


if __name__ == "__main__":
    main()
