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
from collections.abc import Callable
from dataclasses import dataclass
from types import ModuleType

import numpy as np
import sympy
from tqdm import tqdm

from mtt.cli.experiment_args import DEFAULT_DT, DEFAULT_SEED, DEFAULT_T_END
from mtt.cli.options import choice_from_args
from mtt.derivation import pipeline
from mtt.estimator import codegen
from mtt.language.parse import LAPLACE, parse_expression

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


def _signal(module: ModuleType, args) -> tuple[np.ndarray, np.ndarray]:
    """The input samples: a unit step from t = 0 on a regular grid, or a CSV file's."""
    if args.signal not in (None, "step"):
        if args.t_end is not None or args.dt is not None:
            raise UsageError("--t-end and --dt apply to --signal step; the file gives the times")
        return module.read_csv(args.signal, ("t", "u"))
    t_end = DEFAULT_T_END if args.t_end is None else args.t_end
    dt = DEFAULT_DT if args.dt is None else args.dt
    if not (0 < dt <= t_end < np.inf):
        raise UsageError(f"need 0 < --dt <= --t-end, not --dt {dt} and --t-end {t_end}")
    count = max(1, round(t_end / dt))
    if count >= MAX_SAMPLES:
        raise UsageError(f"--t-end / --dt = {count} samples is too many (at most {MAX_SAMPLES})")
    t = np.linspace(0.0, t_end, count + 1)
    return t, np.ones_like(t)


def experiment_data(module: ModuleType, args) -> Data:
    """Measured data (--data), or a simulation of the model with the chosen input and noise."""
    simulation = {"--signal": args.signal, "--t-end": args.t_end, "--dt": args.dt, "--k": args.k}
    simulation |= {"--noise-uniform": args.noise_uniform, "--seed": args.seed}
    if getattr(args, "data", None):
        given = [flag for flag, value in simulation.items() if value is not None]
        if given:
            raise UsageError(f"--data and {given[0]} do not go together ({given[0]} simulates)")
        t, u, y = module.read_csv(args.data)
        return Data(t, u, y, None, None, f"{t.size} samples from {args.data}")
    t, u = _signal(module, args)
    k = module.TRUE_VALUE if args.k is None else args.k
    if k is None:
        raise UsageError(f"the model gives no value of {module.UNKNOWN} to simulate with: pass --k")
    clean = module.simulate(t, u, k, hold=args.hold)
    noise = args.noise_uniform or 0.0
    if not 0 <= noise < np.inf:
        raise UsageError(f"--noise-uniform must be >= 0, not {noise}")
    seed = DEFAULT_SEED if args.seed is None else args.seed
    y = clean + np.random.default_rng(seed).uniform(-noise, noise, clean.size) if noise else clean
    source = "a unit step" if args.signal in (None, "step") else args.signal
    note = f"{t.size} samples simulated with {module.UNKNOWN} = {k:g}, input {source}"
    if noise:
        note += f", noise uniform in [-{noise:g}, {noise:g}] (seed {seed})"
    return Data(t, u, y, clean, k, note)


# the runs ------------------------------------------------------------------------------


@dataclass(frozen=True)
class Run:
    k0: float
    filter: str  # C(s) as the user wrote it (or the default)
    result: object  # the generated module's Estimate


def _polynomial(text: str) -> list[float]:
    """--filter "(1+s)^5": a polynomial in s, parsed by mtt's expression grammar."""
    expr = parse_expression(text, variables=frozenset({LAPLACE}))
    try:
        poly = sympy.Poly(expr, sympy.Symbol(LAPLACE))
    except sympy.PolynomialError:
        raise UsageError(f"--filter {text!r} is not a polynomial in {LAPLACE}") from None
    return [float(c) for c in poly.all_coeffs()]


def _filters(module: ModuleType, args) -> list[tuple[str, object]]:
    """(label, C) for each filter asked for: C as the generated `estimate` takes it."""
    power = module.n + 1
    filters = [(text.strip(), _polynomial(text)) for text in args.filter or []]
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
    module = codegen.load(pipeline.theta_for(args.file, choice_from_args(args)))
    missing = [name for name, value in module.DEFAULTS.items() if value is None]
    if missing:
        name = missing[0]
        raise UsageError(f"the model gives no value for {name}: pass --set {name}=VALUE")
    return module


def guarded(action: Callable[[argparse.Namespace], int]) -> Callable[[argparse.Namespace], int]:
    """Bad options, data and files end with a message and exit status 2, not a traceback."""

    def run(args) -> int:
        try:
            return action(args)
        except (UsageError, ValueError) as exc:
            print(f"mtt {args.command}: error: {exc}", file=sys.stderr)
        except OSError as exc:
            print(f"mtt {args.command}: error: {exc.filename}: {exc.strerror}", file=sys.stderr)
        return EXIT_USAGE

    return run


def cmd_compile(args) -> int:
    theta = pipeline.theta_for(args.file, choice_from_args(args))
    source = codegen.render(theta)
    path = codegen.output_path(args.path, theta)
    codegen.write_atomic(path, source)
    kept = f", {', '.join(theta.symbols)} kept symbolic" if theta.symbols else ""
    print(
        f"wrote {path}: estimator of {theta.unknown} for {theta.model} "
        f"(n = {theta.n}, m = {theta.m}, N = {theta.N}{kept})"
    )
    return EXIT_OK


def cmd_simulate(args) -> int:
    from mtt.cli import plots  # matplotlib takes a quarter second to import: only plotting pays

    module = _model(args)
    data = experiment_data(module, args)
    if args.data_plot:
        plots.data(
            args.data_plot, data.t, data.u, data.y, clean=data.clean,
            title=f"{module.MODEL}: {data.note}", input_label=module.INPUT,
            output_label=module.OUTPUT,
        )  # fmt: skip
    text = _csv_text(["t", "u", "y"], zip(data.t, data.u, data.y, strict=True))
    if args.csv:
        codegen.write_atomic(args.csv, text)
    elif not args.data_plot:
        sys.stdout.write(text)
    return EXIT_OK


def cmd_estimate(args) -> int:
    from mtt.cli import plots  # matplotlib takes a quarter second to import: only plotting pays

    if args.cost_range and not args.cost_range[0] < args.cost_range[1]:
        low, high = args.cost_range
        raise UsageError(f"--cost-range needs A < B, not {low:g} {high:g}")
    module = _model(args)
    data = experiment_data(module, args)
    runs = run_all(module, data, args)
    labels = _labels(runs)
    curves = [
        plots.Curve(label, run.result.t, run.result.khat, run.result.minima(),
                    run.result.normalised_cost, run.result.global_k)
        for label, run in zip(labels, runs, strict=True)
    ]  # fmt: skip
    title = f"{module.MODEL}: {data.note}"
    settings = f"\u03b2 = {args.beta:g}, S\u2080 = {args.S0:g}"
    if len({run.filter for run in runs}) == 1:
        settings += f", C(s) = {runs[0].filter}"
    if args.data_plot:
        plots.data(
            args.data_plot, data.t, data.u, data.y, clean=data.clean, title=title,
            input_label=module.INPUT, output_label=module.OUTPUT,
        )  # fmt: skip
    if args.plot:
        plots.estimates(
            args.plot, curves, unknown=module.UNKNOWN, true_value=data.k,
            title=f"{module.MODEL}: estimate of {module.UNKNOWN} ({settings})",
        )  # fmt: skip
    if args.cost_plot:
        plots.cost(
            args.cost_plot, curves, k_range=_cost_range(runs, data, args.cost_range),
            unknown=module.UNKNOWN, true_value=data.k,
            title=f"{module.MODEL}: normalised cost at t = {data.t[-1]:g}",
        )  # fmt: skip
    if args.csv:
        _write_trajectories(args.csv, runs, module.N)
    for run in runs:
        for kind, text in _notes(module, data, run):
            print(f"mtt estimate: {kind}: k0 = {run.k0:g}, C(s) = {run.filter}: {text}",
                  file=sys.stderr)  # fmt: skip
    if args.json:
        print(json.dumps(_record(module, runs)))
    else:
        print(_table(module, data, runs))
    return EXIT_OK if all(run.result.ok for run in runs) else EXIT_STOPPED


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
