"""Held-out records for `fit_many(..., validate=...)`: each fit that comes back is compared
with them here (the generated module's `Fit.compare`: fit % and residual RMS with the
held-out record's own initial state and output offset estimated)."""

from __future__ import annotations

import math
from dataclasses import dataclass

from mtt.batch import worker
from mtt.language.diagnostics import MttError


@dataclass(frozen=True)
class Validation:
    """A fit compared with a held-out record: `comparison` the module's Comparison without
    its signals (fit_percent, residual_rms, the record's estimated offset and initial
    state; several outputs: a SignalsComparison, a figure per output), None where there is
    no fitted model."""

    name: str
    comparison: object | None

    def record(self) -> dict:
        c = self.comparison
        figures = {"fit_percent": None, "residual_rms": None} if c is None else {
            "fit_percent": plain(c.fit_percent), "residual_rms": plain(c.residual_rms),
            "offset": plain(c.offset), "initial_state": plain(getattr(c, "initial_state", None)),
            "samples": c.samples, "estimated": c.estimated,
        }  # fmt: skip
        return {"data": self.name, **figures}


def plain(value):
    """A float for JSON (None for none or not finite), a list of them for an array."""
    if value is None:
        return None
    if hasattr(value, "tolist") and getattr(value, "ndim", 0) > 0:
        return [plain(v) for v in value.tolist()]
    value = float(value)
    return value if math.isfinite(value) else None


def held_out(module, specs, columns) -> list[tuple[str, tuple]]:
    """The held-out records, (name, spec) pairs read and checked here (an unreadable one is
    an error: MttError naming it)."""
    found = []
    for name, spec in specs:
        try:
            found.append((name, worker.read(module, spec, tuple(columns))))
        except (OSError, ValueError) as error:
            reason = getattr(error, "strerror", None) or str(error)
            raise MttError(f"validate: {name}: {reason}", kind="io", file=name) from None
    return found


def compared(result, records: list) -> tuple[Validation, ...]:
    """The fit's Comparison on each held-out record (None without a fitted model)."""
    k = None if result is None else result.k
    values = k.tolist() if hasattr(k, "tolist") else [k]
    usable = k is not None and all(math.isfinite(v) for v in values)
    return tuple(
        Validation(name, result.compare(*arrays).without_signals() if usable else None)
        for name, arrays in records
    )
