"""Monte Carlo figures and speed of the nonlinear fit (issue 20): the simulator's `fit` of
the shipped models (models/two_tanks.bg, models/pendulum.bg) on records made
independently of mtt.

The records: scipy's solve_ivp (DOP853, rtol = atol = 1e-12) on right-hand sides written
by hand here from the model files, the input held between samples (one integration per
piece of constant input), white Gaussian noise at 20 dB (output variance over noise
variance), a new noise and a new random binary input per seed:

- two tanks (unknowns a1, a2): the pump between 4 and 16 cm^3/s, switching every 100 s at
  most, 600 samples every 5 s from the steady state at 4; at 16 the upper tank overflows
  (its level passes its rim at 30 cm) in every record;
- pendulum (unknowns j, fc): the armature voltage between -2 and 2 V, switching every
  0.5 s at most, 1000 samples every 0.01 s from rest; the arm swings through large angles
  (gravity's torque reaches 0.59 N m, the motor's 0.5) and its speed changes sign, where
  the Coulomb friction switches.

A third row: the two tanks' records with coloured noise instead, AR(1) with pole 0.9
at 20 dB (the noise's stationary variance), fitted with the default noise="auto": the
noise model chosen by the BIC from the output-error residuals, the prediction errors
whitened by it, k_se and the intervals from their covariance (the last column counts the
noise models chosen).

`fit` is told the input was held (hold="zoh"); each record's initial state and output
offset are estimated; the starts are the model file's values and the default multistart
(4 quasi-random points within a factor 10 of them). Per unknown: the bias of the mean
estimate (relative), the ratio of the mean k_se to the spread of the estimates, the
coverage of the 95 % intervals. Validation: each fit compared with a second record of the
same seed (`Fit.compare`: its initial state and offset estimated) against the truth's fit
% on it (the noise alone). Then: a tank whose pump gain and cross-section appear only as
their ratio, reported not identifiable.

Speed: a 10001-sample two-tank record fitted from the small-signal model's estimate
(multistart=0: that start and the model file's values), against
scipy.optimize.least_squares with finite differences over the same parameters (a1, a2,
the initial state, the offset), simulating with solve_ivp on the hand-written right-hand
side (LSODA, one call per piece of constant input), from the same two starts, the lower
minimum taken: the times are this process's CPU, the ratio peer / generated, and both
answers are printed with their costs. The peer is written as a careful user would: its
finite differences step by 1e-5 (relative) over a simulation at rtol = atol = 1e-10, so
that the simulation's error is far below the difference. With least_squares' defaults
(a step of 1.5e-8 over LSODA at rtol 1e-8) the differences are noise in the
initial-state directions, and it stops with the initial state hundreds of noise
variances from its minimum (answers 1.7 standard errors from the generated fit's, found
so in an earlier run).

    nice -n 10 .venv/bin/python bench/nonlinear_fit.py            # 40 seeds per row
    .venv/bin/python bench/nonlinear_fit.py --seeds 4 --no-speed  # while developing
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # before numpy loads OpenBLAS

import argparse  # noqa: E402
import math  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import sympy  # noqa: E402
from scipy import optimize  # noqa: E402
from scipy.integrate import solve_ivp  # noqa: E402
from scipy.signal import lfilter  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))

from nonlinear_models import TWO_TANKS_K, two_tanks  # noqa: E402
from nonlinear_records import held, noisy, pump, tanks_output, tanks_rhs, weir_rhs  # noqa: E402

import mtt  # noqa: E402
from mtt.derivation.nonlinear import NonlinearStateSpace  # noqa: E402
from mtt.estimator import nonlinear_codegen  # noqa: E402

Z95 = 1.959963984540054
POLE = 0.9  # the coloured-noise row's AR(1) pole (a sample every 5 s: a correlation time of 47 s)


def pendulum_rhs(k):
    """models/pendulum.bg at k = (j, fc): states (p_la, p_arm, q_joint)."""
    j, fc = k
    ra, la, km, b, v0, mgl = 2.0, 0.01, 0.5, 0.01, 0.01, 0.2 * 9.81 * 0.3

    def rhs(x, v):
        i, w = x[0] / la, x[1] / j
        return [
            v - ra * i - km * w,
            km * i - fc * math.tanh(w / v0) - b * w - mgl * math.sin(x[2]),
            w,
        ]

    return rhs


def tanks_record(seed: int, size: int = 600, k=(2.0, 2.5)):
    t = np.arange(size) * 5.0
    u = pump(t, 4.0, 16.0, 20, seed)
    states = held(weir_rhs(k), t, u, [50 * (4 / k[0]) ** 2, 40 * (4 / k[1]) ** 2])
    assert states[:, 0].max() / 50 > 30, "the record does not reach the overflow"
    return t, u, states[:, 1] / 40


def pendulum_record(seed: int, size: int = 1000, k=(0.02, 0.05)):
    t = np.arange(size) * 0.01
    v = pump(t, -2.0, 2.0, 50, seed)
    states = held(pendulum_rhs(k), t, v, [0.0, 0.0, 0.0])
    speed = states[:, 1] / k[0]
    assert np.ptp(states[:, 2]) > 1.0 and speed.min() < 0 < speed.max()
    return t, v, speed


def product_tank() -> NonlinearStateSpace:
    """One tank filled by a pump of gain a b and drained through an orifice c: a and b
    appear only as their product."""
    x, u, y, a, b, c = sympy.symbols("x u y a b c")
    f = sympy.Matrix([a * b * u - c * sympy.sqrt(x)])
    return NonlinearStateSpace("product_tank", (x,), u, y, (a, b, c), {}, f, sympy.Matrix([x]))


def coloured(y: np.ndarray, snr_db: float, seed: int, pole: float) -> np.ndarray:
    """y plus AR(1) noise 1/(1 - pole q^-1) e at a signal-to-noise ratio in dB (var y over
    the noise's stationary variance), started in its stationary distribution."""
    if pole == 0:
        return noisy(y, snr_db, seed)
    scale = float(np.std(y)) * 10 ** (-snr_db / 20)
    z = np.random.default_rng(seed).standard_normal(y.size)
    e = z * scale * math.sqrt(1 - pole**2)
    e[0] = z[0] * scale  # the first sample from the stationary distribution
    return y + lfilter([1.0], [1.0, -pole], e)


def monte_carlo(module, record, truth, seeds: int, snr: float = 20.0, pole: float = 0.0,
                first: int = 0) -> dict:  # fmt: skip
    rows, compared, clock, kinds = [], [], 0.0, []
    for seed in range(first, seeds):
        t, u, clean = record(seed)
        y = coloured(clean, snr, 1000 + seed, pole)
        start = time.process_time()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            found = module.fit(t, u, y, hold="zoh", profile=None)
        clock += time.process_time() - start
        rows.append((found.ok, found.k, found.k_se, found.ci))
        kinds.append("white" if found.noise is None else found.noise.kind)
        t2, u2, clean2 = record(500 + seed)
        y2 = coloured(clean2, snr, 2000 + seed, pole)
        truth_fit = 100 * (1 - np.linalg.norm(y2 - clean2) / np.linalg.norm(y2 - y2.mean()))
        if found.ok:
            compared.append(found.compare(t2, u2, y2).fit_percent - truth_fit)
        print(f"  seed {seed}: k = {np.round(found.k, 6)}, k_se = {np.round(found.k_se, 6)}, "
              f"ok {found.ok}, validation {compared[-1] if found.ok else math.nan:+.4f}",
              file=sys.stderr, flush=True)  # fmt: skip
    ok = np.array([row[0] for row in rows])
    k = np.array([row[1] for row in rows])[ok]
    se = np.array([row[2] for row in rows])[ok]
    ci = np.array([row[3] for row in rows])[ok]
    truth = np.asarray(truth, dtype=float)
    covered = (ci[:, :, 0] <= truth) & (truth <= ci[:, :, 1])
    return dict(
        ok=int(ok.sum()), seeds=seeds - first, bias=(k.mean(0) - truth) / truth,
        ratio=se.mean(0) / k.std(0, ddof=1), coverage=100 * covered.mean(0),
        validation=np.array(compared), seconds=clock / (seeds - first),
        noise=", ".join(f"{kind} {kinds.count(kind)}" for kind in sorted(set(kinds))),
    )  # fmt: skip


def table(name: str, unknowns, figures: dict) -> list[str]:
    lines, validation = [], figures["validation"]
    for i, unknown in enumerate(unknowns):
        lines.append(
            f"| {name} | {unknown} | {figures['ok']}/{figures['seeds']} | "
            f"{100 * figures['bias'][i]:+.3f} % | {figures['ratio'][i]:.2f} | "
            f"{figures['coverage'][i]:.0f} % | "
            f"{np.mean(validation):+.3f} (worst {np.max(np.abs(validation)):.3f}) | "
            f"{figures['seconds']:.1f} s | {figures['noise']} |"
        )
    return lines


def identifiability() -> str:
    module = nonlinear_codegen.load(product_tank(), values=dict(a=2.0, b=0.5, c=0.5))
    t = np.arange(301) * 0.5
    u = pump(t, 0.3, 1.0, 20, seed=1)
    states = held(lambda x, v: [v - 0.5 * math.sqrt(max(x[0], 0.0))], t, u, [1.0])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        found = module.fit(t, u, noisy(states[:, 0], 20, seed=1), hold="zoh")
    return (
        f"product tank (a b u - c sqrt(x)): ok {found.ok}, identifiable {found.identifiable}: "
        f"{found.determined}; k_se {found.k_se}; {found.message}"
    )


def full_start(seeds: int) -> str:
    """The plateau of an empty tank (issue 19's leftover): tests/nonlinear_models.two_tanks
    (unknowns c1, c2, kp) with the upper tank full (1.0) and the lower empty at the start,
    the pump off for 20 s, then between 0.3 and 0.8; 241 samples every 0.5 s, 20 dB. The
    fit's guess of the initial state, the steady state at the first input, is both tanks
    empty. Each fit against a fit started at the true initial state: counted, those that
    reach its cost (within 3.84 noise variances, or lower), those higher with ok, those
    higher and refused, and those with no estimate."""
    values = dict(zip(("c1", "c2", "kp"), TWO_TANKS_K, strict=True))
    module = nonlinear_codegen.load(two_tanks(), values=values)
    t, counts, clock = np.arange(241) * 0.5, dict(right=0, wrong_ok=0, refused=0, none=0), 0.0
    for seed in range(1, seeds + 1):
        u = np.where(t < 20, 0.0, pump(t, 0.3, 0.8, 20, seed))
        y = noisy(tanks_output(held(tanks_rhs(TWO_TANKS_K), t, u, (1.0, 0.0))), 20, seed)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            start = time.process_time()
            found = module.fit(t, u, y, hold="zoh", multistart=0, profile=None)
            clock += time.process_time() - start
            truth = module.fit(t, u, y, hold="zoh", multistart=0, profile=None, x0=[1.0, 0.0])
        if not found.states:
            counts["none"] += 1
            continue
        extra = t.size * (found.residual_rms**2 - truth.residual_rms**2) / truth.noise_std**2
        counts["right" if extra < 3.84 else "wrong_ok" if found.ok else "refused"] += 1
    return (
        f"tanks full at the start, guessed empty ({seeds} seeds): {counts['right']} reach the "
        f"fit from the true initial state, {counts['wrong_ok']} higher with ok, "
        f"{counts['refused']} higher refused, {counts['none']} no estimate (ok False); CPU per "
        f"fit {clock / seeds:.2f} s"
    )


def speed(samples: int) -> list[str]:
    """The 1e4-sample two-tank fit from the small-signal start (multistart=0: that start and
    the model file's values) against least_squares with finite differences over solve_ivp
    from the same two starts, the lower minimum taken."""
    model = mtt.load(str(ROOT / "models" / "two_tanks.bg"))
    module = model.simulator()
    t = np.arange(samples) * 5.0
    u = pump(t, 4.0, 16.0, 20, seed=7)
    truth = (2.0, 2.5)
    states = held(weir_rhs(truth), t, u, [50 * (4 / 2.0) ** 2, 40 * (4 / 2.5) ** 2])
    y = noisy(states[:, 1] / 40, 20, seed=7)
    from mtt.api.nonlinear_fits import linearised_start

    start_clock = time.process_time()
    start = linearised_start(model, t, u, y, hold="zoh")
    linear = time.process_time() - start_clock
    k0 = start.k if start.k is not None else np.array(truth)
    begin = time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        found = module.fit(t, u, y, k0=k0, hold="zoh", multistart=0, profile=None)
    generated = time.process_time() - begin
    pieces = [0, *(np.flatnonzero(np.diff(u[:-1]) != 0) + 1).tolist(), t.size - 1]

    def residuals(theta):
        rhs = weir_rhs(theta[:2])
        x, out = theta[2:4].copy(), np.empty(t.size)
        out[0] = x[1] / 40
        for a, b in zip(pieces[:-1], pieces[1:], strict=True):
            value = float(u[a])
            run = solve_ivp(lambda _, z, v=value: rhs(z, v), (t[a], t[b]), x, method="LSODA",
                            t_eval=t[a : b + 1], rtol=1e-10, atol=1e-10)  # fmt: skip
            if not run.success:
                return np.full(t.size, 1e6)
            out[a + 1 : b + 1] = run.y[1, 1:] / 40
            x = run.y[:, -1]
        return y - out - theta[4]

    begin = time.process_time()
    peers = []  # from each of the generated fit's starts (the small-signal estimate, the file's)
    for _, point, _ in found.starts:
        x0 = module.steady_state(u[0], point)
        theta0 = np.array([*point, *x0, float(np.mean(y - x0[1] / 40))])
        peers.append(optimize.least_squares(residuals, theta0, method="trf", x_scale="jac",
                                            diff_step=1e-5))  # fmt: skip
    peer_time = time.process_time() - begin
    peer = min(peers, key=lambda run: run.cost)
    ends = "; ".join(
        f"{np.round(run.x[:2], 5)} (cost {run.cost:.6g}) in {run.nfev + run.njev * run.x.size} "
        "simulations"
        for run in peers
    )
    return [
        f"speed, {samples} samples, two tanks: small-signal start ({start.note}) "
        f"{linear:.2f} s CPU, k0 = {np.round(k0, 5)}",
        f"  generated fit (starts: {', '.join(origin for origin, _, _ in found.starts)}): "
        f"{generated:.2f} s CPU, k = {found.k}, cost {found.exact_cost:.6g}, ok {found.ok}",
        f"  least_squares (finite differences) over solve_ivp from the same starts: "
        f"{peer_time:.2f} s CPU, ends {ends}",
        f"  ratio peer / generated: {peer_time / generated:.1f}; answers differ by "
        f"{np.max(np.abs(peer.x[:2] - found.k) / found.k):.2e} (relative), "
        f"{np.max(np.abs(peer.x[:2] - found.k) / found.k_se):.2e} standard errors",
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=40)
    parser.add_argument("--first", type=int, default=0, help="the first seed (runs in parts)")
    parser.add_argument("--samples", type=int, default=10001)
    parser.add_argument("--no-speed", action="store_true")
    parser.add_argument("--only", choices=("tanks", "coloured", "pendulum", "full", "speed"))
    args = parser.parse_args()
    lines = [
        "| model | unknown | ok | bias | k_se / std | 95 % coverage | validation fit % - "
        "truth's | CPU per fit | noise models chosen |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    if args.only in (None, "tanks"):
        tanks = mtt.load(str(ROOT / "models" / "two_tanks.bg")).simulator()
        lines += table(
            "two tanks",
            ("a1", "a2"),
            monte_carlo(tanks, tanks_record, (2.0, 2.5), args.seeds, first=args.first),
        )
    if args.only in (None, "coloured"):
        tanks = mtt.load(str(ROOT / "models" / "two_tanks.bg")).simulator()
        figures = monte_carlo(tanks, tanks_record, (2.0, 2.5), args.seeds, pole=POLE,
                              first=args.first)  # fmt: skip
        lines += table(f"two tanks, AR(1) noise (pole {POLE})", ("a1", "a2"), figures)
    if args.only in (None, "pendulum"):
        arm = mtt.load(str(ROOT / "models" / "pendulum.bg")).simulator()
        lines += table(
            "pendulum",
            ("j", "fc"),
            monte_carlo(arm, pendulum_record, (0.02, 0.05), args.seeds, first=args.first),
        )
    if args.only not in ("speed", "full"):
        print("\n".join(lines))
        print(identifiability())
    if args.only in (None, "full"):
        print(full_start(args.seeds))
    if not args.no_speed and args.only in (None, "speed"):
        print("\n".join(speed(args.samples)))


if __name__ == "__main__":
    main()
