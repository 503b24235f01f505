"""Causality assignment time against the number of bonds (issue 12 item 8).

Run: .venv/bin/python bench/causality.py [--repeat 3]

Three families, each at growing sizes: an RC ladder (four bonds a stage), the same with a
clash no causality suits placed after all of its free choices, and one 1-junction with
many inertias. The table gives the best time of `--repeat` runs, the time of reading the
same model (parse and build) in the same process as the baseline, their ratio, and the
growth exponent of the causality time between sizes (1 is linear).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

from test_hostile import junction, ladder  # noqa: E402  the models of the regression tests

from mtt.derivation.causality import assign  # noqa: E402
from mtt.language.bondgraph import build  # noqa: E402
from mtt.language.diagnostics import ModelError, Source  # noqa: E402
from mtt.language.parse import parse  # noqa: E402

TARGET = 1.0  # seconds for a 1000-bond model


def best(action, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        action()
        times.append(time.perf_counter() - start)
    return min(times)


def attempt(graph) -> str:
    try:
        causal = assign(graph)
    except ModelError:
        return "causal_conflict"
    return f"{len(causal.dependent)} dependent"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    families = {
        "ladder": [ladder(n) for n in (125, 250, 500, 1000)],
        "ladder + clash": [ladder(n, conflict=True) for n in (125, 250, 500, 1000)],
        "1-junction": [junction(n) for n in (500, 1000, 2000, 4000)],
    }
    header = ("model", "bonds", "causality", "read", "ratio", "growth")
    print("{:16} {:>6} {:>10} {:>8} {:>6} {:>6}  result".format(*header))
    for family, texts in families.items():
        previous = None
        for text in texts:
            source = Source("bench.bg", text)
            read = best(lambda: build(parse(source)), args.repeat)  # noqa: B023
            graph = build(parse(source))
            spent = best(lambda: attempt(graph), args.repeat)  # noqa: B023
            bonds = len(graph.bonds)
            growth = ""
            if previous is not None:
                growth = f"{math.log(spent / previous[1]) / math.log(bonds / previous[0]):6.2f}"
            note = attempt(graph)
            if 900 <= bonds <= 1100:
                note += f"  (target < {TARGET} s: {'met' if spent < TARGET else 'NOT met'})"
            print(
                f"{family:16} {bonds:6d} {spent * 1e3:8.1f}ms {read * 1e3:6.1f}ms "
                f"{spent / read:6.2f} {growth:>6}  {note}"
            )
            previous = (bonds, spent)


if __name__ == "__main__":
    main()
