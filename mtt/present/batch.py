"""A batch of fits (mtt.batch) as text: `mtt fit --data 'logs/*.csv'`'s table, one row per
record, its CSV, and each failed record's message; `Batch.table()` and `Batch.to_csv()` of
the API print the same."""

from __future__ import annotations

from types import ModuleType, SimpleNamespace

import numpy as np

from mtt.present import tables
from mtt.present.fits import (
    METHOD_NAMES,
    fit_text,
    signals_comparison_record,
    signals_fit_record,
    signals_fit_text,
    signals_validation_lines,
    validation_lines,
)

NONLINEAR = {"pem": "prediction error with the nonlinear model"}  # a simulator's fit


def place(outcome) -> tuple[str, int | None]:
    """The file and line of a record's error (its message starts FILE:LINE: for a line)."""
    line = outcome.error.removeprefix(f"{outcome.name}:").partition(":")[0]
    return outcome.name, int(line) if line.isdigit() else None


def named(outcome) -> str:
    """A record's error message, starting with its name."""
    named = outcome.error.startswith(outcome.name)
    return outcome.error if named else f"{outcome.name}: {outcome.error}"


def warning_lines(batch) -> list[str]:
    """Each record's warnings, the record named."""
    return [
        f"{o.name}: {text}" for o in batch if o.result is not None for text in o.result.warnings
    ]


def _cells(module: ModuleType, outcome) -> tuple[str, ...]:
    """A record's row: its estimate and standard error (each unknown's), fit, warnings."""
    result, count = outcome.result, len(module.UNKNOWNS)
    held_out = [
        "" if v.comparison is None else percent(v.comparison.fit_percent)
        for v in outcome.validation
    ]
    if outcome.error is not None:
        return (outcome.name, *[""] * (2 * count), "", *held_out, "",
                "failed (the error is on stderr)")  # fmt: skip
    pairs = zip(np.atleast_1d(result.k), np.atleast_1d(result.k_se), strict=True)
    estimates = (cell for k, se in pairs for cell in (f"{k:.6g}", f"{se:.3g}"))
    return (outcome.name, *estimates, percent(result.fit_percent), *held_out,
            str(len(result.warnings) or ""), "")  # fmt: skip


def percent(fit) -> str:
    """A fit % cell: one figure, or one per output (several outputs) separated by " / "."""
    return " / ".join(f"{value:.4g}" for value in np.atleast_1d(fit))


def table(
    module: ModuleType, batch, where: str = "in this process", method: str | None = None
) -> str:
    """One row per record: each unknown's estimate and standard error, the fit % (and on
    each held-out record), the count of warnings; a failed record says so (its error is
    printed apart: `named`). `method`: the fits' (by default read from their results)."""
    methods = {getattr(o.result, "method", None) for o in batch if o.result is not None}
    methods = sorted(methods - {None}) if method is None else [method]
    names = METHOD_NAMES if hasattr(module, "fit_records") else NONLINEAR  # (a simulator's)
    method = ", ".join(names.get(m, str(m)) for m in methods)
    if len(module.UNKNOWNS) == 1:
        estimates = (module.UNKNOWN, "k_se")
    else:
        estimates = tuple(part for name in module.UNKNOWNS for part in (name, f"{name} k_se"))
    held_out = tuple(f"fit % on {v.name}" for v in (batch[0].validation if len(batch) else ()))
    several = hasattr(module, "fit_signals")  # several inputs or outputs: a fit % per output
    fit = f"fit % ({' / '.join(module.OUTPUTS)})" if several else "fit %"
    header = ("file", *estimates, fit, *held_out, "warnings", "")
    fitted = len(batch) - len(batch.errors)
    failed = f"; {len(batch.errors)} failed" if batch.errors else ""
    return "\n".join([
        f"{module.MODEL}: {len(batch)} records, one fit each ({method or 'none fitted'}, "
        f"{where})",
        *tables.rows([header, *(_cells(module, outcome) for outcome in batch)]),
        f"  {fitted} of {len(batch)} records fitted{failed}",
    ])  # fmt: skip


def table_csv(module: ModuleType, batch) -> str:
    """One row per record; several unknowns: k, k_se, ci_low and ci_high of each, named."""
    names = [""] if len(module.UNKNOWNS) == 1 else [f"_{name}" for name in module.UNKNOWNS]
    estimates = [f"{part}{name}" for name in names for part in ("k", "k_se", "ci_low", "ci_high")]
    several = hasattr(module, "fit_signals")  # several inputs or outputs: a fit % per output
    outputs = [f"_{name}" for name in module.OUTPUTS] if several else [""]
    figures = [f"{part}{name}" for part in ("fit_percent", "residual_rms") for name in outputs]
    header = ["file", *estimates, *figures, "iterations", "warnings", "error"]
    rows = []
    for outcome in batch:
        result = None if outcome.error else outcome.result
        numbers = ("",) * (len(estimates) + len(figures) + 1)
        if result is not None:
            columns = zip(np.atleast_1d(result.k), np.atleast_1d(result.k_se),
                          np.reshape(result.ci, (-1, 2)), strict=True)  # fmt: skip
            numbers = (*(v for k, se, (lo, hi) in columns for v in (k, se, lo, hi)),
                       *np.atleast_1d(result.fit_percent), *np.atleast_1d(result.residual_rms),
                       result.iterations)  # fmt: skip
        warnings = " | ".join(outcome.result.warnings) if outcome.result is not None else ""
        rows.append((outcome.name, *numbers, warnings, outcome.error or ""))
    return tables.csv_text(header, rows)


def pooled_text(module: ModuleType, batch) -> str:
    """A pooled fit's text, as `mtt fit` prints it, the records named (and its comparison
    with each held-out record)."""
    notes = [SimpleNamespace(note=outcome.name) for outcome in batch]
    compared = [(v.name, v.comparison) for v in batch.validation if v.comparison is not None]
    if hasattr(module, "fit_signals"):
        return "\n".join([signals_fit_text(module, notes, batch.pooled),
                          *signals_validation_lines(module, compared)])  # fmt: skip
    return "\n".join([fit_text(module, notes, batch.pooled), *validation_lines(compared)])


def record(module: ModuleType, batch) -> dict:
    """`mtt fit --json` of a batch: {"ok", "records": [one per record]}, or pooled the fit's
    record with its records' names under "data" (and "validation")."""
    if batch.pooled is None:
        return {"ok": batch.ok, "records": [outcome.record() for outcome in batch]}
    names = [outcome.name for outcome in batch]
    if hasattr(module, "fit_signals"):
        found = signals_fit_record(module, batch.pooled, names)
        if batch.validation:
            found["validation"] = [signals_comparison_record(module, v.name, v.comparison)
                                   for v in batch.validation]  # fmt: skip
        return found
    found = {"model": module.MODEL, "unknown": module.UNKNOWN, **module.fit_record(batch.pooled)}
    found["data"] = names
    if batch.validation:
        found["validation"] = [v.record() for v in batch.validation]
    return found
