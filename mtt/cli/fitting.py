"""`mtt fit`: the generated module's batch `fit` over whole records, measured or simulated.

Like `estimate`, it builds the estimator module in memory and calls it: the algorithm, its
uncertainty and its warnings live in the template; what is here reads the records, prints
the result (text or JSON), the warnings on stderr, and draws the compare plot.
"""

from __future__ import annotations

import json
import re
from itertools import zip_longest

import numpy as np

from mtt import files
from mtt.api import nonlinear_fits
from mtt.api.model import Model
from mtt.cli.experiment import checked_module, experiment_data, module_for
from mtt.cli.fit_options import nonlinear_options, options
from mtt.cli.options import choice_from_args
from mtt.cli.running import EXIT_OK, EXIT_STOPPED, UsageError, say, warn
from mtt.data.records import columns, read
from mtt.derivation import pipeline
from mtt.derivation.nonlinear import nonlinear_parts
from mtt.language.diagnostics import MttError
from mtt.present import fits, tables


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
    arrays = [[getattr(data, name) for data in records] for name in ("t", "u", "y")]
    if len(records) == 1:
        arrays = [part[0] for part in arrays]
    try:
        if model is not None:
            result = nonlinear_fits.fit(model, *arrays, **nonlinear_options(module, args)).result
        else:
            result = module.fit(*arrays, **options(module, args))
    except MttError as error:  # the nonlinear fit's refusals (bad_argument)
        raise UsageError(_files_named(str(error), records)) from None
    except ValueError as error:  # "record 1 has 3 samples": name the file
        if len(records) == 1:
            raise
        raise UsageError(_files_named(str(error), records)) from None
    warn("fit", result.warnings)
    compared = validate(result, held_out)
    shown_fit = len(result.fitted) == len(records) and all(len(f) for f in result.fitted)
    if args.plot and shown_fit:  # (an estimate that is not ok is drawn, and said to be)
        from mtt.present import plots  # matplotlib takes a quarter second to import

        shown = [
            plots.Record(data.note, data.t, data.y, fitted)
            for data, fitted in zip(records, result.fitted, strict=True)
        ]
        checked = [
            plots.Record(fits.validation_label(data.note, c), data.t, data.y, c.fitted)
            for data, c in zip(held_out, compared, strict=False)
        ]
        plots.fit(
            args.plot, shown, output_label=plots.signal_label(module, "output"), dpi=args.dpi,
            title=f"{module.MODEL}: {fits.estimates(module, result)}, "
            f"fit {result.fit_percent:.4g} %"
            + ("" if result.noise is None else f"; noise {fits.noise_text(result.noise)}")
            + ("" if result.ok else " (not ok: see the warnings)"),
            validation=checked,
        )  # fmt: skip
    elif args.plot:
        warn("fit", [f"no plot: {result.message}"])
    if args.csv and shown_fit:
        rows = (
            (number, t, u, y, fitted, y - fitted)
            for number, (data, fitted) in enumerate(zip(records, result.fitted, strict=True), 1)
            for t, u, y, fitted in zip(data.t, data.u, data.y, fitted, strict=True)
        )
        files.write_atomic(
            args.csv, tables.csv_text(["record", "t", "u", "y", "fitted", "residual"], rows)
        )
    if args.json:
        record = {"model": module.MODEL, "unknown": module.UNKNOWN, **module.fit_record(result)}
        record["data"] = [data.note for data in records]
        if held_out:
            record["validation"] = validation_records(module, held_out, compared)
        say(json.dumps(record))
    else:
        lines = [(data.note, c) for data, c in zip(held_out, compared, strict=False)]
        say("\n".join([fits.fit_text(module, records, result), *fits.validation_lines(lines)]))
    return EXIT_OK if result.ok else EXIT_STOPPED


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


def validate(result, held_out: list) -> list:
    """The fit compared with each held-out record (`Fit.compare`): none without a fitted
    model (a warning says so)."""
    if not held_out:
        return []
    if not np.all(np.isfinite(result.k)):
        warn("fit", [f"no validation: {result.message}"])
        return []
    compared = []
    for data in held_out:
        try:
            compared.append(result.compare(data.t, data.u, data.y))
        except ValueError as error:
            source = data.note.split(" samples from ", 1)[-1]
            raise UsageError(f"--validate {source}: {error}") from None
    return compared


def validation_records(module, held_out: list, compared: list) -> list[dict]:
    """--json's "validation": per held-out record, its figures (only "data" without a model)."""
    return [
        {"data": data.note, **(module.comparison_record(c) if c is not None else {})}
        for data, c in zip_longest(held_out, compared)
    ]


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
