"""Issue 21's targets for estimation from several inputs and outputs: a measured disturbance
fitted against the same unknown fitted with the disturbance left in the noise, and the
speed of a two-input two-output fit against a single-channel fit.

The records: models/dc_motor_load.bg (unknown load inertia jl = 10), the armature voltage a
PRBS of 1 s switching period, the load torque an independent PRBS of 1.5 s, both held
between samples (dt = 0.01 s, 100 s); every output simulated by scipy.signal.lsim of mtt's
state space (interp=False: exact for the held inputs), plus white Gaussian noise at 20 dB
on each output (the clean output's variance over the noise's). "measured": the compiled
module's fit_signals with both inputs (noise "auto", offsets and initial states
estimated, told the hold); "voltage alone": its fit (channel Se:v -> Df:speed) with the
torque unmeasured. "k_se / std" is the mean standard error over the spread of the
estimates; "covers" the share of 95 % intervals that hold the truth; the medians and the
interquartile range (over 1.349: the std of a normal spread) are there for a fit whose
estimates have outliers. Speed: the wall time
of fit_signals on a 2 x 2 record against fit on one channel's record of the same samples,
interleaved, the ratio of their medians (throughput per sample: single over two-by-two
time; the target is at least 1/3).

    .venv/bin/python bench/mimo.py --seeds 60        # the table (about 10 minutes)
    .venv/bin/python bench/mimo.py --seeds 8 --repeats 3
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # before numpy loads OpenBLAS

import argparse  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
from scipy import signal  # noqa: E402

import mtt  # noqa: E402

MODEL = str(Path(__file__).resolve().parent.parent / "models" / "dc_motor_load.bg")
TRUTH = 10.0
DT, SPAN, SNR_DB = 0.01, 100.0, 20.0


def prbs(t: np.ndarray, period: float, rng) -> np.ndarray:
    switches = rng.choice([-1.0, 1.0], size=int(t[-1] / period) + 2)
    return switches[(t / period).astype(int)]


def record(model, outputs: int, seed: int):
    """(t, U, Y): both inputs, the first `outputs` outputs, 20 dB white noise on each."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, SPAN, DT)
    U = np.column_stack([prbs(t, 1.0, rng), prbs(t, 1.5, rng)])
    G = model.to_scipy(TRUTH)
    clean = signal.lsim((G.A, G.B, G.C, G.D), U, t, interp=False)[1].reshape(t.size, -1)
    clean = clean[:, :outputs]
    noise = rng.standard_normal(clean.shape) * np.sqrt(clean.var(0) / 10 ** (SNR_DB / 10))
    return t, U, clean + noise


def row(label: str, k: np.ndarray, se: np.ndarray) -> str:
    std = k.std(ddof=1)
    covers = np.mean(np.abs(k - TRUTH) <= 1.96 * se)
    spread = np.subtract(*np.percentile(k, [75, 25])) / 1.349  # the std if normal, robustly
    return (f"| {label} | {100 * (k.mean() - TRUTH) / TRUTH:+.3g} % | "
            f"{100 * (np.median(k) - TRUTH) / TRUTH:+.3g} % | {std:.4g} | {spread:.4g} | "
            f"{np.median(se):.4g} | {np.mean(se) / std:.2f} | {100 * covers:.0f} % |")  # fmt: skip


def calibration(seeds: int) -> None:
    model = mtt.load(MODEL, input="Se:v,Se:tl", output="Df:speed")
    module = model.estimator()
    found = {"measured": [], "voltage alone": []}
    for seed in range(seeds):
        t, U, Y = record(model, 1, seed)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            both = module.fit_signals(t, U, Y, hold="zoh")
            alone = module.fit(t, U[:, 0], Y[:, 0], hold="zoh")
        found["measured"].append((both.k, both.k_se))
        found["voltage alone"].append((alone.k, alone.k_se))
    print(f"\nDC motor, jl = {TRUTH:g}, two PRBS inputs, speed at {SNR_DB:g} dB, {seeds} seeds")
    print("| fit | bias | median bias | std | IQR / 1.349 | median k_se | k_se / std | covers |")
    print("|---|---|---|---|---|---|---|---|")
    for label, pairs in found.items():
        k, se = (np.array(values) for values in zip(*pairs, strict=True))
        print(row(label, k, se))


def speed(repeats: int) -> None:
    both = mtt.load(MODEL, input="Se:v,Se:tl", output="Df:speed,Df:current")
    one = mtt.load(MODEL, input="Se:v", output="Df:speed")
    mimo, siso = both.estimator(), one.estimator()
    times = {"2 x 2": [], "1 x 1": []}
    for seed in range(repeats):
        t, U, Y = record(both, 2, 1000 + seed)
        rng = np.random.default_rng(seed)
        G = one.to_scipy(TRUTH)
        y = signal.lsim(G, U[:, 0], t, interp=False)[1]
        y = y + rng.standard_normal(y.size) * y.std() / 10
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            start = time.perf_counter()
            mimo.fit_signals(t, U, Y, hold="zoh")
            times["2 x 2"].append(time.perf_counter() - start)
            start = time.perf_counter()
            siso.fit(t, U[:, 0], y, hold="zoh")
            times["1 x 1"].append(time.perf_counter() - start)
    two, single = (float(np.median(times[key])) for key in ("2 x 2", "1 x 1"))
    print(f"\nspeed, {int(SPAN / DT)} samples, {repeats} records, wall seconds (median)")
    print("| fit | seconds | throughput per sample vs single channel |\n|---|---|---|")
    print(f"| fit, Se:v -> Df:speed | {single:.3g} | 1 |")
    print(f"| fit_signals, 2 inputs x 2 outputs | {two:.3g} | {single / two:.2f} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=60)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--only", choices=("calibration", "speed"))
    args = parser.parse_args()
    if args.only != "speed":
        calibration(args.seeds)
    if args.only != "calibration":
        speed(args.repeats)


if __name__ == "__main__":
    main()
