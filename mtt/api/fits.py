"""A fit as a Python user holds it: the generated module's Fit, every attribute read
through, that prints as `mtt fit` does (str, summary) and shows as a table in Jupyter."""

from __future__ import annotations

import html
from dataclasses import dataclass, field
from types import ModuleType, SimpleNamespace

import numpy as np

from mtt.language.diagnostics import MttError
from mtt.present import fits


@dataclass(frozen=True)
class Fit:
    """The generated module's `Fit` (k, k_se, ci, fit_percent, warnings...: see its
    docstring), with its report."""

    result: object
    module: ModuleType = field(repr=False)
    notes: tuple[str, ...] = ()  # where each record came from, for the report's first line

    def __getattr__(self, name: str):
        if name.startswith("__"):  # copy, pickle and dataclasses ask for these
            raise AttributeError(name)
        return getattr(self.result, name)

    def summary(self) -> str:
        """The text `mtt fit` prints: each unknown's estimate, standard error and 95 %
        interval, the fit, the method and the local minima of the criterion."""
        records = [SimpleNamespace(note=note) for note in self.notes]
        return fits.fit_text(self.module, records, self.result)

    def __str__(self) -> str:
        return self.summary()

    def __repr__(self) -> str:
        return repr(self.result)

    def _repr_html_(self) -> str:
        """The estimates as a table (Jupyter shows it), then the fit and the warnings."""
        head = f"<p><b>{html.escape(self.module.MODEL)}</b>: {html.escape('; '.join(self.notes))}"
        if not np.all(np.isfinite(self.result.k)):
            return f"{head}</p><p>no estimate: {html.escape(self.result.message)}</p>"
        if not self.result.ok:
            head += f"</p><p>not ok: {html.escape(self.result.message)}"
        kinds = tuple(getattr(self.result, "intervals", ()))
        kinds = kinds or ("wald",) * len(self.module.UNKNOWNS)
        cells = zip(self.module.UNKNOWNS, np.atleast_1d(self.result.k),
                    np.atleast_1d(self.result.k_se), np.reshape(self.result.ci, (-1, 2)), kinds,
                    strict=True)  # fmt: skip
        rows = "".join(
            f"<tr><td>{html.escape(name)}</td><td>{k:.6g}</td><td>{se:.3g}</td>"
            f"<td>{low:.6g} to {high:.6g}{' (profile likelihood)' if kind == 'profile' else ''}"
            "</td></tr>"
            for name, k, se, (low, high), kind in cells
        )
        warnings = "".join(f"<li>{html.escape(text)}</li>" for text in self.result.warnings)
        return (
            f"{head}</p><table><tr><th>unknown</th><th>estimate</th><th>standard error</th>"
            f"<th>95 % interval</th></tr>{rows}</table>"
            f"<p>fit {self.result.fit_percent:.4g} %, residual RMS "
            f"{self.result.residual_rms:.3g}"
            + (
                ""
                if self.result.noise is None
                else f"; noise model {html.escape(fits.noise_text(self.result.noise))}"
            )
            + "</p>"
            + (f"<ul>{warnings}</ul>" if warnings else "")
        )


def delegate(function, *args, **options):
    """Call the generated module; its ValueErrors (bad arguments, named) become MttError."""
    try:
        return function(*args, **options)
    except ValueError as exc:
        raise MttError(str(exc), kind="bad_argument") from exc


def compare_each(result, held_out, option: str = "validate") -> tuple[list, list[str]]:
    """The fit compared with each held-out record (mtt.data's Records, by `Fit.compare`:
    each with its own initial state and output offset), and the warnings: no comparison
    without a fitted model. A record the fit cannot be compared with is an MttError
    naming it (after `option`, as the caller names the held-out records)."""
    if not held_out:
        return [], []
    if not np.all(np.isfinite(result.k)):
        return [], [f"no validation: {result.message}"]
    compared = []
    for data in held_out:
        try:
            compared.append(result.compare(data.t, data.u, data.y))
        except ValueError as error:
            source = data.note.split(" samples from ", 1)[-1]
            raise MttError(f"{option} {source}: {error}", kind="bad_argument") from None
    return compared, []
