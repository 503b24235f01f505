"""Issue 18's targets for the exact fit (`fit`'s default, method="pem"): exactness on short
noise-free records, calibration under white and coloured noise, and speed against the
output-error peer, all on records made here, independently of the generated modules.

The records: the transfer functions of method.md written out (bench/montecarlo.py), a
PRBS held between switches (or a piecewise-linear input) simulated by scipy.signal.lsim
(interp=False for a held input, True for a piecewise-linear one: exact for each), from a
random initial state of scipy's tf2ss realisation where the row says so, plus an output
offset; output noise white Gaussian, AR(1) with its pole at 0.9, or ARMA(2,1) with
D(q) = 1 - 1.5 q^-1 + 0.7 q^-2 (poles 0.75 +- 0.37i) and C(q) = 1 + 0.5 q^-1, at a
signal-to-noise ratio (the clean output's variance over the noise's). `fit` is told the
hold and nothing else (noise "auto", offset and initial state estimated). "k_se / std" is
the mean standard error over the spread of the estimates; "covers" the share of 95 %
intervals that hold the truth. Times: this process's CPU time, BLAS on one thread; the
speed rows interleave `fit` and the peer (bench/output_error_peer.py, started at the
model file's values, the reference of issue 18) and give the ratio of their medians; the
"first" rows time each record's first fit and the peer in fresh interpreters (the code
warmed on another record), which the tables a fit keeps for the next one do not help.

    .venv/bin/python bench/exact.py --seeds 60           # every table (about 15 minutes)
    .venv/bin/python bench/exact.py --seeds 8 --only short,coloured
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # before numpy loads OpenBLAS

import argparse  # noqa: E402
import math  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402

import numpy as np  # noqa: E402
import output_error_peer as peer  # noqa: E402
from _generated import generated  # noqa: E402
from montecarlo import absorber_tf, dc_drive_tf, dc_motor_tf, prbs, table  # noqa: E402
from scipy import signal  # noqa: E402

NOISES = {  # (D, C) of v = C(q)/D(q) e
    "white": ([1.0], [1.0]),
    "AR(1), pole 0.9": ([1.0, -0.9], [1.0]),
    "ARMA(2,1)": ([1.0, -1.5, 0.7], [1.0, 0.5]),
}


def simulate(tf, k, t, u, hold: str, x0=None) -> np.ndarray:
    system = signal.StateSpace(*signal.tf2ss(*tf(k)))
    return signal.lsim(system, u, t, X0=x0, interp=hold == "linear")[1]


def noisy(clean: np.ndarray, snr_db: float, noise: str, seed: int) -> np.ndarray:
    D, C = NOISES[noise]
    v = signal.lfilter(C, D, np.random.default_rng(10_000 + seed).standard_normal(clean.size))
    return clean + v * math.sqrt(np.var(clean) / 10 ** (snr_db / 10) / np.var(v))


def summary(k: np.ndarray, se: np.ndarray, truth: float) -> list[str]:
    std = k.std(ddof=1)
    covers = np.mean(np.abs(k - truth) <= 1.959963984540054 * se)
    return [f"{100 * (k.mean() / truth - 1):+.3f} %", f"{100 * std / truth:.3f} %",
            f"{se.mean() / std:.2f}", f"{100 * covers:.0f} %"]  # fmt: skip


def short_rows(seeds: int) -> list[list[str]]:
    """Noise-free DC drive, 3 s, PRBS held 0.2 s (or piecewise linear, hold linear), a random
    initial state and offset per seed: the largest error of k over the seeds."""
    module = generated("dc_drive")
    rows = [["record (noise-free, 3 s)", "hold", "dt", "method", "largest |k/10 - 1|",
             "median", "ok", "time per fit"]]  # fmt: skip
    for hold in ("zoh", "linear"):
        for dt in (0.01, 0.02):
            t = dt * np.arange(round(3.0 / dt) + 1)
            errors, oks, spent = {"pem": [], "iv": []}, {"pem": 0, "iv": 0}, {"pem": [], "iv": []}
            for seed in range(seeds):
                rng = np.random.default_rng(seed)
                if hold == "zoh":
                    u = prbs(t, 0.2, seed)
                else:  # piecewise linear between knots 0.2 s apart
                    knots = t[:: round(0.2 / dt)]
                    u = np.interp(t, knots, rng.standard_normal(knots.size))
                y = simulate(dc_drive_tf, 10.0, t, u, hold, rng.standard_normal(4))
                y = y + rng.uniform(-1, 1)
                for method in errors:
                    start = time.process_time()
                    result = module.fit(t, u, y, hold=hold, method=method)
                    spent[method].append(time.process_time() - start)
                    errors[method].append(abs(result.k / 10.0 - 1))
                    oks[method] += result.ok
            label = "PRBS held 0.2 s" if hold == "zoh" else "piecewise linear, knots 0.2 s"
            for method in errors:
                rows.append([label, hold, f"{dt:g}", method, f"{max(errors[method]):.1e}",
                             f"{np.median(errors[method]):.1e}", f"{oks[method]}/{seeds}",
                             f"{1e3 * np.median(spent[method]):.0f} ms"])  # fmt: skip
    return rows


def calibration(module, tf, truth, t, hold_period, snr, noise, seeds, methods, known, x0=False):
    """{method: (k, se, oks, noise kinds, times)} over the seeds."""
    found = {m: ([], [], 0, {}, []) for m in methods}
    for seed in range(seeds):
        rng = np.random.default_rng(seed)
        u = prbs(t, hold_period, seed)
        order = len(tf(truth)[1]) - 1
        clean = simulate(tf, truth, t, u, "zoh", rng.standard_normal(order) if x0 else None)
        y = noisy(clean + (rng.uniform(-1, 1) if x0 else 0.0), snr, noise, seed)
        for method, options in methods.items():
            start = time.process_time()
            result = module.fit(t, u, y, hold="zoh", **options, **known)
            ks, ses, oks, kinds, spent = found[method]
            spent.append(time.process_time() - start)
            ks.append(result.k)
            ses.append(result.k_se)
            kind = "-" if result.noise is None else result.noise.kind
            kinds[kind] = kinds.get(kind, 0) + 1
            found[method] = (ks, ses, oks + result.ok, kinds, spent)
    return found


def calibration_rows(title, cases, seeds) -> list[list[str]]:
    rows = [[title, "noise", "SNR", "method", "bias", "std", "k_se / std", "95 % CI covers",
             "ok", "noise models chosen", "time per fit"]]  # fmt: skip
    for label, name, tf, truth, t, period, snr, noise, methods, known, x0 in cases:
        module = generated(name)
        found = calibration(module, tf, truth, t, period, snr, noise, seeds, methods, known, x0)
        for method, (ks, ses, oks, kinds, spent) in found.items():
            chosen = ", ".join(f"{kind} {count}" for kind, count in sorted(kinds.items()))
            rows.append([label, noise, f"{snr:g} dB", method,
                         *summary(np.array(ks), np.array(ses), truth), f"{oks}/{seeds}", chosen,
                         f"{1e3 * np.median(spent):.0f} ms"])  # fmt: skip
        print(f"  {label}, {noise} done", file=sys.stderr)
    return rows


def dc10_rows(seeds: int) -> list[list[str]]:
    """Issue 18's record: from rest, no offset (both estimated), as `mtt fit --signal prbs
    --period 0.2 --t-end 10 --dt 0.01 --noise-snr 20` makes it."""
    t = 0.01 * np.arange(1001)
    methods = {"fit (pem, defaults)": {}, "fit, method='iv'": {"method": "iv"}}
    case = ("DC drive, 10 s, PRBS 0.2 s, dt 0.01", "dc_drive", dc_drive_tf, 10.0, t, 0.2, 20.0,
            "white", methods, {}, False)  # fmt: skip
    return calibration_rows("record", [case], seeds)


def coloured_rows(seeds: int) -> list[list[str]]:
    dc = 0.02 * np.arange(20001)
    absorber = 0.01 * np.arange(4001)
    methods = {"fit (pem, noise auto)": {}, "fit, noise='white'": {"noise": "white"},
               "fit, method='iv'": {"method": "iv"}}  # fmt: skip
    cases = []
    for noise in ("AR(1), pole 0.9", "ARMA(2,1)"):
        cases.append(("DC drive, 400 s, PRBS 1 s, dt 0.02", "dc_drive", dc_drive_tf, 10.0, dc,
                      1.0, 10.0, noise, methods, {}, False))  # fmt: skip
        known = {"tau": 2.0, "l": 0.5}
        cases.append(("absorber, 40 s, PRBS 2 s, dt 0.01", "absorber", absorber_tf, 0.72,
                      absorber, 2.0, 10.0, noise, methods, known, False))  # fmt: skip
    return calibration_rows("record", cases, seeds)


SPEED_CASES = [  # (label, model, transfer function, truth, dt, PRBS period, known values)
    ("DC drive, PRBS 1 s, dt 0.02", "dc_drive", dc_drive_tf, 10.0, 0.02, 1.0, {}),
    (
        "absorber, PRBS 2 s, dt 0.01",
        "absorber",
        absorber_tf,
        0.72,
        0.01,
        2.0,
        {"tau": 2.0, "l": 0.5},
    ),
    ("dc_motor, PRBS 0.5 s, dt 0.01", "dc_motor", dc_motor_tf, (1.0, 10.0), 0.01, 0.5, {}),
]


def speed_calls(module, tf, truth, dt, period, known, seed: int = 1, samples: int = 20001):
    """{"fit": ..., "peer": ...}: (function, args, options) of the default fit and the peer on
    a PRBS record of the case at 20 dB (white noise)."""
    t = dt * np.arange(samples)
    u = prbs(t, period, seed)
    y = noisy(simulate(tf, truth, t, u, "zoh"), 20.0, "white", seed)
    k0 = module.TRUE_VALUE
    box = None if np.ndim(k0) == 0 else [(v / module.DEFAULT_RANGE, v * module.DEFAULT_RANGE)
                                         for v in k0]  # fmt: skip
    return {
        "fit": (module.fit, (t, u, y), dict(hold="zoh", **known)),
        "peer": (peer.fit, (module, t, u, y), dict(k0=k0, bounds=box, hold="zoh", **known)),
    }


def speed_rows(repeats: int) -> list[list[str]]:
    """The default fit against the peer on 2e4-sample records at 20 dB (white noise)."""
    rows = [["record (2e4 samples, 20 dB)", "fit (defaults)", "output-error peer", "peer / fit",
             "k: fit", "k: peer"]]  # fmt: skip
    for label, name, tf, truth, dt, period, known in SPEED_CASES:
        module = generated(name)
        t = dt * np.arange(2001)
        peer.check(module, t, prbs(t, period, 1), truth, hold="zoh", **known)
        calls = speed_calls(module, tf, truth, dt, period, known)
        spent, out = {key: [] for key in calls}, {}
        for _ in range(repeats):
            for key, (call, args, options) in calls.items():
                start = time.process_time()
                out[key] = call(*args, **options)
                spent[key].append(time.process_time() - start)
        fit_, peer_ = np.median(spent["fit"]), np.median(spent["peer"])
        shown = [np.array2string(np.atleast_1d(out[key].k), precision=6) for key in calls]
        rows.append([label, f"{1e3 * fit_:.1f} ms", f"{1e3 * peer_:.1f} ms",
                     f"{peer_ / fit_:.2f}", *shown])  # fmt: skip
    return rows


FIRST = """
import os, sys, time, warnings
os.environ["OPENBLAS_NUM_THREADS"] = "1"
sys.path[:0] = [{bench!r}]
from _generated import generated
from exact import SPEED_CASES, speed_calls
warnings.simplefilter("ignore")
for label, name, tf, truth, dt, period, known in SPEED_CASES:
    module = generated(name)
    other = speed_calls(module, tf, truth, 1.25 * dt, period, known, 2)
    for call, args, options in other.values():  # (the code warmed on another record: another
        call(*args, **options)  # sampling interval, so another filter, and another input)
    spent = []
    for call, args, options in speed_calls(module, tf, truth, dt, period, known).values():
        start = time.process_time()
        call(*args, **options)
        spent.append(time.process_time() - start)
    print(*spent)
"""


def first_rows(repeats: int) -> list[list[str]]:
    """The speed rows' fit and peer, each the first of its record in a fresh interpreter
    (the code warmed on another record, of another sampling interval and input): what the
    tables a fit keeps for the next of the same filter, sampling and input (the moments'
    filter, the input's autocorrelations) do not save. Medians over `repeats` processes."""
    bench = os.path.dirname(os.path.abspath(__file__))
    code = FIRST.format(bench=bench)
    runs = []
    for _ in range(repeats):
        out = subprocess.run(
            [sys.executable, "-c", code], capture_output=True, text=True, check=True
        )
        runs.append([[float(x) for x in line.split()] for line in out.stdout.splitlines()])
    times = np.median(np.array(runs), axis=0)  # (cases, [fit, peer])
    rows = [["record (2e4 samples, 20 dB)", "first fit", "output-error peer", "peer / fit"]]
    for (label, *_), (fit_, peer_) in zip(SPEED_CASES, times, strict=True):
        rows.append([label, f"{1e3 * fit_:.1f} ms", f"{1e3 * peer_:.1f} ms", f"{peer_ / fit_:.2f}"])
    return rows


THROUGHPUT = """
import os, resource, sys, time, tracemalloc, warnings
os.environ["OPENBLAS_NUM_THREADS"] = "1"
sys.path[:0] = [{bench!r}]
import numpy as np
from _generated import generated
from montecarlo import dc_drive_tf, prbs
from exact import noisy, simulate
warnings.simplefilter("ignore")
module = generated("dc_drive")
t = 0.01 * np.arange(10**6)
u = prbs(t, 1.0, 1)
y = noisy(simulate(dc_drive_tf, 10.0, t, u, "zoh"), 20.0, "white", 1)
tracemalloc.start()
start = time.process_time()
result = module.fit(t, u, y, hold="zoh")
spent = time.process_time() - start
peak = tracemalloc.get_traced_memory()[1]
rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
print(t.size / spent, spent, peak, rss, result.k, result.k_se, result.noise.kind)
"""


def throughput_rows() -> list[list[str]]:
    """The default fit on a 1e6-sample DC-drive record in a fresh interpreter: samples per
    CPU second, numpy's peak allocation (tracemalloc) and the process's peak resident size."""
    bench = os.path.dirname(os.path.abspath(__file__))
    code = THROUGHPUT.format(bench=bench)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    rate, spent, peak, rss, k, se, kind = out.stdout.split()
    head = ["record", "samples/s", "time", "numpy peak", "process peak", "k", "noise model"]
    row = ["DC drive, 1e6 samples, PRBS 1 s, dt 0.01, 20 dB", f"{float(rate):.3g}",
           f"{float(spent):.2f} s", f"{float(peak) / 2**20:.0f} MiB",
           f"{float(rss) / 2**20:.0f} MiB", f"{float(k):.6g} +- {float(se):.2g}", kind]  # fmt: skip
    return [head, row]


def honest_rows(seeds: int) -> list[list[str]]:
    """Issue 18 item 4 (honest ok): `fit`'s defaults on records long and short; how often
    it says ok, and the interval it reports (Wald or profile likelihood) among the ok fits
    and over all. "absorbed": the largest share of an unknown's information the offset and
    initial state take, the highest among the ok fits (then over all)."""
    rows = [["record", "noise", "SNR", "unknown", "ok", "profile intervals", "covers (ok)",
             "covers (all)", "k_se / std (ok)", "bias (ok)", "absorbed (ok; all)",
             "time per fit"]]  # fmt: skip
    dc = 0.02 * np.arange(20001)
    absorber = 0.01 * np.arange(4001)
    known = {"tau": 2.0, "l": 0.5}
    cases = [
        ("DC drive, 3 s, PRBS 0.2 s, dt 0.01", "dc_drive", dc_drive_tf, 10.0,
         0.01 * np.arange(301), 0.2, 10.0, "white", {}),
        ("DC drive, 10 s, PRBS 0.2 s, dt 0.01", "dc_drive", dc_drive_tf, 10.0,
         0.01 * np.arange(1001), 0.2, 20.0, "white", {}),
        ("DC drive, 400 s, PRBS 1 s, dt 0.02", "dc_drive", dc_drive_tf, 10.0, dc, 1.0, 10.0,
         "AR(1), pole 0.9", {}),
        ("absorber, 40 s, PRBS 2 s, dt 0.01", "absorber", absorber_tf, 0.72, absorber, 2.0,
         10.0, "AR(1), pole 0.9", known),
        ("DC drive, 400 s, PRBS 1 s, dt 0.02", "dc_drive", dc_drive_tf, 10.0, dc, 1.0, 10.0,
         "ARMA(2,1)", {}),
        ("absorber, 40 s, PRBS 2 s, dt 0.01", "absorber", absorber_tf, 0.72, absorber, 2.0,
         10.0, "ARMA(2,1)", known),
        ("dc_motor, 60 s, PRBS 0.5 s, dt 0.01", "dc_motor", dc_motor_tf, (1.0, 10.0),
         0.01 * np.arange(6001), 0.5, 20.0, "white", {}),
        ("dc_motor, 60 s, PRBS 0.5 s, dt 0.01", "dc_motor", dc_motor_tf, (1.0, 10.0),
         0.01 * np.arange(6001), 0.5, 10.0, "white", {}),
    ]  # fmt: skip
    for label, name, tf, truth, t, period, snr, noise, extra in cases:
        module = generated(name)
        truths = np.atleast_1d(truth)
        found = []  # (k, se, lo, hi, ok, profiled, absorbed, time) per seed
        for seed in range(seeds):
            u = prbs(t, period, seed)
            y = noisy(simulate(tf, truth, t, u, "zoh"), snr, noise, seed)
            start = time.process_time()
            result = module.fit(t, u, y, hold="zoh", **extra)
            spent = time.process_time() - start
            ci = np.reshape(result.ci, (-1, 2))
            found.append((np.atleast_1d(result.k), np.atleast_1d(result.k_se), ci[:, 0],
                          ci[:, 1], result.ok, result.intervals.count("profile"),
                          result.absorbed, spent))  # fmt: skip
        ok = np.array([row[4] for row in found])
        absorbed = np.array([row[6] for row in found])
        for i, (unknown, value) in enumerate(zip(module.UNKNOWNS, truths, strict=True)):
            k, se, lo, hi = (np.array([row[j][i] for row in found]) for j in range(4))
            covers = (lo <= value) & (value <= hi)
            good = k[ok]
            spread = good.std(ddof=1) if good.size > 1 else math.nan
            rows.append([
                label, noise, f"{snr:g} dB", f"{unknown} = {value:g}", f"{ok.sum()}/{seeds}",
                f"{sum(row[5] for row in found)}",
                f"{100 * covers[ok].mean():.0f} %" if ok.any() else "-",
                f"{100 * covers.mean():.0f} %",
                f"{se[ok].mean() / spread:.2f}" if good.size > 1 else "-",
                f"{100 * (good.mean() / value - 1):+.3f} %" if ok.any() else "-",
                (f"{absorbed[ok].max():.4f}" if ok.any() else "-") + f"; {absorbed.max():.4f}",
                f"{1e3 * np.median([row[7] for row in found]):.0f} ms",
            ])  # fmt: skip
        print(f"  {label}, {noise}, {snr:g} dB done", file=sys.stderr)
    return rows


TABLES = {
    "short": ("Short noise-free records (DC drive, k = 10)", short_rows),
    "dc10": ("DC drive 10 s at 20 dB", dc10_rows),
    "coloured": ("Coloured noise at 10 dB", coloured_rows),
    "honest": ("Honest ok: how often fit says ok, and its intervals", honest_rows),
    "speed": ("Speed against the output-error peer", lambda seeds: speed_rows(7)),
    "first": (
        "Speed of a record's first fit (a fresh interpreter each)",
        lambda seeds: first_rows(7),
    ),
    "throughput": ("Throughput and memory", lambda seeds: throughput_rows()),
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=60, help="records per row (60)")
    parser.add_argument("--only", default=",".join(TABLES), help=f"tables: {','.join(TABLES)}")
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    for name in args.only.split(","):
        title, rows = TABLES[name]
        seeded = name not in ("speed", "first", "throughput")
        print(f"\n{title} ({args.seeds} seeds a row):\n" if seeded else f"\n{title}:\n")
        print(table(rows(args.seeds)))
        sys.stdout.flush()


if __name__ == "__main__":
    main()
