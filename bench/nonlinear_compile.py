"""Compile time of the nonlinear examples, in process (issue 19: target < 1 s each).

For each nonlinear model in models/: the state equations (text -> NonlinearStateSpace),
the generated simulator (state equations -> module source), and the small-signal
estimator `make compile` writes (state equations -> steady state -> linearisation ->
transfer function -> Theta -> module source, at the Makefile's operating point). The
baseline is the linear chain of models/dc_drive.bg (text -> estimator source) in the same
process; every figure is the median of REPEATS runs after one warm-up (imports and
lark's parser in place), each from an empty sympy cache (a repeated derivation would
otherwise find its results there).

    python bench/nonlinear_compile.py
"""

from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path
from types import MappingProxyType

import sympy
from sympy.core.cache import clear_cache

from mtt.derivation.nonlinear import nonlinear_state_space
from mtt.derivation.parameters import ParameterChoice
from mtt.derivation.pipeline import theta_for
from mtt.estimator import codegen, nonlinear_codegen

ROOT = Path(__file__).resolve().parent.parent
REPEATS = 5
POINTS = {  # the Makefile's COMPILE_OPTIONS
    "two_tanks": ({"u": 10}, None),
    "pendulum": ({"u": 1}, 1),
    "diode_clipper": ({"u": 1}, None),
}


def _median(work) -> float:
    work()  # warm-up
    times = []
    for _ in range(REPEATS):
        clear_cache()
        start = time.perf_counter()
        work()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main() -> None:
    baseline = _median(lambda: codegen.render(theta_for(ROOT / "models" / "dc_drive.bg")))
    print(f"baseline: dc_drive, text -> estimator source: {baseline:.3f} s")
    print(f"{'model':<14} {'equations':>10} {'simulator':>10} {'estimator':>10}  x baseline")
    for name, (at, branch) in POINTS.items():
        path = ROOT / "models" / f"{name}.bg"
        choice = ParameterChoice(
            at=MappingProxyType({k: sympy.Rational(v) for k, v in at.items()}), branch=branch
        )
        equations = _median(lambda p=path: nonlinear_state_space(p))
        simulator = _median(lambda p=path: nonlinear_codegen.render(nonlinear_state_space(p)))
        estimator = _median(lambda p=path, c=choice: codegen.render(theta_for(p, c)))
        worst = max(simulator, estimator)
        print(
            f"{name:<14} {equations:>9.3f}s {simulator:>9.3f}s {estimator:>9.3f}s  "
            f"{worst / baseline:.1f}  ({'met' if worst < 1 else 'NOT met'}: < 1 s)"
        )
    sys.stdout.flush()


if __name__ == "__main__":
    main()
