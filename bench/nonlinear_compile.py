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

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # before numpy loads: one thread

import resource  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402
from types import MappingProxyType  # noqa: E402

import sympy  # noqa: E402
from sympy.core.cache import clear_cache  # noqa: E402

from mtt.derivation.nonlinear import nonlinear_state_space  # noqa: E402
from mtt.derivation.parameters import ParameterChoice  # noqa: E402
from mtt.derivation.pipeline import theta_for  # noqa: E402
from mtt.estimator import codegen, nonlinear_codegen  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
REPEATS = 5
POINTS = {  # the Makefile's COMPILE_OPTIONS
    "two_tanks": ({"u": 10}, None),
    "pendulum": ({"u": 1}, 1),
    "diode_clipper": ({"u": 1}, None),
}


def _processor() -> float:
    """Processor seconds used so far by this process and its finished children."""
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    return time.process_time() + children.ru_utime + children.ru_stime


def _median(work) -> tuple[float, float]:
    """(processor, wall) seconds of `work`: medians of REPEATS runs after a warm-up."""
    work()  # warm-up
    processor, wall = [], []
    for _ in range(REPEATS):
        clear_cache()
        start, begun = _processor(), time.perf_counter()
        work()
        wall.append(time.perf_counter() - begun)
        processor.append(_processor() - start)
    return statistics.median(processor), statistics.median(wall)


def main() -> None:
    baseline, baseline_wall = _median(
        lambda: codegen.render(theta_for(ROOT / "models" / "dc_drive.bg"))
    )
    print(
        f"baseline: dc_drive, text -> estimator source: {baseline:.3f} s "
        f"(wall {baseline_wall:.3f} s)"
    )
    print(
        f"{'model':<14} {'equations':>10} {'simulator':>10} {'estimator':>10}  x baseline"
        "  (processor time; wall time of the slower)"
    )
    for name, (at, branch) in POINTS.items():
        path = ROOT / "models" / f"{name}.bg"
        choice = ParameterChoice(
            at=MappingProxyType({k: sympy.Rational(v) for k, v in at.items()}), branch=branch
        )
        equations, _ = _median(lambda p=path: nonlinear_state_space(p))
        simulator = _median(lambda p=path: nonlinear_codegen.render(nonlinear_state_space(p)))
        estimator = _median(lambda p=path, c=choice: codegen.render(theta_for(p, c)))
        worst, wall = max(simulator, estimator)
        print(
            f"{name:<14} {equations:>9.3f}s {simulator[0]:>9.3f}s {estimator[0]:>9.3f}s  "
            f"{worst / baseline:.1f}  ({'met' if worst < 1 else 'NOT met'}: < 1 s; "
            f"wall {wall:.3f} s)"
        )
    sys.stdout.flush()


if __name__ == "__main__":
    main()
