"""The generated estimators' `estimate` against a plain reference integration (issue 8).

The reference is the algorithm of method.md section 4 as a user would first write it:
scipy's solve_ivp (RK23, the estimates wanted at every sample, rtol 1e-6, atol 1e-9) with a
Python right-hand side that interpolates the data with np.interp and builds the Hankel
matrices K_i = d^i(K K^T)/dk^i on every call. It runs in this process, on the same data,
with the same filter and settings as the modules in generated/, which are timed with their
default engine (exact moments) and with engine="ode" (the paper's integration, the
previous default).

Agreement: the largest relative difference between the moments engine's k^ and the
reference's, over every sample of every run (relative to max |k^| of the run, as k^ may
cross zero).

Times are this process's CPU time (BLAS runs on one thread, as the reference does, so on
an idle machine CPU time is wall time; on a shared one, wall time also counts the other
processes, and OpenBLAS's worker threads can stall a call for a scheduler quantum), the
median of several runs (one run of the reference on the 10^5-sample record: it takes
minutes).

    .venv/bin/python bench/estimate.py          # all: a few minutes, mostly the reference
    .venv/bin/python bench/estimate.py --quick  # 10^4 instead of 10^5 samples
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # before numpy loads OpenBLAS

import argparse  # noqa: E402
import math  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402
from dataclasses import dataclass  # noqa: E402

import numpy as np  # noqa: E402
from _generated import generated  # noqa: E402
from scipy.integrate import solve_ivp  # noqa: E402

RTOL, ATOL = 1e-6, 1e-9  # the reference's tolerances (the ODE engine's defaults)


def reference(module, t, u, y, *, k0, C, beta=0.1, S0=1e-4) -> np.ndarray:
    """k^ at every sample, computed as a user would first write the algorithm."""
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
    solution = solve_ivp(rhs, (t[0], t[-1]), x0, method="RK23", t_eval=t, rtol=RTOL, atol=ATOL)
    return solution.y[2 * nc]


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
    fig2 = Experiment("Fig. 2: DC drive, 3 k0", dc, t, u, dc.simulate(t, u, 10.0), [])
    fig2.runs = [dict(k0=k0, C=None) for k0 in (0.0, 5.0, 20.0)]
    t = np.linspace(0.0, 4.0, 401)
    u = np.ones_like(t)
    y = absorber.simulate(t, u, 0.72) + np.random.default_rng(0).uniform(-0.02, 0.02, t.size)
    fig6 = Experiment("Fig. 6: absorber, 5 k0", absorber, t, u, y, [])
    fig6.runs = [dict(k0=k0, C=None) for k0 in (0.0, 0.25, 0.5, 0.75, 1.0)]
    fig7 = Experiment("Fig. 7: absorber, 3 C(s)", absorber, t, u, y, [])
    fig7.runs = [dict(k0=1.0, C=T) for T in (0.5, 1.0, 2.0)]
    samples = 10**4 if quick else 10**5  # 0.01 s apart, square-wave input, noisy output
    t = np.linspace(0.0, samples / 100, samples + 1)
    u = np.where((t // 20) % 2 == 0, 1.0, -1.0)
    y = absorber.simulate(t, u, 0.72) + np.random.default_rng(0).uniform(-0.02, 0.02, t.size)
    long = Experiment(f"absorber, {samples:.0e} noisy samples", absorber, t, u, y, [])
    long.runs = [dict(k0=1.0, C=None)]
    return [fig2, fig6, fig7, long]


def timed(function, repeat: int) -> tuple[float, object]:
    """Median CPU time of `repeat` calls, and the last result."""
    times = []
    for _ in range(repeat):
        start = time.process_time()
        result = function()
        times.append(time.process_time() - start)
    return statistics.median(times), result


def measure(experiment: Experiment) -> str:
    """One line of the table."""
    module, runs = experiment.module, experiment.runs
    data = (experiment.t, experiment.u, experiment.y)
    small = experiment.t.size < 10**4
    ours, results = timed(
        lambda: [module.estimate(*data, **run) for run in runs], 7 if small else 3
    )
    ode, _ = timed(
        lambda: [module.estimate(*data, **run, engine="ode") for run in runs], 3 if small else 1
    )
    theirs, trajectories = timed(
        lambda: [reference(module, *data, **run) for run in runs], 3 if small else 1
    )
    difference = max(
        np.max(np.abs(result.khat - khat)) / np.max(np.abs(khat))
        for result, khat in zip(results, trajectories, strict=True)
    )
    return (
        f"| {experiment.name} | {ours:.4f} s | {ode:.3f} s | {theirs:.2f} s | "
        f"{theirs / ours:,.0f}x | {ode / ours:.0f}x | {difference:.1e} |"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="10^4 samples in the long run")
    args = parser.parse_args()
    print("| experiment | estimate (moments) | engine=\"ode\" | reference | reference / moments "
          "| ode / moments | k^ vs reference |")  # fmt: skip
    print("|---|---|---|---|---|---|---|")
    for experiment in experiments(args.quick):
        print(measure(experiment), flush=True)


if __name__ == "__main__":
    main()
