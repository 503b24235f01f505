"""`mtt estimate`: the generated module's recursive estimate, once per start and filter.

Like `fit`, it builds the estimator module in memory and calls it: what is here runs the
estimates with a progress bar, prints their table (or JSON) and notes, and draws the
paper's figures. With several unknowns k0 and the estimates are vectors: the table has a
column per unknown, the figure a panel per unknown, and the cost is not drawn (it is a
surface).
"""

from __future__ import annotations

import json
import sys
from dataclasses import dataclass
from types import ModuleType

import numpy as np
from tqdm import tqdm

from mtt.cli import unknowns
from mtt.cli.experiment import (
    EXIT_OK,
    EXIT_STOPPED,
    Data,
    UsageError,
    _csv_text,
    _model,
    _rows,
    experiment_data,
    hold_of,
    say,
    signal_label,
    warn,
)
from mtt.cli.fitting import uncertainty_lines
from mtt.estimator import codegen


@dataclass(frozen=True)
class Run:
    k0: float | np.ndarray  # several unknowns: in the module's UNKNOWNS order
    filter: str  # C(s) as the user wrote it (or the default)
    result: object  # the generated module's Estimate
    k_se: float | np.ndarray | None = None  # see `_least_squares`
    k_ls: float | np.ndarray | None = None  # the record's least-squares minimum (no prior)

    @property
    def ci(self):
        """The approximate 95 % interval about the final estimate (None without k_se)."""
        if self.k_se is None:
            return None
        k, half = np.atleast_1d(self.result.k), 1.96 * np.atleast_1d(self.k_se)
        return np.stack([k - half, k + half], 1)


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
    options = dict(beta=args.beta, S0=args.S0, hold=hold_of(args), engine=args.engine,
                   bounds=unknowns.bounds(module, args.bounds), rtol=args.rtol,
                   atol=args.atol)  # fmt: skip
    starts = [unknowns.point(module, k0, "--k0") for k0 in args.k0]
    span = float(data.t[-1] - data.t[0])
    runs = []
    fits: dict[bytes, object] = {}  # the least-squares fit per filter: runs from each k0 share it
    with tqdm(
        total=span * len(filters) * len(starts),
        desc="estimating",
        unit="s",
        delay=1.0,
        leave=False,
        disable=not sys.stderr.isatty(),
        bar_format="{l_bar}{bar}| {n:.3g}/{total:.3g} s of data [{elapsed}<{remaining}]",
    ) as bar:
        for label, C in filters:
            for k0 in starts:
                start = bar.n
                if args.S0_relative is not None:
                    options["S0"] = module.prior_weight(
                        data.t, data.u, data.y, k0=k0, fraction=args.S0_relative, C=C,
                        hold=hold_of(args),
                    )  # fmt: skip
                result = module.estimate(
                    data.t, data.u, data.y, k0=k0, C=C, **options,
                    progress=lambda now, start=start: bar.update(start + now - data.t[0] - bar.n),
                )  # fmt: skip
                bar.update(start + span - bar.n)
                runs.append(Run(k0, label, result, *_least_squares(module, data, result, args,
                                                                    fits)))  # fmt: skip
    return runs


def _start(module: ModuleType, run: Run) -> str:
    """`k0 = 5`, or `k0: ra = 0.5, jl = 5` for several unknowns."""
    if len(module.UNKNOWNS) == 1:
        return f"k0 = {run.k0:g}"
    return f"k0: {unknowns.text(module, run.k0)}"


def _labels(module: ModuleType, runs: list[Run]) -> list[str]:
    several_k0 = len({unknowns.text(module, run.k0) for run in runs}) > 1
    several_filters = len({run.filter for run in runs}) > 1
    labels = []
    for run in runs:
        parts = [_start(module, run)] if several_k0 or not several_filters else []
        parts += [f"C(s) = {run.filter}"] if several_filters else []
        labels.append(", ".join(parts))
    return labels


def _minima(module: ModuleType, result) -> np.ndarray:
    """The local minima of a run's cost at its end (several unknowns: within its bounds;
    none without them)."""
    if len(module.UNKNOWNS) > 1 and result.bounds is None:
        return np.zeros((0, len(module.UNKNOWNS)))
    return result.minima()


def _cost_range(runs: list[Run], data: Data, given: list[float] | None) -> tuple[float, float]:
    if given is not None:
        return given[0], given[1]
    points = [run.k0 for run in runs] + [value for run in runs for value in run.result.minima()]
    points += [] if data.k is None else [data.k]
    low, high = min(points), max(points)
    margin = max(0.25 * (high - low), 0.5)
    return low - margin, high + margin


def cmd_estimate(args) -> int:
    from mtt.present import plots  # matplotlib: a quarter second, paid by plotting only

    if args.cost_range and not args.cost_range[0] < args.cost_range[1]:
        low, high = args.cost_range
        raise UsageError(f"--cost-range needs A < B, not {low:g} {high:g}")
    module = _model(args)
    several = len(module.UNKNOWNS) > 1
    if several and (args.cost_plot or args.cost_range):
        raise UsageError(
            "--cost-plot draws the cost against one unknown; with several "
            f"({', '.join(module.UNKNOWNS)}) it is a surface: see the table's minima"
        )
    (data,) = experiment_data(module, args)
    runs = run_all(module, data, args)
    labels = _labels(module, runs)
    curves = [
        plots.Curve(label, run.result.t, run.result.khat, _minima(module, run.result),
                    None if several else run.result.normalised_cost, run.result.global_k,
                    _band(module, run) if args.plot and len(runs) == 1 else None)
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
        names = ", ".join(module.UNKNOWNS)
        plots.estimates(
            args.plot, curves, unknowns=module.UNKNOWNS, true_value=data.k,
            title=f"{module.MODEL}: estimate of {names} ({settings})", dpi=args.dpi,
        )  # fmt: skip
    if args.cost_plot:
        plots.cost(
            args.cost_plot, curves, k_range=_cost_range(runs, data, args.cost_range),
            unknown=module.UNKNOWN, true_value=data.k,
            title=f"{module.MODEL}: normalised cost at t = {data.t[-1]:g}", dpi=args.dpi,
        )  # fmt: skip
    if args.csv:
        _write_trajectories(args.csv, module, runs)
    for run in runs:
        for kind, text in _notes(module, run):
            start = f"k0 = {unknowns.text(module, run.k0)}" if several else _start(module, run)
            say(f"mtt estimate: {kind}: {start}, C(s) = {run.filter}: {text}", stderr=True)
    for text in dict.fromkeys(text for run in runs for text in run.result.warnings):
        warn("estimate", [text])
    if args.json:
        say(json.dumps(_record(module, runs)))
    else:
        say(_table(module, data, runs))
    return EXIT_OK if all(run.result.ok for run in runs) else EXIT_STOPPED


def _least_squares(module: ModuleType, data: Data, result, args, fits: dict) -> tuple:
    """(k_se, k_ls): the final estimate's standard error (a vector for several unknowns),
    that of the least-squares fit of the same cost J over the record, with the same filter
    and forgetting (its sandwich variance, which counts the colour of the equation error),
    and that fit's minimiser, where the estimate would be without the prior S0. (None, None)
    when the run stopped, ended at a local minimum that is not the global one (whose basin
    the fit's figures do not describe), or the data do not determine k. `fits` keeps the
    fit of each filter (C="auto" may choose another for another k0)."""
    if not (result.ok and result.at_global):  # stopped, or in another minimum's basin
        return None, None
    key = np.asarray(result.filter, dtype=float).tobytes()
    if key not in fits:
        fits[key] = module.fit(data.t, data.u, data.y, method="ls", C=result.filter,
                               beta=args.beta, hold=hold_of(args), offset=False,
                               initial_state=False)  # fmt: skip
    final = fits[key]
    if not (final.ok and np.all(np.isfinite(final.k_se))):
        return None, None
    return final.k_se, final.k


def _band(module: ModuleType, run: Run) -> np.ndarray | None:
    """Half-width of an approximate 95 % band about k^(t) (drawn for a single run: several
    would hide one another; one unknown): the final standard error scaled by the
    information gathered, 1/sqrt(J_2)."""
    if run.k_se is None or len(module.UNKNOWNS) > 1:
        return None
    J2 = run.result.J[0]
    return 1.96 * run.k_se * np.sqrt(J2[-1] / J2)


def _notes(module: ModuleType, run: Run) -> list[tuple[str, str]]:
    """What a run's table cannot say: it stopped, it is not at the global minimum, or the
    data stopped informing it."""
    result = run.result
    notes = [] if result.ok else [("warning", result.message)]
    if not result.at_global:
        best = result.global_k[-1]
        here, there = unknowns.text(module, result.k, ".6g"), unknowns.text(module, best, ".6g")
        notes.append((
            "warning",
            f"the estimate {unknowns.named(module, result.k)} is a local minimum of J at t = "
            f"{result.t[-1]:g}, with J({here}) - J({there}) = {-float(result.cost(best)):.3g}: "
            f"the global minimum is at {unknowns.named(module, best)}",
        ))  # fmt: skip
    if result.informed_until is not None:
        notes.append((
            "note",
            f"the data stopped informing the estimate at t = {result.informed_until:.6g}: "
            "after that they are rounding noise, which leaves it unchanged",
        ))  # fmt: skip
    return notes


def _record(module: ModuleType, runs: list[Run]) -> dict:
    """The --json record (its shape is a public contract): k0, k, minima and global_k are
    numbers for one unknown, lists in the order of `unknowns` for several."""
    plain = unknowns.plain
    single = len(module.UNKNOWNS) == 1
    return {
        "ok": all(run.result.ok for run in runs),
        "model": module.MODEL,
        "unknown": module.UNKNOWN,
        "unknowns": list(module.UNKNOWNS),
        "runs": [
            {
                "k0": plain(run.k0),
                "filter": run.filter,
                "k": plain(run.result.k),
                "minima": plain(_minima(module, run.result)),
                "global_k": plain(run.result.global_k[-1]),
                "global_cost": _global_cost(run.result),
                "ok": run.result.ok,
                "stopped_at": run.result.stopped_at,
                "informed_until": run.result.informed_until,
                "k_se": plain(run.k_se),
                "ci": plain(None if run.ci is None else (run.ci[0] if single else run.ci)),
                "k_ls": plain(run.k_ls),
                "warnings": list(run.result.warnings),
            }
            for run in runs
        ],
    }


def _global_cost(result) -> float | None:
    """J(global) - J(estimate); None where J has no global minimiser."""
    best = result.global_k[-1]
    return None if np.isnan(best).any() else unknowns.plain(result.cost(best))


def _table(module: ModuleType, data: Data, runs: list[Run]) -> str:
    """The final estimates and local minima, then the global minimum of each run's cost."""
    end = f"t = {data.t[-1]:g}"
    several = len(module.UNKNOWNS) > 1
    final = tuple(f"{name} at {end}" for name in module.UNKNOWNS)
    estimates = [("k0", "C(s)", *final, "local minima of J")]
    globals_ = [("k0", "C(s)", f"global minimum of J at {end}", "J(global) - J(estimate)", "ok")]
    for run in runs:
        result = run.result
        minima = _minima(module, result)
        if several:
            listed = f"{len(minima)} within the bounds" if result.bounds is not None else "-"
        else:
            listed = ", ".join(f"{value:.6g}" for value in minima)
        stopped = "" if result.ok else " (stopped)"
        values = [f"{value:.6g}" for value in np.atleast_1d(result.k)]
        values[-1] += stopped
        start = unknowns.text(module, run.k0)
        estimates.append((start, run.filter, *values, listed))
        best = result.global_k[-1]
        if several and np.isnan(best).any():
            where, cost = "none (no bounds)" if result.bounds is None else "none", "-"
        else:
            where = unknowns.text(module, best, ".6g")
            where += "" if result.at_global else " (not the estimate)"
            cost = f"{float(result.cost(best)):.3g}"
        where += "" if result.ok else f" (at t = {result.t[-1]:g}, where it stopped)"
        ok = "yes" if result.ok else f"no: stopped at t = {result.stopped_at:.6g}"
        globals_.append((start, run.filter, where, cost, ok))
    errors = [f"standard errors at {end} (of least squares on the same cost over the record):"]
    for run in runs:
        start = f"  {_start(module, run)}, C(s) = {run.filter}"
        if run.k_se is None:
            why = ("stopped" if not run.result.ok else "not at the global minimum"
                   if not run.result.at_global else "not determined")  # fmt: skip
            errors.append(f"{start}: none ({why})")
            continue
        errors += [f"{start}:", *uncertainty_lines(module, run.result.k, run.k_se, run.ci, "    ")]
        held = np.asarray(run.result.k) - np.asarray(run.k_ls)  # a number for one unknown
        if np.any(np.abs(held) > np.asarray(run.k_se)):
            errors.append(
                f"    the prior S0 holds it {unknowns.text(module, held, '+.3g')} from the "
                f"record's least-squares minimum, {unknowns.named(module, run.k_ls)}, more "
                "than a standard error: lower S0 (--S0-relative) or use a longer record"
            )
    return "\n".join(
        [f"{module.MODEL}: {data.note}", *_rows(estimates), "", *_rows(globals_), "", *errors]
    )


def _write_trajectories(path: str, module: ModuleType, runs: list[Run]) -> None:
    """k^(t) of every run, and for one unknown J_2..J_2N."""
    if len(module.UNKNOWNS) == 1:
        header = ["run", "k0", "filter", "t", "khat"]
        header += [f"J{i}" for i in range(2, 2 * module.N + 1)]
        rows = (
            [number, run.k0, run.filter, t, khat, *J]
            for number, run in enumerate(runs, start=1)
            for t, khat, J in zip(run.result.t, run.result.khat, run.result.J.T, strict=True)
        )
    else:
        header = ["run", "k0", "filter", "t", *(f"khat_{name}" for name in module.UNKNOWNS)]
        rows = (
            [number, unknowns.text(module, run.k0), run.filter, t, *khat]
            for number, run in enumerate(runs, start=1)
            for t, khat in zip(run.result.t, run.result.khat, strict=True)
        )
    codegen.write_atomic(path, _csv_text(header, rows))
