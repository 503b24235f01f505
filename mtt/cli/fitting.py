"""`mtt fit`: the generated module's batch `fit` over whole records, measured or simulated.

Like `estimate`, it builds the estimator module in memory and calls it: the algorithm, its
uncertainty and its warnings live in the template; what is here reads the records, prints
the result (text or JSON), the warnings on stderr, and draws the compare plot.
"""

from __future__ import annotations

import json

from mtt.cli.experiment import (
    EXIT_OK,
    EXIT_STOPPED,
    UsageError,
    _csv_text,
    _model,
    experiment_data,
    signal_label,
    warn,
)
from mtt.estimator import codegen


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
    result = module.fit(
        *arrays, method=args.method, C=_filter(args), k0=args.k0, bounds=args.bounds,
        offset=args.offset, initial_state=args.initial_state, hold=args.hold, beta=args.beta,
    )  # fmt: skip
    warn("fit", result.warnings)
    if args.plot and result.ok:
        from mtt.cli import plots  # matplotlib takes a quarter second to import: only plotting pays

        shown = [
            plots.Record(data.note, data.t, data.y, fitted)
            for data, fitted in zip(records, result.fitted, strict=True)
        ]
        plots.fit(
            args.plot, shown, output_label=signal_label(module, "output"), dpi=args.dpi,
            title=f"{module.MODEL}: {module.UNKNOWN} = {result.k:.6g} \u00b1 {result.k_se:.3g}, "
            f"fit {result.fit_percent:.4g} %",
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
        print(json.dumps(record))
    else:
        print(_text(module, records, result))
    return EXIT_OK if result.ok else EXIT_STOPPED


def _text(module, records, result) -> str:
    name = module.UNKNOWN
    sources = "; ".join(data.note for data in records)
    lines = [f"{module.MODEL}: {sources}"]
    if not result.ok:
        lines.append(f"  no estimate: {result.message}")
        return "\n".join(lines)
    method = "refined instrumental variables" if result.method == "iv" else "least squares"
    steps = f", {result.iterations} iterations" if result.method == "iv" else ""
    lines += [
        f"  {name} = {result.k:.6g} \u00b1 {result.k_se:.3g} (standard error; 95 % interval "
        f"{result.ci[0]:.6g} to {result.ci[1]:.6g})",
        f"  fit {result.fit_percent:.4g} %, residual RMS {result.residual_rms:.3g}, "
        f"noise std {result.noise_std:.3g}",
        f"  method: {method}{steps}; local minima of the criterion: "
        + ", ".join(f"{value:.6g}" for value in result.minima),
    ]
    if any(result.offsets):
        lines.append("  output offset at rest: " + ", ".join(f"{v:.6g}" for v in result.offsets))
    return "\n".join(lines)
