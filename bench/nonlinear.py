"""The generated nonlinear simulator against scipy's solve_ivp at equal accuracy (issue 19).

Run: nice .venv/bin/python bench/nonlinear.py [--samples 10001] [--sets 100] [--quick]

For the two tanks (orifices, overflow) and the pendulum arm on a DC motor (gravity, tanh
Coulomb friction), each under a PRBS held between samples (hold="zoh", a switch every 1 %
of the record) and a multisine interpolated linearly (hold="linear", a new slope at every
sample), over --samples samples:

- reference: solve_ivp (DOP853, rtol 1e-13) from sample to sample on a hand-written
  right-hand side, so that no step crosses a change of the input;
- baseline: the same hand-written right-hand side (Python floats, math functions, the
  input looked up by index) given to solve_ivp over the whole record with t_eval at the
  samples, for each of its methods (RK45, DOP853, LSODA, BDF, Radau), at the loosest
  rtol in 1e-6 .. 1e-13 (atol = rtol / 100) whose output is within 1e-8 of the
  reference (relative to the output's largest value); the fastest method is the baseline;
- generated: the module's simulate at the loosest rtol in that list meeting the same
  accuracy; the ratio is baseline / generated, best of 3 runs each.

Then --sets parameter sets (the unknowns drawn within +-20 % of the model's values):
the generated module simulates them all at once (one call, rows of k), checked against
the reference on 5 of them; the baseline is the fastest single-set baseline method at
its tolerance, timed on 5 sets and scaled to all of them.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from functools import partial
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))

from nonlinear_models import PENDULUM_K, TWO_TANKS_K, pendulum, two_tanks  # noqa: E402

from mtt.estimator import nonlinear_codegen  # noqa: E402

TOLERANCES = [10.0**-e for e in range(6, 14)]
METHODS = ("RK45", "DOP853", "LSODA", "BDF", "Radau")
ACCURACY = 1e-8
SLOW = 20.0  # seconds: a baseline method slower than this at some tolerance is dropped


def _input(t, u, hold):
    """u(time) as a hand-written right-hand side looks it up: by index on a regular grid."""
    start, step, last = float(t[0]), float(t[1] - t[0]), t.size - 2
    values, slopes = u.tolist(), (np.diff(u) / np.diff(t)).tolist()

    def held(time):
        j = min(max(math.ceil((time - start) / step) - 1, 0), last)  # left-continuous
        return values[j]

    def linear(time):
        j = min(max(int((time - start) / step), 0), last)
        return values[j] + (time - start - j * step) * slopes[j]

    return held if hold == "zoh" else linear


def tanks_rhs(k, t, u, hold):
    c1, c2, kp = k
    at = _input(t, u, hold)

    def rhs(time, x):
        h1, h2 = max(x[0], 0.0), max(x[1], 0.0) / 1.5
        q = c1 * math.sqrt(h1)
        return [kp * at(time) - q - 2.0 * max(h1 - 3.0, 0.0), q - c2 * math.sqrt(h2)]

    return rhs


def pendulum_rhs(k, t, u, hold):
    J, fc = k
    at = _input(t, u, hold)

    def rhs(time, x):
        i, w = 20.0 * x[0], x[1] / J
        torque = 0.5 * i - 0.5 * math.sin(x[2]) - fc * math.tanh(50.0 * w) - w / 100.0
        return [at(time) - i - 0.5 * w, torque, w]

    return rhs


CASES = {
    # model: (system, values, hand-written rhs, output index and scale, x0, span, input)
    "two tanks": (two_tanks, TWO_TANKS_K, tanks_rhs, (1, 1 / 1.5), [1.0, 1.0], 1000.0,
                  (0.2, 0.8)),
    "pendulum": (pendulum, PENDULUM_K, pendulum_rhs, (2, 1.0), [0.0, 0.0, 0.0], 100.0,
                 (0.0, 3.0)),
}  # fmt: skip


def signals(module, t, kind, levels):
    low, high = levels
    if kind == "prbs":
        u = module.input_signal("prbs", t, amplitude=1.0, period=(t[-1] - t[0]) / 100)
        return low + high * (u + 1) / 2 if low else high * u, "zoh"
    u = module.input_signal("multisine", t, amplitude=1.0, period=(t[-1] - t[0]) / 5)
    return (low + high * (u + 1) / 2 if low else high * u), "linear"


def reference(rhs, t, x0, index):
    x, out = np.array(x0, dtype=float), [x0[index[0]]]
    for a, b in zip(t[:-1], t[1:], strict=True):
        x = solve_ivp(rhs, (a, b), x, method="DOP853", rtol=1e-13, atol=1e-15).y[:, -1]
        out.append(x[index[0]])
    return np.array(out) * index[1]


def error(y, exact):
    return float(np.max(np.abs(y - exact)) / np.max(np.abs(exact)))


def best(function, repeat=3):
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        result = function()
        times.append(time.perf_counter() - start)
    return min(times), result


def baseline(rhs, t, x0, index, exact):
    """{method: (seconds, rtol, error)} at the loosest tolerance meeting ACCURACY."""
    found = {}
    for method in METHODS:
        for rtol in TOLERANCES:
            run = partial(solve_ivp, rhs, (t[0], t[-1]), x0, method=method, t_eval=t,
                          rtol=rtol, atol=rtol / 100)  # fmt: skip

            start = time.perf_counter()
            solution = run()
            seconds = time.perf_counter() - start
            if seconds > SLOW or not solution.success:
                break
            miss = error(solution.y[index[0]] * index[1], exact)
            if miss <= ACCURACY:
                seconds, _ = best(run, 2)
                found[method] = (seconds, rtol, miss)
                break
    return found


def generated(module, t, u, hold, k, x0, exact):
    for rtol in TOLERANCES:
        y = module.simulate(t, u, k, x0=x0, hold=hold, rtol=rtol, atol=rtol / 100)
        if error(y, exact) <= ACCURACY:
            options = dict(x0=x0, hold=hold, rtol=rtol, atol=rtol / 100)
            seconds, y = best(partial(module.simulate, t, u, k, **options))
            return seconds, rtol, error(y, exact)
    return math.inf, None, error(y, exact)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=10001)
    parser.add_argument("--sets", type=int, default=100)
    parser.add_argument("--quick", action="store_true", help="1001 samples, 10 sets")
    options = parser.parse_args(argv)
    samples, sets = (1001, 10) if options.quick else (options.samples, options.sets)
    rows = []
    for name, (system, values, hand, index, x0, span, levels) in CASES.items():
        module = nonlinear_codegen.load(system())
        t = np.linspace(0.0, span, samples)
        for kind in ("prbs", "multisine"):
            u, hold = signals(module, t, kind, levels)
            exact = reference(hand(values, t, u, hold), t, x0, index)
            ours = generated(module, t, u, hold, values, x0, exact)
            theirs = baseline(hand(values, t, u, hold), t, x0, index, exact)
            method = min(theirs, key=lambda m: theirs[m][0])
            rows.append((name, kind, hold, ours, method, theirs))
            print(f"{name}, {kind} ({hold}), {samples} samples: generated {ours[0]:.3f} s "
                  f"(rtol {ours[1]:g}, error {ours[2]:.1e}); solve_ivp "
                  + ", ".join(f"{m} {s:.3f} s (rtol {r:g})" for m, (s, r, _) in theirs.items())
                  + f"; ratio {theirs[method][0] / ours[0]:.1f}x against {method}",
                  flush=True)  # fmt: skip
            # many parameter sets at once
            rng = np.random.default_rng(1)
            K = np.array(values) * (1 + 0.2 * rng.uniform(-1, 1, (sets, len(values))))
            options = dict(x0=x0, hold=hold, rtol=ours[1], atol=ours[1] / 100)
            together, Y = best(partial(module.simulate, t, u, K, **options), repeat=1)
            checked = [error(Y[i], reference(hand(K[i], t, u, hold), t, x0, index))
                       for i in range(0, sets, max(1, sets // 5))]  # fmt: skip
            seconds, rtol_b, _ = theirs[method]
            single = []
            for i in range(0, sets, max(1, sets // 5)):
                start = time.perf_counter()
                solve_ivp(hand(K[i], t, u, hold), (t[0], t[-1]), x0, method=method, t_eval=t,
                          rtol=rtol_b, atol=rtol_b / 100)  # fmt: skip
                single.append(time.perf_counter() - start)
            scaled = float(np.mean(single)) * sets
            print(
                f"    {sets} sets at once: generated {together:.2f} s (worst error of 5 "
                f"checked {max(checked):.1e}); solve_ivp {method} {scaled:.1f} s for "
                f"{sets} (5 timed); ratio {scaled / together:.1f}x",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
