"""`mtt fit`: the generated module's batch `fit` over whole records, measured or simulated.

Like `estimate`, it builds the estimator module in memory and calls it: the algorithm, its
uncertainty and its warnings live in the template; what is here reads the options, takes
the records from mtt.data, compares the fit with held-out ones (mtt.api.fits) and prints
what mtt.present.fits makes of it (text or JSON, the CSV and the compare plot), the
warnings on stderr.
"""

from __future__ import annotations

import json

from mtt import files
from mtt.api import nonlinear_fits
from mtt.api.fits import compare_each
from mtt.api.model import Model
from mtt.cli.experiment import checked_module, experiment_data, module_for
from mtt.cli.fit_options import nonlinear_options, options
from mtt.cli.options import choice_from_args
from mtt.cli.running import EXIT_OK, EXIT_STOPPED, UsageError, say, warn
from mtt.data.records import columns, read
from mtt.derivation import pipeline
from mtt.derivation.nonlinear import nonlinear_parts
from mtt.language.diagnostics import MttError
from mtt.present import fits


def cmd_fit(args) -> int:
    from mtt.cli import batch

    kind = batch.mode(args)  # --data patterns, --per-record, --jobs...: mtt.batch
    if kind is not None:
        return batch.cmd_fit_many(args, kind)
    model = nonlinear_model(args)  # a nonlinear model without --at: its simulator's fit
    if model is not None:
        module = checked_module(model.simulator())
    else:
        module = module_for(args, several=True)
        if hasattr(module, "theta_channels"):  # several inputs or outputs
            from mtt.cli.signals import cmd_fit_signals

            return cmd_fit_signals(args, module)
    records = experiment_data(module, args, several=True)
    held_out = validation_data(module, args)  # read first: a wrong path fails before the fit
    if args.data_plot:
        _data_plot(module, args, records)
    arrays = [[getattr(data, name) for data in records] for name in ("t", "u", "y")]
    if len(records) == 1:
        arrays = [part[0] for part in arrays]
    try:
        if model is not None:
            result = nonlinear_fits.fit(model, *arrays, **nonlinear_options(module, args)).result
        else:
            result = module.fit(*arrays, **options(module, args))
    except MttError as error:  # the nonlinear fit's refusals (bad_argument)
        raise UsageError(fits.files_named(str(error), records)) from None
    except ValueError as error:  # "record 1 has 3 samples": name the file
        if len(records) == 1:
            raise
        raise UsageError(fits.files_named(str(error), records)) from None
    warn("fit", result.warnings)
    try:
        compared, notes = compare_each(result, held_out, "--validate")
    except MttError as error:
        raise UsageError(str(error)) from None
    warn("fit", notes)
    if args.plot and fits.shown_fit(result, records):
        fits.plot_fit(args.plot, module, result, records, held_out, compared, args.dpi)
    elif args.plot:
        warn("fit", [f"no plot: {result.message}"])
    if args.csv and fits.shown_fit(result, records):
        files.write_atomic(args.csv, fits.fit_csv(records, result))
    if args.json:
        say(json.dumps(fits.fit_record(module, result, records, held_out, compared)))
    else:
        lines = [(data.note, c) for data, c in zip(held_out, compared, strict=False)]
        say("\n".join([fits.fit_text(module, records, result), *fits.validation_lines(lines)]))
    return EXIT_OK if result.ok else EXIT_STOPPED


def _data_plot(module, args, records) -> None:
    """--data-plot: the input and output of the (first) record, as `simulate` draws them."""
    from mtt.present import plots

    data = records[0]
    more = f" (the first of {len(records)} records)" if len(records) > 1 else ""
    plots.data(
        args.data_plot, data.t, data.u, data.y, clean=data.clean, dpi=args.dpi,
        title=f"{module.MODEL}: {data.note}{more}",
        input_label=plots.signal_label(module, "input"),
        output_label=plots.signal_label(module, "output"),
    )  # fmt: skip


def nonlinear_model(args):
    """The Model (mtt.api) of a nonlinear model given without --at, else None."""
    choice = choice_from_args(args)
    if choice.at is not None:
        return None
    graph = pipeline.load(args.file, choice.selection)
    return Model(graph, choice) if nonlinear_parts(graph) else None


def validation_data(module, args) -> list:
    """The --validate records, read and checked as --data is."""
    names = columns(args.columns)
    return [read(module, path, names) for path in args.validate or ()]
