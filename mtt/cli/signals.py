"""`mtt fit` with several inputs or outputs: the compiled module's `fit_signals` over CSV
records whose columns are the time and every signal, named by the signals' own labels
(t,Se:v,Se:tl,Df:speed) or by --columns in that order (t,u1,u2,y1); --validate compares
the fit with held-out records of every signal, --plot, --csv and --data-plot draw and
write them (mtt.data.signals reads, mtt.present the text and figures)."""

from __future__ import annotations

import json
from itertools import zip_longest
from types import ModuleType

from mtt import files
from mtt.api.fits import compare_each
from mtt.cli.experiment import refuse_simulation
from mtt.cli.fit_options import signal_options
from mtt.cli.running import EXIT_OK, EXIT_STOPPED, UsageError, say, warn
from mtt.data.signals import read_signals, signal_columns
from mtt.language.diagnostics import MttError
from mtt.present import fits


def cmd_fit_signals(args, module: ModuleType) -> int:
    """Fit every input and output of the --data records; print the estimate and each
    output's noise and fit (or JSON), compare with --validate records, draw and write."""
    if not args.data:
        raise UsageError(
            "with several inputs or outputs `mtt fit` reads measured records: give --data "
            f"FILE.csv with the columns {','.join(signal_columns(module, None))} (or --columns)"
        )
    refuse_simulation(args)
    chosen = signal_options(module, args)
    names = signal_columns(module, args.columns)
    records = [read_signals(module, path, names) for path in args.data]
    held_out = [read_signals(module, path, names) for path in args.validate or ()]
    if args.data_plot:
        _data_plot(module, args, records[0])
    arrays = [[getattr(record, name) for record in records] for name in ("t", "u", "y")]
    result = module.fit_signals(*(arrays if len(records) > 1 else [a[0] for a in arrays]), **chosen)
    warn("fit", result.warnings)
    try:  # as the one-signal fit's (SignalsFit.compare: a figure per output)
        compared, notes = compare_each(result, held_out, "--validate")
    except MttError as error:
        raise UsageError(str(error)) from None
    warn("fit", notes)
    if args.plot:
        _plot(module, args, result, records, held_out, compared)
    if args.csv:
        files.write_atomic(args.csv, fits.signals_fit_csv(module, records, result))
    if args.json:
        record = fits.signals_fit_record(module, result, args.data)
        if held_out:
            pairs = zip_longest(held_out, compared)
            record["validation"] = [fits.signals_comparison_record(module, data.note, c)
                                    for data, c in pairs]  # fmt: skip
        say(json.dumps(record))
    else:
        lines = [(data.note, c) for data, c in zip(held_out, compared, strict=False)]
        say("\n".join([fits.signals_fit_text(module, records, result),
                       *fits.signals_validation_lines(module, lines)]))  # fmt: skip
    return EXIT_OK if result.ok else EXIT_STOPPED


def _plot(module, args, result, records, held_out, compared) -> None:
    from mtt.present import plots  # matplotlib takes a quarter second to import

    if not result.fitted:
        warn("fit", [f"no plot: {result.message}"])
        return
    shown = [plots.Record(data.note, data.t, data.y, fitted)
             for data, fitted in zip(records, result.fitted, strict=True)]  # fmt: skip
    checked = [plots.Record(f"validation: {data.note}", data.t, data.y, c.fitted)
               for data, c in zip(held_out, compared, strict=False)]  # fmt: skip
    percent = ", ".join(f"{fit:.4g} %" for fit in result.fit_percent)
    plots.fit_signals(
        args.plot, shown, outputs=module.OUTPUTS, dpi=args.dpi, validation=checked,
        title=f"{module.MODEL}: {fits.estimates(module, result)}, fit {percent}"
        + ("" if result.ok else " (not ok: see the warnings)"),
    )  # fmt: skip


def _data_plot(module, args, data) -> None:
    from mtt.present import plots

    columns = [(name, data.u[:, j], True) for j, name in enumerate(module.INPUTS)]
    columns += [(name, data.y[:, i], False) for i, name in enumerate(module.OUTPUTS)]
    plots.signals_data(args.data_plot, data.t, columns, title=f"{module.MODEL}: {data.note}",
                       dpi=args.dpi)  # fmt: skip
