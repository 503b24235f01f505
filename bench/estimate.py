"""Wall time of the generated estimators against a plain reference integration.

The reference is the algorithm of method.md section 4 as a user would first write it:
scipy's solve_ivp (RK23, the estimates wanted at every sample) with a Python right-hand
side that interpolates the data with np.interp and builds the Hankel matrices
K_i = d^i(K K^T)/dk^i on every call. It runs in this process, on the same data, with the
same filter and settings as the generated module in generated/.

Accuracy: the error of a run is its largest distance, over the experiment's runs, from
the final estimates of a very tight run (the generated module at rtol 1e-10). The
reference is timed at the generated module's tolerance and then, if it is less accurate,
at tighter tolerances until it is at least as accurate: "equal accuracy" is that time.

    .venv/bin/python bench/estimate.py          # all: ten minutes, mostly the reference
    .venv/bin/python bench/estimate.py --quick  # 10^4 instead of 10^5 samples: one minute
"""

from __future__ import annotations

import argparse
import importlib.util
import math
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

ROOT = Path(__file__).resolve().parent.parent
RTOL, ATOL = 1e-6, 1e-9  # the generated estimator's defaults


def generated(name: str):
    spec = importlib.util.spec_from_file_location(name, ROOT / "generated" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


def reference(module, t, u, y, *, k0, C, beta=0.1, S0=1e-4, rtol=RTOL, atol=ATOL) -> float:
    """The final estimate, computed as a user would first write the algorithm."""
    Theta, n, m, N = module.theta(), module.n, module.m, module.N
    c = module.filter_polynomial(C)
    nc = len(c) - 1
    A = np.zeros((nc, nc))  # controllable canonical form of 1/C(s)
    A[:-1, 1:] = np.eye(nc - 1)
    A[-1, :] = -c[::-1][:-1] / c[0]
    B = np.zeros(nc)
    B[-1] = 1 / c[0]

    def K_derivative(k, i):  # d^i/dk^i of K K^T, K = [1, k, ..., k^N]
        Ki = np.zeros((N + 1, N + 1))
        for a in range(N + 1):
            for b in range(N + 1):
                p = a + b
                if p >= i:
                    Ki[a, b] = math.factorial(p) / math.factorial(p - i) * k ** (p - i)
        return Ki

    def rhs(time, x):
        yt, ut = np.interp(time, t, y), np.interp(time, t, u)
        xy, xu, k, J = x[:nc], x[nc : 2 * nc], x[2 * nc], x[2 * nc + 1 :]
        X = np.concatenate([xy[: n + 1], xu[: m + 1]])
        h = [0.5 * X @ Theta @ K_derivative(k, i) @ Theta.T @ X for i in range(1, 2 * N + 1)]
        dk = -h[0] / J[0]
        dJ = [
            -beta * J[i] + h[i + 1] + (J[i + 1] * dk if i + 1 < len(J) else 0.0)
            for i in range(len(J))
        ]
        return np.concatenate([A @ xy + B * yt, A @ xu + B * ut, [dk], dJ])

    x0 = np.zeros(2 * nc + 2 * N)
    x0[2 * nc], x0[2 * nc + 1] = k0, S0
    solution = solve_ivp(rhs, (t[0], t[-1]), x0, method="RK23", t_eval=t, rtol=rtol, atol=atol)
    return float(solution.y[2 * nc, -1])


@dataclass
class Experiment:
    name: str
    module: object
    t: np.ndarray
    u: np.ndarray
    y: np.ndarray
    runs: list[dict]  # keyword arguments of estimate: k0 and C


def experiments(quick: bool) -> list[Experiment]:
    dc, absorber = generated("dc_drive"), generated("absorber")
    t = np.linspace(0.0, 10.0, 1001)
    u = np.ones_like(t)
    fig2 = Experiment("Fig. 2  dc_drive, 3 k0", dc, t, u, dc.simulate(t, u, 10.0), [])
    fig2.runs = [dict(k0=k0, C=None) for k0 in (0.0, 5.0, 20.0)]
    t = np.linspace(0.0, 4.0, 401)
    u = np.ones_like(t)
    y = absorber.simulate(t, u, 0.72) + np.random.default_rng(0).uniform(-0.02, 0.02, t.size)
    fig6 = Experiment("Fig. 6  absorber, 5 k0", absorber, t, u, y, [])
    fig6.runs = [dict(k0=k0, C=None) for k0 in (0.0, 0.25, 0.5, 0.75, 1.0)]
    fig7 = Experiment("Fig. 7  absorber, 3 C(s)", absorber, t, u, y, [])
    fig7.runs = [dict(k0=1.0, C=T) for T in (0.5, 1.0, 2.0)]
    samples = 10**4 if quick else 10**5  # 0.01 s apart, square wave input, noisy output
    t = np.linspace(0.0, samples / 100, samples + 1)
    u = np.where((t // 20) % 2 == 0, 1.0, -1.0)
    y = dc.simulate(t, u, 10.0) + np.random.default_rng(0).uniform(-0.01, 0.01, t.size)
    long = Experiment(f"dc_drive, {samples:.0e} noisy samples", dc, t, u, y, [dict(k0=5.0, C=None)])
    return [fig2, fig6, fig7, long]


def timed(function, repeat: int) -> tuple[float, list[float]]:
    """Best wall time of `repeat` calls, and the result."""
    best = math.inf
    for _ in range(repeat):
        start = time.perf_counter()
        result = function()
        best = min(best, time.perf_counter() - start)
    return best, result


def measure(experiment: Experiment) -> str:
    """One line of the table: times, ratios and errors of one experiment."""
    module, data, runs = (
        experiment.module,
        (experiment.t, experiment.u, experiment.y),
        experiment.runs,
    )
    repeat = 3 if experiment.t.size < 10**4 else 1
    truth = [module.estimate(*data, **run, rtol=1e-10, atol=1e-13).k for run in runs]

    def error(estimates: list[float]) -> float:
        return max(abs(a - b) for a, b in zip(estimates, truth, strict=True))

    time_ours, k_ours = timed(lambda: [module.estimate(*data, **run).k for run in runs], repeat)
    error_ours = error(k_ours)
    timings = []  # (seconds, error, rtol) of the reference, tighter and tighter
    for tighter in range(4):
        rtol, atol = RTOL * 10**-tighter, ATOL * 10**-tighter
        seconds, k_theirs = timed(
            lambda rtol=rtol, atol=atol: [
                reference(module, *data, **run, rtol=rtol, atol=atol) for run in runs
            ],
            repeat,
        )
        timings.append((seconds, error(k_theirs), rtol))
        if timings[-1][1] <= error_ours:
            break
    same, equal = timings[0], timings[-1]
    reached = "" if equal[1] <= error_ours else " (not reached)"
    return (
        f"{experiment.name:32} {time_ours:9.3f}s {same[0]:9.3f}s {same[0] / time_ours:5.1f}x   "
        f"{equal[0]:8.3f}s at rtol {equal[2]:.0e} = {equal[0] / time_ours:5.1f}x{reached}   "
        f"{error_ours:.1e}, {same[1]:.1e}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="10^4 samples in the long run")
    args = parser.parse_args()
    print(f"{'experiment':32} {'generated':>10} {'reference':>10} {'ratio':>6}   "
          f"{'reference at equal accuracy':>31}   errors at rtol {RTOL:.0e}: generated, "
          "reference")  # fmt: skip
    for experiment in experiments(args.quick):
        print(measure(experiment), flush=True)


if __name__ == "__main__":
    main()
