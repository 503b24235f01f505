"""Validation on held-out records (issue 18): `Fit.compare` against the truth, over seeds.

Per seed, the records are made here, independently of the generated modules (bench/
montecarlo.py's transfer functions written out, its PRBS, scipy.signal.lsim with a
zero-order hold, white Gaussian noise at the SNR):

- an estimation record from rest, fitted by the module's `fit` with its defaults
  (hold="zoh", offset and initial state estimated);
- a held-out record of the same system: the second half of a run twice as long (so it
  starts wherever the first half left the system, never at rest), an output offset drawn
  in [-0.5, 0.5] of the output's standard deviation, its own PRBS and noise.

Against each other: `compare`'s fit % (the held-out record's initial state and offset
estimated by least squares), and the fit % of the fitted model simulated with the true
initial state (run over the whole input history) and the true offset: the figure one would
get knowing them. Also the fit % simulated from rest at the estimation record's operating
point (`Fit.simulate(t, u)`), what validation without estimating the initial state gives.
Target: |compare - true| < 1 point on every seed.

    .venv/bin/python bench/validation.py [--seeds 60]
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # before numpy loads OpenBLAS

import argparse  # noqa: E402
import math  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402

import numpy as np  # noqa: E402
from _generated import generated  # noqa: E402
from montecarlo import EXPERIMENTS, Experiment, prbs, table  # noqa: E402
from scipy import signal  # noqa: E402


def percent(y: np.ndarray, model: np.ndarray) -> float:
    return 100.0 * (1.0 - np.linalg.norm(y - model) / np.linalg.norm(y - y.mean()))


def noisy(clean: np.ndarray, snr_db: float, rng: np.random.Generator) -> np.ndarray:
    return clean + math.sqrt(np.var(clean) / 10 ** (snr_db / 10)) * rng.standard_normal(clean.size)


def one_seed(module, experiment: Experiment, snr_db: float, seed: int):
    """(compare's fit %, the true-initial-state fit %, from-rest fit %, seconds to compare)."""
    rng = np.random.default_rng(50_000 + seed)
    t = experiment.times()
    u = prbs(t, experiment.hold, seed)
    G = experiment.tf(experiment.k)
    y = noisy(signal.lsim(G, u, t, interp=False)[1], snr_db, rng)
    found = module.fit(t, u, y, hold="zoh")
    whole = experiment.dt * np.arange(2 * t.size - 1)  # twice as long; the second half held out
    history = prbs(whole, experiment.hold, 1000 + seed)
    clean = signal.lsim(G, history, whole, interp=False)[1]
    offset = rng.uniform(-0.5, 0.5) * np.std(clean)
    held = slice(t.size - 1, None)
    tv, uv = whole[held], history[held]
    yv = noisy(clean[held], snr_db, rng) + offset
    start = time.process_time()
    compared = found.compare(tv, uv, yv)
    spent = time.process_time() - start
    truth = module.simulate(whole, history, found.k, hold="zoh")[held] + offset
    rest = found.simulate(tv, uv)
    return compared.fit_percent, percent(yv, truth), percent(yv, rest), spent


SYSTEMS = {
    **EXPERIMENTS,
    # a short record: the initial state's response is a large part of what is held out
    "dc_drive_short": Experiment("dc_drive", 10.0, EXPERIMENTS["dc_drive"].tf, 20.0, 0.02, 1.0),
}


def rows(seeds: int, names) -> list[list[str]]:
    header = ["held-out record", "SNR", "compare fit % (mean)", "true-state fit % (mean)",
              "|difference|: mean", "max", "within 1 point", "from rest (mean)",
              "compare's time"]  # fmt: skip
    out = [header]
    for name in names:
        experiment = SYSTEMS[name]
        module = generated(experiment.name)
        label = (f"{experiment.name} (PRBS {experiment.hold:g} s, {experiment.t_end:g} s, dt "
                 f"{experiment.dt:g}; {experiment.t_end:g} s held out)")  # fmt: skip
        for snr in (20.0, 10.0):
            found = np.array([one_seed(module, experiment, snr, seed) for seed in range(seeds)])
            difference = np.abs(found[:, 0] - found[:, 1])
            out.append([
                label, f"{snr:g} dB", f"{found[:, 0].mean():.2f}", f"{found[:, 1].mean():.2f}",
                f"{difference.mean():.3f}", f"{difference.max():.3f}",
                f"{np.mean(difference < 1.0) * 100:.0f} %", f"{found[:, 2].mean():.1f}",
                f"{1e3 * np.median(found[:, 3]):.1f} ms",
            ])  # fmt: skip
            print(f"  {name} at {snr:g} dB done", file=sys.stderr)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=60, help="records per row (60)")
    parser.add_argument("--models", default="dc_drive,dc_drive_short,absorber",
                        help="the systems (default dc_drive,dc_drive_short,absorber)")  # fmt: skip
    args = parser.parse_args()
    warnings.simplefilter("ignore")  # the fits' advice (EstimationWarning)
    print(f"Validation on held-out records, {args.seeds} seeds per row:\n")
    print(table(rows(args.seeds, args.models.split(","))))


if __name__ == "__main__":
    main()
