"""Records for the batch tests: small DC-drive logs as CSV files, one of them corrupt.

Each record is the DC drive (k = 10) driven by its own PRBS with output noise at 20 dB;
records are short (801 samples) so that a fit takes milliseconds.
"""

from __future__ import annotations

import os
import signal
import warnings
from pathlib import Path

import numpy as np
import pytest

from mtt.batch import worker

CORRUPT = "run_07.csv"
COUNT = 12


def simulated(module, seed: int, samples: int = 801):
    t = np.linspace(0.0, 0.05 * (samples - 1), samples)
    u = module.input_signal("prbs", t, period=1.0, seed=seed)
    y = module.with_noise(module.simulate(t, u, 10.0, hold="zoh"), 20.0, seed=seed)
    return t, u, y


def write(path: Path, t, u, y) -> None:
    np.savetxt(path, np.c_[t, u, y], delimiter=",", header="t,u,y", comments="", fmt="%.17g")


@pytest.fixture(scope="module")
def logs(dc_drive, tmp_path_factory) -> Path:
    """COUNT CSV logs run_00.csv.., written out of order; CORRUPT has text on line 18."""
    folder = tmp_path_factory.mktemp("logs")
    for seed in reversed(range(COUNT)):
        write(folder / f"run_{seed:02d}.csv", *simulated(dc_drive, seed))
    lines = (folder / CORRUPT).read_text().splitlines()
    lines[17] = lines[17].rsplit(",", 1)[0] + ",oops"
    (folder / CORRUPT).write_text("\n".join(lines) + "\n")
    return folder


def direct_fits(module, paths, **options) -> dict:
    """The module's own fit of each readable record, here, BLAS on one thread."""
    out = {}
    with warnings.catch_warnings(), worker.one_thread(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        for path in paths:
            try:
                out[str(path)] = module.fit(*module.read_csv(path), **options)
            except ValueError:
                continue
    return out


def same_numbers(a, b) -> bool:
    """Bitwise: k, k_se and fit_percent (NaN equals NaN)."""
    return (
        all(
            np.array_equal(getattr(a, name), getattr(b, name), equal_nan=True)
            for name in ("k", "k_se", "fit_percent", "residual_rms")
        )
        and a.warnings == b.warnings
    )


def kill(pid: int) -> None:
    os.kill(pid, signal.SIGKILL)
