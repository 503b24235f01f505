"""Monte Carlo figures of the batch fit (`fit`) on noisy data, against the plain least-squares
fit and the output-error peer (bench/output_error_peer.py), all on the same records.

The records are made here, independently of the generated modules: the transfer functions
of method.md (written out below, not taken from the modules), a PRBS from
scipy.signal.max_len_seq held between switches, scipy.signal.lsim with a zero-order hold
(exact for it), and white Gaussian noise on the output samples at a signal-to-noise ratio
(signal variance over noise variance). `fit` is told the input was held (hold="zoh"), as
the experiment was made; everything else is its default (method="pem", noise="auto",
C="auto", offset and initial state estimated; several unknowns: the global search within
the default box, the model file's values within a factor of 10). The DC motor (ra, jl)
and the series RLC circuit (r, l, c) of issue 11 have a row per unknown.

The reference is the output-error peer: G(s, k) from the module's `transfer_function`,
discretised exactly for the zero-order hold, one lfilter recursion per pole, the offset and
initial state projected out (as `fit` estimates them), scipy.optimize.least_squares over k
within `fit`'s default box for several unknowns (one unknown: unbounded), started from the
model file's value (here the true value: the peer's most favourable start). Its simulation
is checked against the module's `simulate` to 1e-10 on each model before the runs.

Times are this process's CPU time with BLAS on one thread (see bench/estimate.py).

    .venv/bin/python bench/montecarlo.py             # 100 seeds per row: a few minutes
    .venv/bin/python bench/montecarlo.py --seeds 50  # the issue's minimum
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # before numpy loads OpenBLAS

import argparse  # noqa: E402
import math  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402
from dataclasses import dataclass  # noqa: E402

import numpy as np  # noqa: E402
import output_error_peer as peer  # noqa: E402
from _generated import generated  # noqa: E402
from scipy import signal  # noqa: E402


def dc_drive_tf(k: float):
    """G(s) = 10 (k s^2 + 1) / ((s^3 + 10 s^2 + 11 s + 10) k s + s^2 + 10 s + 10)."""
    return [10 * k, 0, 10], np.polyadd(k * np.array([1, 10, 11, 10, 0]), [1, 10, 10])


def absorber_tf(k: float, tau: float = 2.0, flow: float = 0.5):
    """G(s) = k^3 / (l [(k + s tau + 1)(3 s tau + 1) k + (s tau + 1)^3 + k^3]), l = flow."""
    first = np.polymul([tau, k + 1], [3 * tau, 1]) * k
    cube = np.polymul(np.polymul([tau, 1], [tau, 1]), [tau, 1])
    return [k**3], flow * np.polyadd(np.polyadd(first, cube), [k**3])


def dc_motor_tf(k):
    """G(s) = km / ((la s + ra)((jm + jl) s + b) + km^2), la = 1/10, km = jm = 1, b = 1/10."""
    ra, jl = k
    return [1.0], np.polyadd(np.polymul([0.1, ra], [1 + jl, 0.1]), [1.0])


def rlc3_tf(k):
    """G(s) = c s / (l c s^2 + r c s + 1): the current of a series RLC circuit."""
    r, inductance, c = k
    return [c, 0.0], [inductance * c, r * c, 1.0]


@dataclass(frozen=True)
class Experiment:
    name: str  # the generated module
    k: float | tuple[float, ...]  # several unknowns: in the module's UNKNOWNS order
    tf: object
    t_end: float
    dt: float
    hold: float  # the PRBS's time between possible switches

    def times(self) -> np.ndarray:
        return self.dt * np.arange(round(self.t_end / self.dt) + 1)

    def record(self, seed: int, snr_db: float | None):
        t = self.times()
        u = prbs(t, self.hold, seed)
        clean = signal.lsim(self.tf(self.k), u, t, interp=False)[1]
        if snr_db is None:
            return t, u, clean
        noise = math.sqrt(np.var(clean) / 10 ** (snr_db / 10))
        return t, u, clean + noise * np.random.default_rng(10_000 + seed).standard_normal(t.size)


def prbs(t: np.ndarray, hold: float, seed: int) -> np.ndarray:
    """+-1, a maximum-length sequence switching at multiples of `hold`, its state seeded."""
    count = int(math.ceil((t[-1] - t[0]) / hold)) + 1
    bits = max(4, math.ceil(math.log2(count + 1)))
    state = np.random.default_rng(seed).integers(0, 2, bits)
    state[0] = 1 if not state.any() else state[0]
    sequence = signal.max_len_seq(bits, state=state, length=count)[0]
    return 2.0 * sequence[np.floor((t - t[0]) / hold + 1e-9).astype(int)] - 1.0


EXPERIMENTS = {
    "dc_drive": Experiment("dc_drive", 10.0, dc_drive_tf, 400.0, 0.02, 1.0),
    "absorber": Experiment("absorber", 0.72, absorber_tf, 40.0, 0.01, 2.0),
    "dc_motor": Experiment("dc_motor", (1.0, 10.0), dc_motor_tf, 60.0, 0.01, 0.5),
    "rlc3": Experiment("rlc3", (2.0, 0.5, 0.1), rlc3_tf, 10.0, 0.002, 0.2),
}


def output_error(module, t, u, y) -> np.ndarray:
    """The reference: the output-error peer with `fit`'s nuisances and default box, from the
    model file's value."""
    k0 = module.TRUE_VALUE
    box = None if np.ndim(k0) == 0 else [(v / module.DEFAULT_RANGE, v * module.DEFAULT_RANGE)
                                         for v in k0]  # fmt: skip
    return np.atleast_1d(peer.fit(module, t, u, y, k0=k0, bounds=box, hold="zoh").k)


def monte_carlo(module, experiment: Experiment, snr_db: float, seeds: int, reference: int):
    rows = {"pem": [], "iv": [], "ls": []}
    times = {"pem": [], "iv": [], "ls": [], "oe": []}
    oe = []  # several unknowns: a row each
    t, u, _ = experiment.record(0, None)
    peer.check(module, t, u, experiment.k, hold="zoh")  # the reference simulates exactly
    for seed in range(seeds):
        t, u, y = experiment.record(seed, snr_db)
        for method in rows:
            start = time.process_time()
            result = module.fit(t, u, y, hold="zoh", method=method)
            times[method].append(time.process_time() - start)
            ci = np.reshape(result.ci, (-1, 2))
            rows[method].append(np.stack([np.atleast_1d(result.k), np.atleast_1d(result.k_se),
                                          ci[:, 0], ci[:, 1]]))  # fmt: skip
        if seed < reference:
            start = time.process_time()
            oe.append(output_error(module, t, u, y))
            times["oe"].append(time.process_time() - start)
    oe = np.reshape(oe, (len(oe), -1)) if oe else np.zeros((0, np.size(experiment.k)))
    return {m: np.array(v) for m, v in rows.items()}, times, oe


def table(rows: list[list[str]]) -> str:
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
    lines = [
        "| " + " | ".join(c.ljust(w) for c, w in zip(row, widths, strict=True)) + " |"
        for row in rows
    ]
    lines.insert(1, "|" + "|".join("-" * (w + 2) for w in widths) + "|")
    return "\n".join(lines)


def noise_rows(seeds: int, reference: int, names=tuple(EXPERIMENTS)) -> list[list[str]]:
    header = [
        "record",
        "SNR",
        "method",
        "bias",
        "std",
        "k_se / std",
        "95 % CI covers",
        "time per fit",
    ]
    rows = [header]
    for name in names:
        experiment = EXPERIMENTS[name]
        module = generated(name)
        truths = np.atleast_1d(experiment.k)
        record = (
            f"{name} (PRBS {experiment.hold:g} s, {experiment.t_end:g} s, dt {experiment.dt:g})"
        )
        for snr in (20.0, 10.0):
            results, times, oe = monte_carlo(module, experiment, snr, seeds, reference)
            for i, (unknown, truth) in enumerate(zip(module.UNKNOWNS, truths, strict=True)):
                label = record if truths.size == 1 else f"{record}: {unknown} = {truth:g}"
                for method, r in results.items():
                    k, se, lo, hi = r[:, :, i].T
                    std = k.std(ddof=1)
                    covered = np.mean((lo <= truth) & (truth <= hi))
                    rows.append([
                        label, f"{snr:g} dB", f"fit, method={method!r}",
                        f"{100 * (k.mean() / truth - 1):+.3f} %", f"{100 * std / truth:.3f} %",
                        f"{se.mean() / std:.2f}", f"{100 * covered:.0f} %",
                        f"{1e3 * np.median(times[method]):.0f} ms",
                    ])  # fmt: skip
                if oe.size:
                    rows.append([
                        label, f"{snr:g} dB", f"output-error peer ({len(oe)} seeds)",
                        f"{100 * (oe[:, i].mean() / truth - 1):+.3f} %",
                        f"{100 * oe[:, i].std(ddof=1) / truth:.3f} %", "", "",
                        f"{1e3 * np.median(times['oe']):.0f} ms",
                    ])  # fmt: skip
            print(f"  {name} at {snr:g} dB done", file=sys.stderr)
    return rows


def nuisance_rows() -> list[list[str]]:
    """A 1 % output offset (of the output's peak) plus a non-zero initial state, noise-free."""
    rows = [
        [
            "record",
            "initial state",
            "offset",
            "fit (defaults)",
            "error",
            "fit, offset=False, initial_state=False",
        ]
    ]
    for name in ("dc_drive", "absorber"):
        experiment = EXPERIMENTS[name]
        module = generated(name)
        t = experiment.times()
        u = prbs(t, experiment.hold, 3)
        system = signal.StateSpace(*signal.tf2ss(*experiment.tf(experiment.k)))
        x0 = np.random.default_rng(5).standard_normal(system.A.shape[0])
        y = signal.lsim(system, u, t, X0=x0, interp=False)[1]
        y = y + 0.01 * np.abs(y).max()
        result = module.fit(t, u, y, hold="zoh")
        plain = module.fit(t, u, y, hold="zoh", offset=False, initial_state=False)
        error = f"{100 * (result.k / experiment.k - 1):+.2e} %"
        rows.append([name, "random (seed 5)", "1 % of max abs(y)", f"{result.k:.6g}", error,
                     f"{plain.k:.6g}"])  # fmt: skip
    return rows


def speed_rows(repeats: int = 5) -> list[list[str]]:
    rows = [["record", "samples", "method", "median time", "iterations"]]
    module = generated("dc_drive")
    experiment = Experiment("dc_drive", 10.0, dc_drive_tf, 2000.0, 0.02, 1.0)
    t, u, y = experiment.record(0, 10.0)
    for method in ("pem", "iv", "ls"):
        spent = []
        for _ in range(repeats):
            start = time.process_time()
            result = module.fit(t, u, y, hold="zoh", method=method)
            spent.append(time.process_time() - start)
        rows.append(["dc_drive, PRBS, 10 dB", f"{t.size:.0e}", method, f"{np.median(spent):.2f} s",
                     str(result.iterations)])  # fmt: skip
    return rows


def degenerate_rows() -> list[list[str]]:
    """Records that carry no usable information: what `fit` and `estimate` say of each."""
    module = generated("dc_drive")
    t = np.linspace(0.0, 10.0, 1001)
    step = np.ones_like(t)
    y = module.simulate(t, step, 10.0)
    cases = {
        "constant input (a step from rest)": (t, step, y),
        "all-zero input and output": (t, 0 * t, 0 * t),
        "3 samples": (t[:3], step[:3], y[:3]),
        "3 samples, offset=False, initial_state=False": (t[:3], step[:3], y[:3]),
        "times scaled by 1e-300": (t * 1e-300, step, y),
    }
    rows = [["record", "fit", "estimate, k0 = 5"]]
    for label, (tt, uu, yy) in cases.items():
        options = {"offset": False, "initial_state": False} if "False" in label else {}
        outcomes = []
        calls = [(module.fit, options)]
        calls += [] if options else [(module.estimate, {"k0": 5.0})]
        for function, arguments in calls:
            try:
                result = function(tt, uu, yy, **arguments)
                said = "; ".join(result.warnings) or "-"
                outcomes.append(f"ok={result.ok}, k={result.k:.4g}; warnings: {said}")
            except ValueError as error:
                outcomes.append(f"ValueError: {error}")
        outcomes += ["(as above)"] * (2 - len(outcomes))
        rows.append([label, *outcomes])
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=100)
    parser.add_argument("--reference", type=int, default=20, help="seeds for the output-error peer")
    parser.add_argument("--models", default=",".join(EXPERIMENTS),
                        help=f"the records' models (default {','.join(EXPERIMENTS)})")  # fmt: skip
    parser.add_argument("--noise-only", action="store_true", help="the noise table alone")
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    print(f"Monte Carlo, {args.seeds} seeds per row:\n")
    print(table(noise_rows(args.seeds, args.reference, tuple(args.models.split(",")))))
    if args.noise_only:
        return
    print("\nOffset and initial state, noise-free:\n")
    print(table(nuisance_rows()))
    print("\nSpeed:\n")
    print(table(speed_rows()))
    print("\nRecords without usable information:\n")
    print(table(degenerate_rows()))


if __name__ == "__main__":
    main()
