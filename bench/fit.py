"""fit against output-error least squares on noisy DC-drive records (issue 8).

The record: the DC drive (k = 10) driven by a unit step, 10 s sampled every 0.001 s (10^4
samples), output noise uniform in +-0.01, one record per seed. The reference is the
output-error peer (bench/output_error_peer.py: G(s, k) discretised exactly by the matrix
exponential, one lfilter recursion per pole, scipy.optimize.least_squares over k, started
at k = 5), told like the fits that the record starts at rest without offset; it is the
least-squares estimate of the output error, the maximum-likelihood one for Gaussian noise.
Its simulation is checked against the module's `simulate` (to 1e-10) before anything is
timed. Against it: the generated module's `fit` (no starting value), by its default
(method="pem": the exact prediction error from the paper's global least-squares minimiser)
and by least squares (the global minimiser of the filtered equation-error cost,
C(s) = (1 + s)^5, beta = 0), both told the record starts
at rest without offset, each with its uncertainty and validation and without
(`uncertainty=False`: the estimate alone, issue 8's fit), and its `estimate` (the paper's
algorithm from k0 = 5, beta = 0.1, S0 = 1e-4).

Times are medians over the seeds, in this process's CPU time (BLAS on one thread: see
bench/estimate.py); errors are the root mean square of k - 10 over the seeds.

    .venv/bin/python bench/fit.py [--seeds 20]
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # before numpy loads OpenBLAS

import argparse  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402

import numpy as np  # noqa: E402
import output_error_peer as peer  # noqa: E402
from _generated import generated  # noqa: E402

REFERENCE = "output-error peer (bench/output_error_peer.py)"
AT_REST = dict(offset=False, initial_state=False)  # the step starts the record from rest


def main() -> None:
    warnings.simplefilter("ignore", UserWarning)  # the fits' advice (EstimationWarning)
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=20, help="records (20)")
    args = parser.parse_args()
    dc = generated("dc_drive")
    t = 0.001 * np.arange(10**4 + 1)
    u = np.ones_like(t)
    clean = dc.simulate(t, u, 10.0)
    peer.check(dc, t, u, 10.0, hold="linear")
    methods = {
        REFERENCE: lambda y: peer.fit(dc, t, u, y, k0=5.0, **AT_REST).k,
        "fit (defaults: method='pem')": lambda y: dc.fit(t, u, y, **AT_REST).k,
        "fit, method='ls'": lambda y: dc.fit(t, u, y, method="ls", C=None, **AT_REST).k,
        "fit, uncertainty=False": lambda y: dc.fit(t, u, y, uncertainty=False, **AT_REST).k,
        "fit, method='ls', uncertainty=False": lambda y: (
            dc.fit(t, u, y, method="ls", C=None, uncertainty=False, **AT_REST).k
        ),
        "estimate (k0 = 5)": lambda y: dc.estimate(t, u, y, k0=5.0).k,
    }
    times = {name: [] for name in methods}
    errors = {name: [] for name in methods}
    for seed in range(args.seeds):
        y = clean + np.random.default_rng(seed).uniform(-0.01, 0.01, t.size)
        for name, method in methods.items():
            start = time.process_time()
            k = method(y)
            times[name].append(time.process_time() - start)
            errors[name].append(k - 10.0)
    baseline = statistics.median(times[REFERENCE])
    print(f"| method | median time | peer's time / time | rms error of k ({args.seeds} "
          "seeds) |")  # fmt: skip
    print("|---|---|---|---|")
    for name in methods:
        median = statistics.median(times[name])
        rms = float(np.sqrt(np.mean(np.square(errors[name]))))
        print(f"| {name} | {median * 1e3:.2f} ms | {baseline / median:.1f}x | {rms:.2e} |")


if __name__ == "__main__":
    main()
