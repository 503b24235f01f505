"""`mtt fit`: the generated module's batch `fit` over whole records, measured or simulated.

Like `estimate`, it builds the estimator module in memory and calls it: the algorithm, its
uncertainty and its warnings live in the template; what is here reads the records, prints
the result (text or JSON), the warnings on stderr, and draws the compare plot.
"""

from __future__ import annotations

import json
import re

import numpy as np

from mtt.cli import unknowns
from mtt.cli.experiment import (
    EXIT_OK,
    EXIT_STOPPED,
    UsageError,
    _csv_text,
    _model,
    experiment_data,
    hold_of,
    say,
    signal_label,
    warn,
)
from mtt.estimator import codegen


def options(module, args) -> dict:
    """The module's `fit` options from the command line (k0 and bounds by unknown)."""
    return dict(
        method=args.method, C=_filter(args),
        k0=None if args.k0 is None else unknowns.point(module, args.k0, "--k0"),
        bounds=unknowns.bounds(module, args.bounds), offset=args.offset,
        initial_state=args.initial_state, hold=hold_of(args), beta=args.beta,
    )  # fmt: skip


def _filter(args):
    """C for the module's `fit`: --filter-T T, --filter TEXT ("auto" by default)."""
    if args.filter is not None and args.filter_T is not None:
        raise UsageError("--filter and --filter-T do not go together")
    if args.filter_T is not None:
        return args.filter_T
    return "auto" if args.filter is None else args.filter.strip()


def cmd_fit(args) -> int:
    from mtt.cli import batch

    kind = batch.mode(args)  # --data patterns, --per-record, --jobs...: mtt.batch
    if kind is not None:
        return batch.cmd_fit_many(args, kind)
    module = _model(args)
    records = experiment_data(module, args, several=True)
    arrays = [[getattr(data, name) for data in records] for name in ("t", "u", "y")]
    if len(records) == 1:
        arrays = [part[0] for part in arrays]
    try:
        result = module.fit(*arrays, **options(module, args))
    except ValueError as error:  # "record 1 has 3 samples": name the file
        if len(records) == 1:
            raise
        raise UsageError(_files_named(str(error), records)) from None
    warn("fit", result.warnings)
    if args.plot and result.ok:
        from mtt.present import plots  # matplotlib: a quarter second, paid by plotting only

        shown = [
            plots.Record(data.note, data.t, data.y, fitted)
            for data, fitted in zip(records, result.fitted, strict=True)
        ]
        plots.fit(
            args.plot, shown, output_label=signal_label(module, "output"), dpi=args.dpi,
            title=f"{module.MODEL}: {_estimates(module, result)}, fit {result.fit_percent:.4g} %",
        )  # fmt: skip
    elif args.plot:
        warn("fit", [f"no plot: {result.message}"])
    if args.csv and result.ok:
        rows = (
            (number, t, u, y, fitted, y - fitted)
            for number, (data, fitted) in enumerate(zip(records, result.fitted, strict=True), 1)
            for t, u, y, fitted in zip(data.t, data.u, data.y, fitted, strict=True)
        )
        codegen.write_atomic(
            args.csv, _csv_text(["record", "t", "u", "y", "fitted", "residual"], rows)
        )
    if args.json:
        record = {"model": module.MODEL, "unknown": module.UNKNOWN, **module.fit_record(result)}
        record["data"] = [data.note for data in records]
        say(json.dumps(record))
    else:
        say(_text(module, records, result))
    return EXIT_OK if result.ok else EXIT_STOPPED


def _files_named(message: str, records) -> str:
    """The module's "record i" (from 0, in the order of --data) followed by its file."""
    sources = [data.note.split(" samples from ", 1)[-1] for data in records]
    return re.sub(
        r"\brecord (\d+)\b",
        lambda match: (
            f"{match.group(0)} ({sources[int(match.group(1))]})"
            if int(match.group(1)) < len(sources)
            else match.group(0)
        ),
        message,
    )


def _estimates(module, result) -> str:
    """`k = 10 ± 0.02`, or `ra = 1 ± 0.01, jl = 10 ± 0.2` for several unknowns."""
    return ", ".join(
        f"{name} = {value:.6g} \u00b1 {se:.3g}"
        for name, value, se in zip(
            module.UNKNOWNS, np.atleast_1d(result.k), np.atleast_1d(result.k_se), strict=True
        )  # fmt: skip
    )


def uncertainty_lines(module, k, k_se, ci, indent: str = "  ") -> list[str]:
    """A line per unknown: its estimate, standard error and 95 % interval."""
    return [
        f"{indent}{name} = {value:.6g} \u00b1 {se:.3g} (standard error; 95 % interval "
        f"{low:.6g} to {high:.6g})"
        for name, value, se, (low, high) in zip(
            module.UNKNOWNS,
            np.atleast_1d(k),
            np.atleast_1d(k_se),
            np.reshape(ci, (-1, 2)),
            strict=True,
        )  # fmt: skip
    ]


def _text(module, records, result) -> str:
    sources = "; ".join(data.note for data in records)
    lines = [f"{module.MODEL}: {sources}"]
    if not result.ok:
        lines.append(f"  no estimate: {result.message}")
        return "\n".join(lines)
    method = "refined instrumental variables" if result.method == "iv" else "least squares"
    steps = f", {result.iterations} iterations" if result.method == "iv" else ""
    lines += uncertainty_lines(module, result.k, result.k_se, result.ci)
    if len(module.UNKNOWNS) == 1:
        minima = ", ".join(f"{value:.6g}" for value in result.minima)
    else:
        minima = "; ".join(f"({unknowns.text(module, point, '.6g')})" for point in result.minima)
    minima = minima or "none within the bounds"
    lines += [
        f"  fit {result.fit_percent:.4g} %, residual RMS {result.residual_rms:.3g}, "
        f"noise std {result.noise_std:.3g}",
        f"  method: {method}{steps}; local minima of the criterion: {minima}",
    ]
    if any(result.offsets):
        lines.append("  output offset at rest: " + ", ".join(f"{v:.6g}" for v in result.offsets))
    return "\n".join(lines)
