"""`mtt compile`, `mtt simulate` and `mtt estimate`: the generated estimator at work.

`compile` writes the estimator module. `simulate` and `estimate` build the same module
in memory (codegen.load) and call its functions, so the algorithm exists once, in the
template; what is here is the experiment around it: data, runs, tables and figures.
"""

from __future__ import annotations

import json
import sys
from dataclasses import dataclass
from types import ModuleType

import numpy as np

from mtt.cli import unknowns
from mtt.cli.experiment_args import DEFAULT_DT, DEFAULT_SEED, DEFAULT_T_END
from mtt.cli.options import choice_from_args
from mtt.cli.running import EXIT_OK, UsageError
from mtt.derivation import pipeline
from mtt.estimator import codegen
from mtt.present import tables, values

MAX_SAMPLES = 10**7


# the data ------------------------------------------------------------------------------


@dataclass(frozen=True)
class Data:
    t: np.ndarray
    u: np.ndarray
    y: np.ndarray
    clean: np.ndarray | None  # the output before noise, when simulated
    k: float | np.ndarray | None  # the true value(s), when simulated (an array: several)
    note: str  # where the data came from, for tables and titles


SIGNAL_KINDS = ("step", "prbs", "square", "multisine")


def _signal(module: ModuleType, args) -> tuple[np.ndarray, np.ndarray, str]:
    """The input samples and a description: a test signal on a regular grid from t = 0
    (step by default), or a CSV file's t,u columns."""
    kind = args.signal or "step"
    if kind not in SIGNAL_KINDS:
        if args.t_end is not None or args.dt is not None or args.period is not None:
            raise UsageError(
                "--t-end, --dt and --period apply to a test signal (--signal step|prbs|square|"
                "multisine); the file gives the times"
            )
        t, u = module.read_csv(kind, ("t", "u"))
        return t, u if args.amplitude is None else args.amplitude * u, kind
    t_end = DEFAULT_T_END if args.t_end is None else args.t_end
    dt = DEFAULT_DT if args.dt is None else args.dt
    if not (0 < dt <= t_end < np.inf):
        raise UsageError(f"need 0 < --dt <= --t-end, not --dt {dt} and --t-end {t_end}")
    if not t_end / dt < MAX_SAMPLES:  # inf for --dt 5e-324: round() raised OverflowError
        raise UsageError(
            f"--t-end / --dt = {t_end / dt:.3g} samples is too many (at most {MAX_SAMPLES})"
        )
    count = max(1, round(t_end / dt))
    if kind == "step" and args.period is not None:
        raise UsageError("--period applies to prbs, square and multisine, not to a step")
    t = np.linspace(0.0, t_end, count + 1)
    amplitude = 1.0 if args.amplitude is None else args.amplitude
    seed = DEFAULT_SEED if args.seed is None else args.seed
    u = module.input_signal(kind, t, amplitude=amplitude, period=args.period, seed=seed)
    described = (
        "a unit step" if kind == "step" and amplitude == 1 else f"{kind}, amplitude {amplitude:g}"
    )
    if args.period is not None:
        described += f", period {args.period:g}"
    return t, u, described


HELD_SIGNALS = ("step", "prbs", "square")  # piecewise constant between their samples


def hold_of(args) -> str:
    """--hold, or its default: zoh for a test signal that is held by construction (the fit
    of a simulated PRBS must not read its jumps as ramps), linear for measured data."""
    if args.hold is not None:
        return args.hold
    simulated = not getattr(args, "data", None) and (args.signal or "step") in HELD_SIGNALS
    return "zoh" if simulated else "linear"


def experiment_data(module: ModuleType, args, several: bool = False) -> list[Data]:
    """Measured data (each --data), or a simulation of the model with the chosen input and
    noise: one record unless `several` (fit) allows more."""
    simulation = {"--signal": args.signal, "--t-end": args.t_end, "--dt": args.dt}
    simulation |= {"--true": args.true}
    simulation |= {"--noise-uniform": args.noise_uniform, "--noise-snr": args.noise_snr}
    simulation |= {"--seed": args.seed, "--amplitude": args.amplitude, "--period": args.period}
    if getattr(args, "data", None):
        given = [flag for flag, value in simulation.items() if value is not None]
        if given:
            raise UsageError(f"--data and {given[0]} do not go together ({given[0]} simulates)")
        if len(args.data) > 1 and not several:
            raise UsageError(
                f"{args.command} takes one --data ({len(args.data)} given); `mtt fit` combines "
                "several experiments"
            )
        names = columns(args.columns)
        records = []
        for path in args.data:
            t, u, y = module.read_csv(path, names)
            late = np.flatnonzero(np.diff(t) <= 0)
            if late.size:  # named here: the module's message cannot name the file
                i = int(late[0])
                later, earlier = float(t[i + 1]), float(t[i])
                raise UsageError(
                    f"{path}: the times (column {names[0]!r}) must increase strictly: "
                    f"{later!r} (data row {i + 2}) follows {earlier!r} (data row {i + 1})"
                )
            records.append(Data(t, u, y, None, None, f"{t.size} samples from {path}"))
        return records
    if getattr(args, "columns", None):
        raise UsageError("--columns names the columns of --data files")
    t, u, source = _signal(module, args)
    k = unknowns.true_point(module, args.true)
    if isinstance(k, list):
        example = ",".join(f"{name}=..." for name in k) if len(module.UNKNOWNS) > 1 else "V"
        raise UsageError(
            f"the model gives no value of {', '.join(k)} to simulate with: pass --true {example}"
        )
    clean = module.simulate(t, u, k, hold=hold_of(args))
    named = values.named(module, k, "g")
    _finite(clean, t, named)
    seed = DEFAULT_SEED if args.seed is None else args.seed
    note = f"{t.size} samples simulated with {named}, input {source}"
    y = clean
    if args.noise_uniform:
        noise = args.noise_uniform
        if not 0 <= noise <= module.MAX_SIGNAL / 100:
            raise UsageError(
                f"--noise-uniform must be from 0 to {module.MAX_SIGNAL / 100:g}, not {noise:g}"
            )
        y = clean + np.random.default_rng(seed).uniform(-noise, noise, clean.size)
        note += f", noise uniform in [-{noise:g}, {noise:g}] (seed {seed})"
    elif args.noise_snr is not None:
        if not np.isfinite(args.noise_snr):
            raise UsageError(f"--noise-snr must be a finite number of dB, not {args.noise_snr}")
        y = module.with_noise(clean, args.noise_snr, seed=seed)
        note += f", white Gaussian noise at {args.noise_snr:g} dB SNR (seed {seed})"
    return [Data(t, u, y, clean, k, note)]


def _finite(y: np.ndarray, t: np.ndarray, named: str) -> None:
    """Refuse a simulation that left floating point (NaN or inf samples were written as
    data, with exit status 0; NaN and Infinity made invalid JSON); the noise added after
    is bounded."""
    bad = np.flatnonzero(~np.isfinite(y))
    if bad.size:
        raise UsageError(
            f"the simulated output overflows at t = {t[bad[0]]:g}: the model is unstable with "
            f"{named}, or its values are far from 1; shorten --t-end, choose another --true, "
            "or give the parameters, the input and the noise in units nearer 1"
        )


def columns(text: str | None) -> tuple[str, str, str]:
    """--columns T,U,Y: the names of the time, input and output columns."""
    if text is None:
        return ("t", "u", "y")
    names = tuple(name.strip() for name in text.split(","))
    if len(names) != 3 or not all(names) or len(set(names)) != 3:
        raise UsageError(f"--columns takes three different names T,U,Y, not {text!r}")
    return names


# the commands --------------------------------------------------------------------------


def module_for(args) -> ModuleType:
    return checked_module(codegen.load(pipeline.theta_for(args.file, choice_from_args(args))))


def checked_module(module: ModuleType) -> ModuleType:
    """The module, if the model gives every kept parameter a value."""
    missing = [name for name, value in module.DEFAULTS.items() if value is None]
    if missing:
        name = missing[0]
        raise UsageError(f"the model gives no value for {name}: pass --set {name}=VALUE")
    return module


def signal_label(module: ModuleType, role: str) -> str:
    """What a plot calls the input or the output: the model's words for the source or
    detector, else what it is (the effort or flow of the component), with its label."""
    label = getattr(module, role.upper())
    description = getattr(module, f"{role.upper()}_DESCRIPTION", None)
    if description:
        return f"{description} ({label})"
    kind, _, name = label.partition(":")
    quantity = "effort" if kind in ("Se", "De") else "flow"
    where = "of the source" if role == "input" else "at the detector"
    return f"{role}: {quantity} {where} {name} ({label})"


def cmd_compile(args) -> int:
    theta = pipeline.theta_for(args.file, choice_from_args(args))
    source = codegen.render(theta)
    path = codegen.output_path(args.path, theta)
    codegen.write_atomic(path, source)
    kept = f", {', '.join(theta.symbols)} kept symbolic" if theta.symbols else ""
    if args.json:
        print(json.dumps({"ok": True, "path": str(path), "model": theta.model,
                          "unknown": theta.unknown, "unknowns": list(theta.unknowns),
                          "n": theta.n, "m": theta.m, "N": theta.N,
                          "kept": list(theta.symbols)}))  # fmt: skip
        return EXIT_OK
    print(
        f"wrote {path}: estimator of {', '.join(theta.unknowns)} for {theta.model} "
        f"(n = {theta.n}, m = {theta.m}, N = {theta.N}{kept})"
    )
    return EXIT_OK


def cmd_simulate(args) -> int:
    from mtt.present import plots  # matplotlib: a quarter second, paid by plotting only

    module = module_for(args)
    (data,) = experiment_data(module, args)
    if args.data_plot:
        plots.data(
            args.data_plot, data.t, data.u, data.y, clean=data.clean,
            title=f"{module.MODEL}: {data.note}", input_label=signal_label(module, "input"),
            output_label=signal_label(module, "output"), dpi=args.dpi,
        )  # fmt: skip
    if args.csv:
        codegen.write_atomic(
            args.csv, tables.csv_text(["t", "u", "y"], zip(data.t, data.u, data.y, strict=True))
        )
    if args.json:
        arrays = {name: getattr(data, name).tolist() for name in ("t", "u", "y")}
        print(json.dumps({"ok": True, "model": module.MODEL, "note": data.note, "csv": args.csv,
                          **arrays}))  # fmt: skip
    elif args.csv:
        print(f"wrote {args.csv}: {data.note}")
    elif not args.data_plot:
        sys.stdout.write(tables.csv_text(["t", "u", "y"], zip(data.t, data.u, data.y, strict=True)))
    return EXIT_OK
