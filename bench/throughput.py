"""Samples per second of the generated modules' simulate, fit and Tracker (issue 8).

Records are regular (0.001 s apart), with a square-wave input and, for fit and the
Tracker, output noise uniform in +-0.01 (DC drive) or +-0.02 (absorber). Each figure is
the median of several runs, in this process's CPU time (BLAS on one thread: see
bench/estimate.py). fit's peak memory is measured in a fresh interpreter: the peak of
numpy's allocations during the call (tracemalloc, which numpy reports to), and the
process's peak resident size (everything: the interpreter, numpy, scipy, the data).

    .venv/bin/python bench/throughput.py
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # before numpy loads OpenBLAS

import json  # noqa: E402
import statistics  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402

import numpy as np  # noqa: E402
from _generated import ROOT, generated  # noqa: E402

TARGETS = {"simulate": 1e7, "fit, least squares, uncertainty=False": 5e6, "fit (defaults)": 1e5,
           "Tracker, one sample at a time": 2e4, "Tracker, chunks of 1000": 1e6}  # fmt: skip
# issue 8's fit: the global minimiser of the paper's least-squares cost J, the estimate alone
ALONE = dict(method="ls", C=None, offset=False, initial_state=False, uncertainty=False)


def record(module, k: float, samples: int, noise: float, seed: int = 0):
    t = 0.001 * np.arange(samples + 1)
    u = np.where((t // 20) % 2 == 0, 1.0, -1.0)
    y = module.simulate(t, u, k) + np.random.default_rng(seed).uniform(-noise, noise, t.size)
    return t, u, y


def rate(function, samples: int, repeat: int = 5) -> float:
    """Median samples per second of `repeat` calls."""
    times = []
    for _ in range(repeat):
        start = time.process_time()
        function()
        times.append(time.process_time() - start)
    return samples / statistics.median(times)


def one_at_a_time(module, t, u, y, k0: float) -> None:
    tracker = module.Tracker(k0=k0)
    for sample in zip(t.tolist(), u.tolist(), y.tolist(), strict=True):
        tracker.update(*sample)


def in_chunks(module, t, u, y, k0: float, size: int = 1000) -> None:
    tracker = module.Tracker(k0=k0)
    for lo in range(0, t.size, size):
        tracker.update(t[lo : lo + size], u[lo : lo + size], y[lo : lo + size])


MEMORY = """
import json, resource, sys, tracemalloc
sys.path.insert(0, {generated!r})
import numpy as np
import dc_drive, warnings
warnings.simplefilter("ignore", UserWarning)
t = 0.001 * np.arange(10**6 + 1)
u = np.where((t // 20) % 2 == 0, 1.0, -1.0)
y = dc_drive.simulate(t, u, 10.0) + np.random.default_rng(0).uniform(-0.01, 0.01, t.size)
tracemalloc.start()
dc_drive.fit(t, u, y)
peak = tracemalloc.get_traced_memory()[1]
print(json.dumps(dict(fit=peak, process=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)))
"""


def main() -> None:
    warnings.simplefilter("ignore", UserWarning)  # the fits' advice (EstimationWarning)
    dc, absorber = generated("dc_drive"), generated("absorber")
    rows = []
    t, u, y = record(dc, 10.0, 10**6, 0.0)
    rows.append(
        ("simulate", "DC drive, 1e6 samples", rate(lambda: dc.simulate(t, u, 10.0), t.size))
    )
    for module, name, k, noise in (
        (dc, "DC drive", 10.0, 0.01),
        (absorber, "absorber", 0.72, 0.02),
    ):
        t, u, y = record(module, k, 10**6, noise)
        alone = rate(lambda m=module, t=t, u=u, y=y: m.fit(t, u, y, **ALONE), t.size)
        rows.append(("fit, least squares, uncertainty=False", f"{name}, 1e6 samples", alone))
        whole = rate(lambda m=module, t=t, u=u, y=y: m.fit(t, u, y), t.size)  # IV, uncertainty
        rows.append(("fit (defaults)", f"{name}, 1e6 samples", whole))
    for module, name, k, noise, k0 in ((dc, "DC drive", 10.0, 0.01, 5.0),
                                       (absorber, "absorber", 0.72, 0.02, 1.0)):  # fmt: skip
        data = record(module, k, 2 * 10**5, noise)
        first = tuple(signal[:5000] for signal in data)
        single = rate(lambda m=module, k0=k0, first=first: one_at_a_time(m, *first, k0), 5000)
        rows.append(("Tracker, one sample at a time", f"{name}, 5000 samples", single))
        chunks = rate(lambda m=module, k0=k0, data=data: in_chunks(m, *data, k0), data[0].size)
        rows.append(("Tracker, chunks of 1000", f"{name}, 2e5 samples", chunks))
    print("| function | record | samples/s (median of 5) | target | met |")
    print("|---|---|---|---|---|")
    for function, what, value in rows:
        target = TARGETS[function]
        met = "yes" if value >= target else "no"
        print(f"| {function} | {what} | {value:,.0f} | {target:,.0f} | {met} |")
    program = MEMORY.format(generated=str(ROOT / "generated"))
    done = subprocess.run(
        [sys.executable, "-c", program], capture_output=True, text=True, check=True
    )
    memory = json.loads(done.stdout)
    print(f"\nfit, 1e6 samples: peak of numpy's allocations during the call "
          f"{memory['fit'] / 2**20:.0f} MiB; peak resident size of the whole process "
          f"{memory['process'] / 2**10:.0f} MiB (target: under 1 GiB)")  # fmt: skip


if __name__ == "__main__":
    main()
