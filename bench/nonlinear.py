"""The generated nonlinear simulator against scipy's solve_ivp at equal accuracy (issue 19).

Run: nice .venv/bin/python bench/nonlinear.py [--samples 10001] [--sets 100] [--quick]
     [--case 'pendulum/prbs' ...]

For the two tanks (orifices, overflow) and the pendulum arm on a DC motor (gravity, tanh
Coulomb friction), each under a PRBS held between samples (hold="zoh", a switch every 1 %
of the record) and a multisine interpolated linearly (hold="linear", a new slope at every
sample), over --samples samples:

- reference: solve_ivp (DOP853, rtol 1e-13, atol 1e-15) from sample to sample on a
  hand-written right-hand side, each interval with its own input (held or linear), so
  that no step sees another interval's input (a failed interval stops the bench);
- baseline: the same hand-written right-hand side (Python floats, math functions) given
  to solve_ivp as a user writes it: over the whole record with t_eval at the samples
  (the input looked up by index), and, for the held input, restarted at each of its
  changes (what a careful user does), for each of its methods (RK45, DOP853, LSODA, BDF,
  Radau), at the loosest rtol in 1e-6 .. 1e-13 (atol = rtol / 100) whose output is
  within 1e-8 of the reference (relative to the output's largest value); the fastest
  variant is the baseline;
- generated: the module's simulate at the loosest rtol in that list meeting the same
  accuracy; the ratio is baseline / generated, the best of 3 timings each, taken in turns.

Then --sets parameter sets (the unknowns drawn within +-20 % of the model's values), 5 of
them checked against their own references: the generated module simulates them all in
one call (rows of k) at the loosest rtol meeting 1e-8 on the 5; the target's baseline is
the fastest single-set variant looped over the sets (at the loosest rtol meeting 1e-8 on
the 5; timed on the 5 and scaled), what a competent user writes; also shown, solve_ivp
on all the sets stacked as one system (a numpy right-hand side written by hand; RK45,
DOP853, LSODA), each ratio against the generated call.
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


def tanks_rhs(k, at):
    c1, c2, kp = k

    def rhs(time, x):
        h1, h2 = max(x[0], 0.0), max(x[1], 0.0) / 1.5
        q = c1 * math.sqrt(h1)
        return [kp * at(time) - q - 2.0 * max(h1 - 3.0, 0.0), q - c2 * math.sqrt(h2)]

    return rhs


def tanks_stacked(K, at):
    """The tanks of every row of K as one system (numpy, states set by set)."""
    c1, c2, kp = K.T

    def rhs(time, x):
        h1, h2 = np.maximum(x[0::2], 0.0), np.maximum(x[1::2], 0.0) / 1.5
        q = c1 * np.sqrt(h1)
        out = np.empty_like(x)
        out[0::2] = kp * at(time) - q - 2.0 * np.maximum(h1 - 3.0, 0.0)
        out[1::2] = q - c2 * np.sqrt(h2)
        return out

    return rhs


def pendulum_rhs(k, at):
    J, fc = k

    def rhs(time, x):
        i, w = 20.0 * x[0], x[1] / J
        torque = 0.5 * i - 0.5 * math.sin(x[2]) - fc * math.tanh(50.0 * w) - w / 100.0
        return [at(time) - i - 0.5 * w, torque, w]

    return rhs


def pendulum_stacked(K, at):
    J, fc = K.T

    def rhs(time, x):
        i, w = 20.0 * x[0::3], x[1::3] / J
        out = np.empty_like(x)
        out[0::3] = at(time) - i - 0.5 * w
        out[1::3] = 0.5 * i - 0.5 * np.sin(x[2::3]) - fc * np.tanh(50.0 * w) - w / 100.0
        out[2::3] = w
        return out

    return rhs


CASES = {
    # model: (system, values, hand-written rhs (one set; all sets stacked), output index
    # and scale, x0, span, input levels)
    "two tanks": (two_tanks, TWO_TANKS_K, (tanks_rhs, tanks_stacked), (1, 1 / 1.5),
                  [1.0, 1.0], 1000.0, (0.2, 0.8)),
    "pendulum": (pendulum, PENDULUM_K, (pendulum_rhs, pendulum_stacked), (2, 1.0),
                 [0.0, 0.0, 0.0], 100.0, (0.0, 3.0)),
}  # fmt: skip


def signals(module, t, kind, levels):
    low, high = levels
    if kind == "prbs":
        u = module.input_signal("prbs", t, amplitude=1.0, period=(t[-1] - t[0]) / 100)
        return low + high * (u + 1) / 2 if low else high * u, "zoh"
    u = module.input_signal("multisine", t, amplitude=1.0, period=(t[-1] - t[0]) / 5)
    return (low + high * (u + 1) / 2 if low else high * u), "linear"


def _line(value, start, slope):
    return lambda time: value + (time - start) * slope


def _slopes(t, u, hold):
    return np.zeros(t.size - 1) if hold == "zoh" else np.diff(u) / np.diff(t)


def reference(one, k, t, u, hold, x0, index):
    """The output at the samples by DOP853 (rtol 1e-13) from sample to sample, each
    interval with its own input (held or linear): no step sees another interval's input."""
    x, out, slopes = np.array(x0, dtype=float), [x0[index[0]]], _slopes(t, u, hold)
    for j in range(t.size - 1):
        rhs = one(k, _line(u[j], t[j], slopes[j]))
        solution = solve_ivp(rhs, (t[j], t[j + 1]), x, method="DOP853", rtol=1e-13, atol=1e-15)
        if not solution.success:
            raise RuntimeError(f"the reference failed at t = {t[j]:g}: {solution.message}")
        x = solution.y[:, -1]
        out.append(x[index[0]])
    return np.array(out) * index[1]


def error(y, exact):
    return float(np.max(np.abs(y - exact)) / np.max(np.abs(exact)))


def pieces(t, u, hold):
    """Where a user restarts the solver: at every change of a held input (PRBS), nowhere
    for an interpolated one (it turns at every sample)."""
    if hold != "zoh":
        return [(0, t.size - 1)]
    bounds = [0, *(np.flatnonzero(np.diff(u[:-1])) + 1).tolist(), t.size - 1]
    return list(zip(bounds[:-1], bounds[1:], strict=True))


def solver(rhs_of, t, u, hold, x0, index, method, rtol, piecewise, stride):
    """A run of solve_ivp as a user writes it: the whole record with t_eval at the samples
    (the input looked up by index), or (piecewise) restarted at each change of a held
    input with that piece's constant input. rhs_of(at) -> the right-hand side. The run
    gives the output at the samples, a row per set (x0: every set's states one after the
    other, `stride` states a set), or None where solve_ivp fails."""
    cuts = pieces(t, u, hold) if piecewise else [(0, t.size - 1)]
    whole = rhs_of(_input(t, u, hold))

    def run():
        x, out = np.array(x0, dtype=float), [np.array(x0, dtype=float)]
        for a, b in cuts:
            rhs = rhs_of(_line(u[a], t[a], 0.0)) if piecewise else whole
            solution = solve_ivp(rhs, (t[a], t[b]), x, method=method, t_eval=t[a : b + 1],
                                 rtol=rtol, atol=rtol / 100)  # fmt: skip
            if not solution.success or solution.y.shape[1] != b - a + 1:
                return None
            out.extend(solution.y[:, 1:].T)
            x = solution.y[:, -1]
        return (np.array(out)[:, index[0] :: stride] * index[1]).T

    return run


def baseline(rhs_of, t, u, hold, x0, index, exacts, stride, methods, slow, rtols=TOLERANCES):
    """{variant: (run, rtol, error)}: solve_ivp at the loosest rtol (atol = rtol / 100)
    whose output is within ACCURACY of the reference on each set of `exacts` ({row of
    the run's output: reference}), per method and, for a held input, whole or restarted
    at the input's changes; a variant slower than `slow` seconds a run is dropped."""
    found = {}
    for method in methods:
        for piecewise in (False, True) if hold == "zoh" else (False,):
            for rtol in rtols:
                run = solver(rhs_of, t, u, hold, x0, index, method, rtol, piecewise, stride)
                start = time.perf_counter()
                rows = run()
                if time.perf_counter() - start > slow or rows is None:
                    break
                miss = max(error(rows[i], exact) for i, exact in exacts.items())
                if miss <= ACCURACY:
                    found[method + " restarted" * piecewise] = (run, rtol, miss)
                    break
    return found


def generated(run_at, exacts):
    """(run, rtol, error): the module's simulate (run_at(rtol) -> rows of outputs) at the
    loosest rtol whose output is within ACCURACY of each reference in `exacts`."""
    miss = math.inf
    for rtol in TOLERANCES:
        run = partial(run_at, rtol)
        rows = np.atleast_2d(run())
        miss = max(error(rows[i], exact) for i, exact in exacts.items())
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


def _listing(times, found):
    return ", ".join(f"{m} {times[m]:.3f} s (rtol {found[m][1]:g})" for m in found)


def one_set(module, case, t, u, hold):
    """The single-set row: generated against each solve_ivp variant; returns the fastest
    variant's (method, piecewise, rtol), or None."""
    _, values, (one, _), index, x0, _, _ = case
    exact = {0: reference(one, values, t, u, hold, x0, index)}
    ours, rtol, miss = generated(
        lambda rtol: module.simulate(t, u, values, x0=x0, hold=hold, rtol=rtol, atol=rtol / 100),
        exact,
    )
    theirs = baseline(partial(one, values), t, u, hold, x0, index, exact, len(x0), METHODS, SLOW)
    if ours is None or not theirs:
        who = "the generated module" if ours is None else "no solve_ivp variant"
        print(f"  one set: {who} met {ACCURACY:g} at rtol >= 1e-13 (within {SLOW:g} s a run)")
        return None
    times = race({"generated": ours} | {m: run for m, (run, _, _) in theirs.items()})
    best = min(theirs, key=times.get)
    print(f"  one set: generated {times['generated']:.3f} s (rtol {rtol:g}, error {miss:.1e}); "
          f"solve_ivp {_listing(times, theirs)}; ratio {times[best] / times['generated']:.1f}x "
          f"against {best}", flush=True)  # fmt: skip
    return best, theirs[best][1]


def many_sets(module, case, t, u, hold, sets, best):
    """The many-sets row: one call of the generated simulate with rows of k, against the
    fastest single-set variant looped over the sets (timed on 5, scaled: what a competent
    user writes) and solve_ivp on all the sets stacked as one vectorised system."""
    _, values, (one, stacked), index, x0, _, _ = case
    rng = np.random.default_rng(1)
    K = np.array(values) * (1 + 0.2 * rng.uniform(-1, 1, (sets, len(values))))
    checked = list(range(0, sets, max(1, sets // 5)))
    exacts = {i: reference(one, K[i], t, u, hold, x0, index) for i in checked}
    ours, rtol, miss = generated(
        lambda rtol: module.simulate(t, u, K, x0=x0, hold=hold, rtol=rtol, atol=rtol / 100),
        exacts,
    )
    method, rtol_one = best
    piecewise = method.endswith(" restarted")
    loop_rtol = None
    for loop_rtol in [r for r in TOLERANCES if r <= rtol_one]:  # every checked set within
        runs = {i: solver(partial(one, K[i]), t, u, hold, x0, index, method.split()[0],
                          loop_rtol, piecewise, len(x0)) for i in checked}  # fmt: skip
        if max(error(runs[i]()[0], exacts[i]) for i in checked) <= ACCURACY:
            break
    loop = {i: runs[i] for i in checked}
    stacked_found = baseline(partial(stacked, K), t, u, hold, np.tile(x0, sets), index, exacts,
                             len(x0), ("RK45", "DOP853", "LSODA"), 4 * SLOW)  # fmt: skip
    entries = {"generated": ours} | {f"stacked {m}": r for m, (r, _, _) in stacked_found.items()}
    entries["loop"] = lambda: [run() for run in loop.values()]
    times = race(entries, repeat=2)
    scaled = times.pop("loop") / len(checked) * sets
    ratio = scaled / times["generated"]
    stacked_text = ", ".join(
        f"{m} {times['stacked ' + m]:.2f} s (rtol {r:g}, "
        f"{times['stacked ' + m] / times['generated']:.1f}x)"
        for m, (_, r, _) in stacked_found.items()
    )
    print(f"  {sets} sets at once: generated {times['generated']:.2f} s (rtol {rtol:g}, worst "
          f"error of {len(checked)} checked {miss:.1e}); solve_ivp {method} looped over the "
          f"sets {scaled:.1f} s (rtol {loop_rtol:g}; {len(checked)} timed, scaled); ratio "
          f"{ratio:.1f}x; stacked as one system: {stacked_text or 'none met the accuracy'}",
          flush=True)  # fmt: skip


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=10001)
    parser.add_argument("--sets", type=int, default=100)
    parser.add_argument("--quick", action="store_true", help="1001 samples, 10 sets")
    parser.add_argument("--case", nargs="*", default=None,
                        help="only these: 'pendulum/prbs', 'two tanks/multisine', ...")  # fmt: skip
    options = parser.parse_args(argv)
    samples, sets = (1001, 10) if options.quick else (options.samples, options.sets)
    for name, case in CASES.items():
        system, _, _, _, _, span, levels = case
        module = nonlinear_codegen.load(system())
        t = np.linspace(0.0, span, samples)
        for kind in ("prbs", "multisine"):
            if options.case is not None and f"{name}/{kind}" not in options.case:
                continue
            u, hold = signals(module, t, kind, levels)
            print(f"{name}, {kind} ({hold}), {samples} samples:", flush=True)
            best = one_set(module, case, t, u, hold)
            if best is not None and sets > 1:
                many_sets(module, case, t, u, hold, sets, best)
    return 0


if __name__ == "__main__":
    sys.exit(main())
