"""`mtt fit` with several inputs or outputs: the compiled module's `fit_signals` over CSV
records whose columns are the time and every signal, named by the signals' own labels
(t,Se:v,Se:tl,Df:speed) or by --columns in that order (t,u1,u2,y1)."""

from __future__ import annotations

import json
from types import ModuleType

from mtt.cli.experiment import refuse_simulation
from mtt.cli.fit_options import options
from mtt.cli.running import EXIT_OK, UsageError, say, warn
from mtt.data.signals import read_signals, signal_columns
from mtt.present.fits import signals_fit_record, signals_fit_text

SETTINGS = ("noise", "C", "k0", "bounds", "offset", "initial_state", "hold")  # fit_signals'


# what the one-signal `mtt fit` does and this one does not yet: (flag, given?, what to do)
UNSUPPORTED = (
    ("--validate", lambda args: args.validate, "in Python, the fit's simulate(t, u) gives "
     "each output at the estimate for a held-out record"),
    ("--plot", lambda args: args.plot, "in Python, the fit's simulate(t, u) gives each "
     "fitted output to plot"),
    ("--csv", lambda args: args.csv, "in Python, the fit's simulate(t, u) gives each "
     "fitted output"),
    ("--data-plot", lambda args: args.data_plot, "plot the record's columns yourself"),
    ("--method", lambda args: args.method != "pem", "several signals are fitted by the exact "
     "prediction error (pem) only"),
    ("--beta", lambda args: args.beta != 0.0, "it weighs the samples of --method iv and ls"),
)  # fmt: skip


def _refuse_unsupported(args) -> None:
    """Every flag either acts or is refused: none is ignored."""
    for flag, given, instead in UNSUPPORTED:
        if given(args):
            raise UsageError(
                f"{flag} is not supported with several inputs or outputs (supported: --data, "
                f"--columns, --noise, --filter, --k0, --bounds, --offset, --initial-state, "
                f"--hold, --json); {instead}"
            )


def cmd_fit_signals(args, module: ModuleType) -> int:
    """Fit every input and output of the --data records; print the estimate and each
    output's noise and fit (or JSON)."""
    if not args.data:
        raise UsageError(
            "with several inputs or outputs `mtt fit` reads measured records: give --data "
            f"FILE.csv with the columns {','.join(signal_columns(module, None))} (or --columns)"
        )
    refuse_simulation(args)
    _refuse_unsupported(args)
    names = signal_columns(module, args.columns)
    records = [read_signals(module, path, names) for path in args.data]
    chosen = {key: value for key, value in options(module, args).items() if key in SETTINGS}
    arrays = [[getattr(record, name) for record in records] for name in ("t", "u", "y")]
    result = module.fit_signals(*(arrays if len(records) > 1 else [a[0] for a in arrays]), **chosen)
    warn("fit", result.warnings)
    if args.json:
        say(json.dumps(signals_fit_record(module, result, args.data)))
    else:
        samples = sum(record.t.size for record in records)
        say(signals_fit_text(module, result, samples, args.data))
    return EXIT_OK
