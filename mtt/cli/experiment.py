"""`mtt compile`, `mtt simulate` and `mtt estimate`: the generated estimator at work.

`compile` writes the estimator module. `simulate` and `estimate` build the same module
in memory (codegen.load) and call its functions, so the algorithm exists once, in the
template; what is here is the experiment around it: data, runs, tables and figures.
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import sys
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from types import ModuleType

import numpy as np
from tqdm import tqdm

from mtt.cli.experiment_args import DEFAULT_DT, DEFAULT_SEED, DEFAULT_T_END
from mtt.cli.options import choice_from_args
from mtt.derivation import pipeline
from mtt.estimator import codegen

EXIT_OK, EXIT_STOPPED, EXIT_USAGE = 0, 1, 2
MAX_SAMPLES = 10**7


class UsageError(Exception):
    """Options or data that do not make an experiment; the message says why."""


# the data ------------------------------------------------------------------------------


@dataclass(frozen=True)
class Data:
    t: np.ndarray
    u: np.ndarray
    y: np.ndarray
    clean: np.ndarray | None  # the output before noise, when simulated
    k: float | None  # the true value, when simulated
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
    count = max(1, round(t_end / dt))
    if count >= MAX_SAMPLES:
        raise UsageError(f"--t-end / --dt = {count} samples is too many (at most {MAX_SAMPLES})")
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


def experiment_data(module: ModuleType, args, several: bool = False) -> list[Data]:
    """Measured data (each --data), or a simulation of the model with the chosen input and
    noise: one record unless `several` (fit) allows more."""
    simulation = {"--signal": args.signal, "--t-end": args.t_end, "--dt": args.dt, "--k": args.k}
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
        columns = _columns(args.columns)
        records = []
        for path in args.data:
            t, u, y = module.read_csv(path, columns)
            records.append(Data(t, u, y, None, None, f"{t.size} samples from {path}"))
        return records
    if getattr(args, "columns", None):
        raise UsageError("--columns names the columns of --data files")
    t, u, source = _signal(module, args)
    k = module.TRUE_VALUE if args.k is None else args.k
    if k is None:
        raise UsageError(f"the model gives no value of {module.UNKNOWN} to simulate with: pass --k")
    clean = module.simulate(t, u, k, hold=args.hold)
    seed = DEFAULT_SEED if args.seed is None else args.seed
    note = f"{t.size} samples simulated with {module.UNKNOWN} = {k:g}, input {source}"
    y = clean
    if args.noise_uniform:
        noise = args.noise_uniform
        if not 0 <= noise < np.inf:
            raise UsageError(f"--noise-uniform must be >= 0, not {noise}")
        y = clean + np.random.default_rng(seed).uniform(-noise, noise, clean.size)
        note += f", noise uniform in [-{noise:g}, {noise:g}] (seed {seed})"
    elif args.noise_snr is not None:
        if not np.isfinite(args.noise_snr):
            raise UsageError(f"--noise-snr must be a finite number of dB, not {args.noise_snr}")
        y = module.with_noise(clean, args.noise_snr, seed=seed)
        note += f", white Gaussian noise at {args.noise_snr:g} dB SNR (seed {seed})"
    return [Data(t, u, y, clean, k, note)]


def _columns(text: str | None) -> tuple[str, str, str]:
    """--columns T,U,Y: the names of the time, input and output columns."""
    if text is None:
        return ("t", "u", "y")
    names = tuple(name.strip() for name in text.split(","))
    if len(names) != 3 or not all(names) or len(set(names)) != 3:
        raise UsageError(f"--columns takes three different names T,U,Y, not {text!r}")
    return names


# the runs ------------------------------------------------------------------------------


@dataclass(frozen=True)
class Run:
    k0: float
    filter: str  # C(s) as the user wrote it (or the default)
    result: object  # the generated module's Estimate


def _filters(module: ModuleType, args) -> list[tuple[str, object]]:
    """(label, C) for each filter asked for: C as the generated `estimate` takes it (text is
    read by the module's own parser, the same as its command line's)."""
    power = module.n + 1
    filters = []
    for text in args.filter or []:
        text = text.strip()
        if text != "auto":
            module.filter_polynomial(text)  # a bad filter is an error before any run
        filters.append((text, text))
    for T in args.filter_T or []:
        filters.append((f"(1 + s)^{power}" if T == 1 else f"(1 + {T:g} s)^{power}", T))
    return filters or [(f"(1 + s)^{power}", None)]


def run_all(module: ModuleType, data: Data, args) -> list[Run]:
    """One estimate per filter and starting value, with a progress bar on a terminal."""
    filters = _filters(module, args)
    options = dict(beta=args.beta, S0=args.S0, hold=args.hold, engine=args.engine,
                   bounds=args.bounds, rtol=args.rtol, atol=args.atol)  # fmt: skip
    span = float(data.t[-1] - data.t[0])
    runs = []
    with tqdm(
        total=span * len(filters) * len(args.k0),
        desc="estimating",
        unit="s",
        delay=1.0,
        leave=False,
        disable=not sys.stderr.isatty(),
        bar_format="{l_bar}{bar}| {n:.3g}/{total:.3g} s of data [{elapsed}<{remaining}]",
    ) as bar:
        for label, C in filters:
            for k0 in args.k0:
                start = bar.n
                if args.S0_relative is not None:
                    options["S0"] = module.prior_weight(
                        data.t, data.u, data.y, k0=k0, fraction=args.S0_relative, C=C,
                        hold=args.hold,
                    )  # fmt: skip
                result = module.estimate(
                    data.t, data.u, data.y, k0=k0, C=C, **options,
                    progress=lambda now, start=start: bar.update(start + now - data.t[0] - bar.n),
                )  # fmt: skip
                bar.update(start + span - bar.n)
                runs.append(Run(k0, label, result))
    return runs


def _labels(runs: list[Run]) -> list[str]:
    several_k0 = len({run.k0 for run in runs}) > 1
    several_filters = len({run.filter for run in runs}) > 1
    labels = []
    for run in runs:
        parts = [f"k0 = {run.k0:g}"] if several_k0 or not several_filters else []
        parts += [f"C(s) = {run.filter}"] if several_filters else []
        labels.append(", ".join(parts))
    return labels


def _cost_range(runs: list[Run], data: Data, given: list[float] | None) -> tuple[float, float]:
    if given is not None:
        return given[0], given[1]
    points = [run.k0 for run in runs] + [value for run in runs for value in run.result.minima()]
    points += [] if data.k is None else [data.k]
    low, high = min(points), max(points)
    margin = max(0.25 * (high - low), 0.5)
    return low - margin, high + margin


# the commands --------------------------------------------------------------------------


def _csv_text(header: list[str], rows) -> str:
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(header)
    writer.writerows(rows)
    return buffer.getvalue()


def _model(args) -> ModuleType:
    return checked_module(codegen.load(pipeline.theta_for(args.file, choice_from_args(args))))


def checked_module(module: ModuleType) -> ModuleType:
    """The module, if the model gives every kept parameter a value."""
    missing = [name for name, value in module.DEFAULTS.items() if value is None]
    if missing:
        name = missing[0]
        raise UsageError(f"the model gives no value for {name}: pass --set {name}=VALUE")
    return module


def guarded(action: Callable[[argparse.Namespace], int]) -> Callable[[argparse.Namespace], int]:
    """Bad options, data and files end with a message and exit status 2, not a traceback
    (with --json also {"ok": false, "errors": [...]} on stdout). The estimator's warnings
    are reported by each command from its results; numpy's floating-point warnings, which
    the estimator's checks turn into messages, are not shown."""

    def run(args) -> int:
        message = None
        try:
            with warnings.catch_warnings(record=True) as caught, np.errstate(all="ignore"):
                warnings.simplefilter("always")
                status = action(args)
            for warning in caught:
                if not _handled(warning.category):
                    print(f"mtt {args.command}: warning: {warning.message}", file=sys.stderr)
            return status
        except (UsageError, ValueError) as exc:
            message = str(exc)
        except OSError as exc:
            message = f"{exc.filename}: {exc.strerror}" if exc.filename else str(exc)
        print(f"mtt {args.command}: error: {message}", file=sys.stderr)
        if getattr(args, "json", False):
            error = {"file": getattr(args, "file", None), "kind": "usage", "line": None,
                     "column": None, "message": message, "notes": []}  # fmt: skip
            print(json.dumps({"ok": False, "errors": [error]}))
        return EXIT_USAGE

    return run


def _handled(category: type) -> bool:
    """Warnings a command reports itself (the estimator's) or that say nothing to a user."""
    return issubclass(category, RuntimeWarning) or category.__name__ == "EstimationWarning"


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


def warn(command: str, texts) -> None:
    for text in texts:
        print(f"mtt {command}: warning: {text}", file=sys.stderr)


def cmd_compile(args) -> int:
    theta = pipeline.theta_for(args.file, choice_from_args(args))
    source = codegen.render(theta)
    path = codegen.output_path(args.path, theta)
    codegen.write_atomic(path, source)
    kept = f", {', '.join(theta.symbols)} kept symbolic" if theta.symbols else ""
    if args.json:
        print(json.dumps({"ok": True, "path": str(path), "model": theta.model,
                          "unknown": theta.unknown, "n": theta.n, "m": theta.m, "N": theta.N,
                          "kept": list(theta.symbols)}))  # fmt: skip
        return EXIT_OK
    print(
        f"wrote {path}: estimator of {theta.unknown} for {theta.model} "
        f"(n = {theta.n}, m = {theta.m}, N = {theta.N}{kept})"
    )
    return EXIT_OK


def cmd_simulate(args) -> int:
    from mtt.cli import plots  # matplotlib takes a quarter second to import: only plotting pays

    module = _model(args)
    (data,) = experiment_data(module, args)
    if args.data_plot:
        plots.data(
            args.data_plot, data.t, data.u, data.y, clean=data.clean,
            title=f"{module.MODEL}: {data.note}", input_label=signal_label(module, "input"),
            output_label=signal_label(module, "output"), dpi=args.dpi,
        )  # fmt: skip
    if args.csv:
        codegen.write_atomic(
            args.csv, _csv_text(["t", "u", "y"], zip(data.t, data.u, data.y, strict=True))
        )
    if args.json:
        arrays = {name: getattr(data, name).tolist() for name in ("t", "u", "y")}
        print(json.dumps({"ok": True, "model": module.MODEL, "note": data.note, "csv": args.csv,
                          **arrays}))  # fmt: skip
    elif args.csv:
        print(f"wrote {args.csv}: {data.note}")
    elif not args.data_plot:
        sys.stdout.write(_csv_text(["t", "u", "y"], zip(data.t, data.u, data.y, strict=True)))
    return EXIT_OK


def cmd_estimate(args) -> int:
    from mtt.cli import plots  # matplotlib takes a quarter second to import: only plotting pays

    if args.cost_range and not args.cost_range[0] < args.cost_range[1]:
        low, high = args.cost_range
        raise UsageError(f"--cost-range needs A < B, not {low:g} {high:g}")
    module = _model(args)
    (data,) = experiment_data(module, args)
    runs = run_all(module, data, args)
    labels = _labels(runs)
    curves = [
        plots.Curve(label, run.result.t, run.result.khat, run.result.minima(),
                    run.result.normalised_cost, run.result.global_k,
                    _band(module, data, run, args) if args.plot and len(runs) == 1 else None)
        for label, run in zip(labels, runs, strict=True)
    ]  # fmt: skip
    title = f"{module.MODEL}: {data.note}"
    weight = f"{args.S0:g}" if args.S0_relative is None else f"{args.S0_relative:g} relative"
    settings = f"\u03b2 = {args.beta:g}, S\u2080 = {weight}"
    if len({run.filter for run in runs}) == 1:
        settings += f", C(s) = {runs[0].filter}"
    if args.data_plot:
        plots.data(
            args.data_plot, data.t, data.u, data.y, clean=data.clean, title=title,
            input_label=signal_label(module, "input"),
            output_label=signal_label(module, "output"), dpi=args.dpi,
        )  # fmt: skip
    if args.plot:
        plots.estimates(
            args.plot, curves, unknown=module.UNKNOWN, true_value=data.k,
            title=f"{module.MODEL}: estimate of {module.UNKNOWN} ({settings})", dpi=args.dpi,
        )  # fmt: skip
    if args.cost_plot:
        plots.cost(
            args.cost_plot, curves, k_range=_cost_range(runs, data, args.cost_range),
            unknown=module.UNKNOWN, true_value=data.k,
            title=f"{module.MODEL}: normalised cost at t = {data.t[-1]:g}", dpi=args.dpi,
        )  # fmt: skip
    if args.csv:
        _write_trajectories(args.csv, runs, module.N)
    for run in runs:
        for kind, text in _notes(module, data, run):
            print(f"mtt estimate: {kind}: k0 = {run.k0:g}, C(s) = {run.filter}: {text}",
                  file=sys.stderr)  # fmt: skip
    for text in dict.fromkeys(text for run in runs for text in run.result.warnings):
        warn("estimate", [text])
    if args.json:
        print(json.dumps(_record(module, runs)))
    else:
        print(_table(module, data, runs))
    return EXIT_OK if all(run.result.ok for run in runs) else EXIT_STOPPED


def _band(module: ModuleType, data: Data, run: Run, args) -> np.ndarray | None:
    """Half-width of an approximate 95 % band about k^(t) (drawn for a single run: several
    would hide one another): the standard error of the
    least-squares fit of the same cost over the record (its sandwich variance, which counts
    the colour of the equation error), scaled by the information gathered, 1/sqrt(J_2)."""
    result = run.result
    if not result.ok:
        return None
    final = module.fit(data.t, data.u, data.y, method="ls", C=result.filter, beta=args.beta,
                       hold=args.hold, offset=False, initial_state=False)  # fmt: skip
    if not np.isfinite(final.k_se):
        return None
    J2 = result.J[0]
    return 1.96 * final.k_se * np.sqrt(J2[-1] / J2)


def _notes(module: ModuleType, data: Data, run: Run) -> list[tuple[str, str]]:
    """What a run's table cannot say: it stopped, it is not at the global minimum, or the
    data stopped informing it."""
    result, name = run.result, module.UNKNOWN
    notes = [] if result.ok else [("warning", result.message)]
    if not result.at_global:
        best = float(result.global_k[-1])
        notes.append((
            "warning",
            f"the estimate {name} = {result.k:.6g} is a local minimum of J at t = "
            f"{result.t[-1]:g}, with J({result.k:.6g}) - J({best:.6g}) = "
            f"{-float(result.cost(best)):.3g}: the global minimum is at {name} = {best:.6g}",
        ))  # fmt: skip
    if result.informed_until is not None:
        notes.append((
            "note",
            f"the data stopped informing the estimate at t = {result.informed_until:.6g}: "
            "after that they are rounding noise, which leaves it unchanged",
        ))  # fmt: skip
    return notes


def _record(module: ModuleType, runs: list[Run]) -> dict:
    """The --json record (its shape is a public contract)."""
    return {
        "ok": all(run.result.ok for run in runs),
        "model": module.MODEL,
        "unknown": module.UNKNOWN,
        "runs": [
            {
                "k0": float(run.k0),
                "filter": run.filter,
                "k": run.result.k,
                "minima": [float(value) for value in run.result.minima()],
                "global_k": _number(run.result.global_k[-1]),
                "global_cost": _number(run.result.cost(run.result.global_k[-1])),
                "ok": run.result.ok,
                "stopped_at": run.result.stopped_at,
                "informed_until": run.result.informed_until,
                "warnings": list(run.result.warnings),
            }
            for run in runs
        ],
    }


def _number(value) -> float | None:
    """A float for JSON; None where there is none (J without a global minimiser)."""
    value = float(value)
    return value if np.isfinite(value) else None


def _table(module: ModuleType, data: Data, runs: list[Run]) -> str:
    """The final estimates and local minima, then the global minimum of each run's cost."""
    end = f"t = {data.t[-1]:g}"
    estimates = [("k0", "C(s)", f"{module.UNKNOWN} at {end}", "local minima of J")]
    globals_ = [("k0", "C(s)", f"global minimum of J at {end}", "J(global) - J(estimate)", "ok")]
    for run in runs:
        result = run.result
        minima = ", ".join(f"{value:.6g}" for value in result.minima())
        final = f"{result.k:.6g}" + ("" if result.ok else " (stopped)")
        estimates.append((f"{run.k0:g}", run.filter, final, minima))
        best = float(result.global_k[-1])
        where = f"{best:.6g}" + ("" if result.at_global else " (not the estimate)")
        where += "" if result.ok else f" (at t = {result.t[-1]:g}, where it stopped)"
        ok = "yes" if result.ok else f"no: stopped at t = {result.stopped_at:.6g}"
        globals_.append((f"{run.k0:g}", run.filter, where, f"{float(result.cost(best)):.3g}", ok))
    return "\n".join([f"{module.MODEL}: {data.note}", *_rows(estimates), "", *_rows(globals_)])


def _rows(rows: list[tuple[str, ...]]) -> list[str]:
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
    return [
        (
            "  " + "  ".join(cell.ljust(width) for cell, width in zip(row, widths, strict=True))
        ).rstrip()
        for row in rows
    ]


def _write_trajectories(path: str, runs: list[Run], N: int) -> None:
    header = ["run", "k0", "filter", "t", "khat"] + [f"J{i}" for i in range(2, 2 * N + 1)]
    rows = (
        [number, run.k0, run.filter, t, khat, *J]
        for number, run in enumerate(runs, start=1)
        for t, khat, J in zip(run.result.t, run.result.khat, run.result.J.T, strict=True)
    )
    codegen.write_atomic(path, _csv_text(header, rows))
