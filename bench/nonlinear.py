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
  accuracy; the ratio is baseline / generated, the best of 3 timings each, taken in turns.

Then --sets parameter sets (the unknowns drawn within +-20 % of the model's values):
the generated module simulates them all at once (one call, rows of k) at the loosest
rtol whose output is within 1e-8 of the reference on 5 of them; the baseline is the
fastest single-set baseline method at its tolerance, timed on those 5 and scaled.
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


def baseline(rhs, t, x0, index, exact):
    """{method: (run, rtol, error)}: solve_ivp's run at the loosest tolerance meeting
    ACCURACY, for each method that meets it within SLOW seconds a run."""
    found = {}
    for method in METHODS:
        for rtol in TOLERANCES:
            run = partial(solve_ivp, rhs, (t[0], t[-1]), x0, method=method, t_eval=t,
                          rtol=rtol, atol=rtol / 100)  # fmt: skip
            start = time.perf_counter()
            solution = run()
            if time.perf_counter() - start > SLOW or not solution.success:
                break
            miss = error(solution.y[index[0]] * index[1], exact)
            if miss <= ACCURACY:
                found[method] = (run, rtol, miss)
                break
    return found


def generated(module, t, u, hold, k, x0, exact):
    """(run, rtol, error): the module's simulate at the loosest tolerance meeting ACCURACY."""
    for rtol in TOLERANCES:
        run = partial(module.simulate, t, u, k, x0=x0, hold=hold, rtol=rtol, atol=rtol / 100)
        miss = error(run(), exact)
        if miss <= ACCURACY:
            return run, rtol, miss
    return None, None, miss


def race(runs: dict, repeat: int = 3) -> dict:
    """The best of `repeat` timings of each run, taken in turns (A, B, C, A, B, C, ...) so
    that a burst of load on the shared machine falls on all of them alike."""
    times = {name: math.inf for name in runs}
    for _ in range(repeat):
        for name, run in runs.items():
            start = time.perf_counter()
            run()
            times[name] = min(times[name], time.perf_counter() - start)
    return times


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=10001)
    parser.add_argument("--sets", type=int, default=100)
    parser.add_argument("--quick", action="store_true", help="1001 samples, 10 sets")
    parser.add_argument("--case", nargs="*", default=None,
                        help="only these: 'pendulum/prbs', 'two tanks/multisine', ...")  # fmt: skip
    options = parser.parse_args(argv)
    samples, sets = (1001, 10) if options.quick else (options.samples, options.sets)
    rows = []
    for name, (system, values, hand, index, x0, span, levels) in CASES.items():
        module = nonlinear_codegen.load(system())
        t = np.linspace(0.0, span, samples)
        for kind in ("prbs", "multisine"):
            if options.case is not None and f"{name}/{kind}" not in options.case:
                continue
            u, hold = signals(module, t, kind, levels)
            exact = reference(hand(values, t, u, hold), t, x0, index)
            ours, rtol, miss = generated(module, t, u, hold, values, x0, exact)
            theirs = baseline(hand(values, t, u, hold), t, x0, index, exact)
            if ours is None or not theirs:
                print(f"{name}, {kind} ({hold}), {samples} samples: "
                      + ("the generated module" if ours is None else "no solve_ivp method")
                      + f" met {ACCURACY:g} at rtol >= 1e-13 (within {SLOW:g} s a run)",
                      flush=True)  # fmt: skip
                continue
            times = race({"generated": ours} | {m: run for m, (run, _, _) in theirs.items()})
            method = min(theirs, key=times.get)
            ratio = times[method] / times["generated"]
            rows.append((name, kind, hold, times, rtol, method, ratio))
            print(f"{name}, {kind} ({hold}), {samples} samples: generated "
                  f"{times['generated']:.3f} s (rtol {rtol:g}, error {miss:.1e}); solve_ivp "
                  + ", ".join(f"{m} {times[m]:.3f} s (rtol {theirs[m][1]:g})" for m in theirs)
                  + f"; ratio {ratio:.1f}x against {method}", flush=True)  # fmt: skip
            # many parameter sets at once, against the fastest method one set at a time
            rng = np.random.default_rng(1)
            K = np.array(values) * (1 + 0.2 * rng.uniform(-1, 1, (sets, len(values))))
            every = max(1, sets // 5)
            exacts = {i: reference(hand(K[i], t, u, hold), t, x0, index)
                      for i in range(0, sets, every)}  # fmt: skip
            for rtol_sets in [r for r in TOLERANCES if r <= rtol]:  # all checked within 1e-8
                start = time.perf_counter()
                Y = module.simulate(t, u, K, x0=x0, hold=hold, rtol=rtol_sets,
                                    atol=rtol_sets / 100)  # fmt: skip
                together = time.perf_counter() - start
                checked = [error(Y[i], exact) for i, exact in exacts.items()]
                if max(checked) <= ACCURACY:
                    break
            rtol_b = theirs[method][1]
            single = []
            for i in range(0, sets, every):
                start = time.perf_counter()
                solve_ivp(hand(K[i], t, u, hold), (t[0], t[-1]), x0, method=method, t_eval=t,
                          rtol=rtol_b, atol=rtol_b / 100)  # fmt: skip
                single.append(time.perf_counter() - start)
            scaled = float(np.mean(single)) * sets
            print(f"    {sets} sets at once: generated {together:.2f} s (rtol {rtol_sets:g}, worst "
                  f"error of {len(checked)} checked {max(checked):.1e}); solve_ivp {method} "
                  f"{scaled:.1f} s "
                  f"for {sets} ({len(single)} timed, scaled); ratio {scaled / together:.1f}x",
                  flush=True)  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
