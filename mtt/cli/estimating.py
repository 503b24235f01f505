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
from types import ModuleType

from tqdm import tqdm

from mtt import files
from mtt.cli import unknowns
from mtt.cli.experiment import experiment_data, hold_of, module_for
from mtt.cli.running import EXIT_OK, EXIT_STOPPED, UsageError, say, warn
from mtt.data.records import Record
from mtt.present import estimates, values
from mtt.present.estimates import Run


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


def _runs(module: ModuleType, data: Record, args) -> list[Run]:
    """mtt.api.runs.run_all with the options given, and a progress bar on a terminal."""
    from mtt.api.runs import run_all

    filters = _filters(module, args)
    starts = [unknowns.point(module, k0, "--k0") for k0 in args.k0]
    span = float(data.t[-1] - data.t[0])
    with tqdm(
        total=span * len(filters) * len(starts),
        desc="estimating",
        unit="s",
        delay=1.0,
        leave=False,
        disable=not sys.stderr.isatty(),
        bar_format="{l_bar}{bar}| {n:.3g}/{total:.3g} s of data [{elapsed}<{remaining}]",
    ) as bar:
        return run_all(
            module, data, filters, starts, S0_relative=args.S0_relative,
            progress=lambda done: bar.update(done - bar.n), beta=args.beta, S0=args.S0,
            hold=hold_of(args), engine=args.engine, bounds=unknowns.bounds(module, args.bounds),
            rtol=args.rtol, atol=args.atol,
        )  # fmt: skip


def cmd_estimate(args) -> int:
    from mtt.present import plots  # matplotlib: a quarter second, paid by plotting only

    if args.cost_range and not args.cost_range[0] < args.cost_range[1]:
        low, high = args.cost_range
        raise UsageError(f"--cost-range needs A < B, not {low:g} {high:g}")
    module = module_for(args)
    several = len(module.UNKNOWNS) > 1
    if several and (args.cost_plot or args.cost_range):
        raise UsageError(
            "--cost-plot draws the cost against one unknown; with several "
            f"({', '.join(module.UNKNOWNS)}) it is a surface: see the table's minima"
        )
    (data,) = experiment_data(module, args)
    runs = _runs(module, data, args)
    curves = estimates.curves(module, runs, banded=bool(args.plot) and len(runs) == 1)
    title = f"{module.MODEL}: {data.note}"
    settings = estimates.settings(runs, args.beta, args.S0, args.S0_relative)
    if args.data_plot:
        plots.data(
            args.data_plot, data.t, data.u, data.y, clean=data.clean, title=title,
            input_label=plots.signal_label(module, "input"),
            output_label=plots.signal_label(module, "output"), dpi=args.dpi,
        )  # fmt: skip
    if args.plot:
        names = ", ".join(module.UNKNOWNS)
        plots.estimates(
            args.plot, curves, unknowns=module.UNKNOWNS, true_value=data.k,
            title=f"{module.MODEL}: estimate of {names} ({settings})", dpi=args.dpi,
        )  # fmt: skip
    if args.cost_plot:
        plots.cost(
            args.cost_plot, curves, k_range=estimates.cost_range(runs, data.k, args.cost_range),
            unknown=module.UNKNOWN, true_value=data.k,
            title=f"{module.MODEL}: normalised cost at t = {data.t[-1]:g}", dpi=args.dpi,
        )  # fmt: skip
    if args.csv:
        files.write_atomic(args.csv, estimates.trajectories_csv(module, runs))
    for run in runs:
        for kind, text in estimates.notes(module, run):
            start = estimates.start_text(module, run)
            start = f"k0 = {values.text(module, run.k0)}" if several else start
            say(f"mtt estimate: {kind}: {start}, C(s) = {run.filter}: {text}", stderr=True)
    for text in dict.fromkeys(text for run in runs for text in run.result.warnings):
        warn("estimate", [text])
    if args.json:
        say(json.dumps(estimates.record(module, runs)))
    else:
        say(estimates.table(module, data.note, float(data.t[-1]), runs))
    return EXIT_OK if all(run.result.ok for run in runs) else EXIT_STOPPED
