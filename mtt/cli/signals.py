"""`mtt fit` with several inputs or outputs: the compiled module's `fit_signals` over CSV
records whose columns are the time and every signal, named by the signals' own labels
(t,Se:v,Se:tl,Df:speed) or by --columns in that order (t,u1,u2,y1)."""

from __future__ import annotations

import json
import math
from types import ModuleType

import numpy as np

from mtt.cli.experiment import refuse_simulation
from mtt.cli.fit_options import options
from mtt.cli.running import EXIT_OK, UsageError, say, warn

SETTINGS = ("noise", "C", "k0", "bounds", "offset", "initial_state", "hold")  # fit_signals'


def columns_for(module: ModuleType, given: str | list[str] | None) -> tuple[str, ...]:
    """The CSV columns of the time, each input and each output, in that order (--columns
    as a list, or text with commas)."""
    default = ("t", *module.INPUTS, *module.OUTPUTS)
    if given is None:
        return default
    parts = given.split(",") if isinstance(given, str) else given
    names = tuple(name.strip() for name in parts)
    given = ",".join(names)
    if len(names) != len(default) or not all(names) or len(set(names)) != len(names):
        raise UsageError(
            f"--columns takes {len(default)} different names: the time, then the inputs "
            f"{', '.join(module.INPUTS)}, then the outputs {', '.join(module.OUTPUTS)} (now "
            f"{given!r}; by default the columns are named {','.join(default)})"
        )
    return names


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
            f"FILE.csv with the columns {','.join(columns_for(module, None))} (or --columns)"
        )
    refuse_simulation(args)
    _refuse_unsupported(args)
    names = columns_for(module, args.columns)
    inputs = len(module.INPUTS)
    records = []
    for path in args.data:
        try:
            t, *signals = module.read_csv(path, names)
        except ValueError as error:
            if "no column" not in str(error):
                raise
            default = ",".join(columns_for(module, None))
            raise UsageError(f"{error}: name the time, each input and each output with "
                             f"--columns (by default {default})") from None  # fmt: skip
        records.append((t, np.column_stack(signals[:inputs]), np.column_stack(signals[inputs:])))
    chosen = {key: value for key, value in options(module, args).items() if key in SETTINGS}
    arrays = [[record[i] for record in records] for i in range(3)]
    result = module.fit_signals(*(arrays if len(records) > 1 else [a[0] for a in arrays]), **chosen)
    warn("fit", result.warnings)
    if args.json:
        say(json.dumps(_record(module, result, args.data)))
    else:
        say(_text(module, result, records, args.data))
    return EXIT_OK


def _finite(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def _record(module: ModuleType, result, paths) -> dict:
    k, se = np.atleast_1d(result.k), np.atleast_1d(result.k_se)
    return {
        "model": module.MODEL, "inputs": list(module.INPUTS), "outputs": list(module.OUTPUTS),
        "data": list(paths), "ok": bool(result.ok), "warnings": list(result.warnings),
        "unknowns": {name: {"k": _finite(value), "k_se": _finite(error)}
                     for name, value, error in zip(module.UNKNOWNS, k, se, strict=True)},
        "signals": {name: {"noise": noise.record(), "fit_percent": _finite(fit),
                           "residual_rms": _finite(rms)}
                    for name, noise, fit, rms in zip(module.OUTPUTS, result.noise,
                                                     result.fit_percent, result.residual_rms,
                                                     strict=True)},
    }  # fmt: skip


def _text(module: ModuleType, result, records, paths) -> str:
    samples = sum(record[0].size for record in records)
    lines = [
        f"{module.MODEL}: from {', '.join(module.INPUTS)} to {', '.join(module.OUTPUTS)}; "
        f"{samples} samples from {', '.join(paths)}"
    ]
    k, se = np.atleast_1d(result.k), np.atleast_1d(result.k_se)
    for name, value, error in zip(module.UNKNOWNS, k, se, strict=True):
        lines.append(f"  {name} = {value:.6g} +- {error:.3g} (95 % interval "
                     f"{value - 1.96 * error:.6g} to {value + 1.96 * error:.6g})")  # fmt: skip
    for name, noise, fit in zip(module.OUTPUTS, result.noise, result.fit_percent, strict=True):
        lines.append(f"  {name}: fit {fit:.4g} %, noise {noise.kind}, std {noise.std:.3g}")
    if not result.ok:
        lines.append("  not ok: " + result.warnings[0])
    return "\n".join(lines)
