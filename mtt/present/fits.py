"""A fit as people read it: each unknown's estimate with its standard error and 95 %
interval, the fit, the method, the local minima of the criterion and the noise model (with
several inputs or outputs: each output's fit and noise)."""

from __future__ import annotations

import math
import re
from itertools import zip_longest

import numpy as np

from mtt.present import tables, values


def estimates(module, result) -> str:
    """`k = 10 ± 0.02`, or `ra = 1 ± 0.01, jl = 10 ± 0.2` for several unknowns."""
    return ", ".join(
        f"{name} = {value:.6g} \u00b1 {se:.3g}"
        for name, value, se in zip(
            module.UNKNOWNS, np.atleast_1d(result.k), np.atleast_1d(result.k_se), strict=True
        )  # fmt: skip
    )


def uncertainty_lines(module, k, k_se, ci, indent: str = "  ", kinds=()) -> list[str]:
    """A line per unknown: its estimate, standard error and 95 % interval (kinds: per
    unknown, "profile" for a profile-likelihood interval; none given: k +- 1.96 k_se)."""
    kinds = tuple(kinds) or ("wald",) * len(module.UNKNOWNS)
    return [
        f"{indent}{name} = {value:.6g} \u00b1 {se:.3g} (standard error; 95 % "
        f"{'profile-likelihood interval' if kind == 'profile' else 'interval'} "
        f"{low:.6g} to {high:.6g})"
        for name, value, se, (low, high), kind in zip(
            module.UNKNOWNS,
            np.atleast_1d(k),
            np.atleast_1d(k_se),
            np.reshape(ci, (-1, 2)),
            kinds,
            strict=True,
        )  # fmt: skip
    ]


METHOD_NAMES = {
    "pem": "exact prediction error",
    "iv": "refined instrumental variables",
    "ls": "least squares",
}


def noise_text(noise) -> str:
    """`ARMA(2,1): D = 1 - 1.5 q^-1 + 0.7 q^-2, C = 1 + 0.5 q^-1, innovations std 0.1`."""
    if noise.orders == (0, 0):
        return f"white, std {noise.std:.3g}"

    def polynomial(letter: str, c) -> str:
        terms = "".join(
            f" {'-' if value < 0 else '+'} {abs(value):.4g} q^-{power}"
            for power, value in enumerate(c[1:], 1)
        )
        return f"{letter} = 1{terms}"

    parts = [polynomial("D", noise.ar)] + ([polynomial("C", noise.ma)] if len(noise.ma) > 1 else [])
    return f"{noise.kind}: {', '.join(parts)}, innovations std {noise.std:.3g}"


def fit_text(module, records, result) -> str:
    sources = "; ".join(data.note for data in records)
    lines = [f"{module.MODEL}: {sources}"]
    if not np.all(np.isfinite(result.k)):
        lines.append(f"  no estimate: {result.message}")
        return "\n".join(lines)
    if not result.ok:
        lines.append(f"  not ok: {result.warnings[0] if result.warnings else result.message}")
    if getattr(result, "shooting", None):  # a nonlinear model's (its simulator's fit)
        lines += uncertainty_lines(module, result.k, result.k_se, result.ci)
        return "\n".join(lines + prediction_error_lines(module, result))
    lines += uncertainty_lines(module, result.k, result.k_se, result.ci,
                               kinds=getattr(result, "intervals", ()))  # fmt: skip
    steps = {"pem": "Gauss-Newton steps", "iv": "iterations"}.get(result.method)
    steps = f", {result.iterations} {steps}" if steps else ""
    if len(module.UNKNOWNS) == 1:
        minima = ", ".join(f"{value:.6g}" for value in result.minima)
    else:
        minima = "; ".join(f"({values.text(module, point, '.6g')})" for point in result.minima)
    minima = minima or "none within the bounds"
    criterion = "least-squares cost (the starts)" if result.method == "pem" else "criterion"
    lines += [
        f"  fit {result.fit_percent:.4g} %, residual RMS {result.residual_rms:.3g}, "
        f"noise std {result.noise_std:.3g}",
        f"  method: {METHOD_NAMES[result.method]}{steps}; "
        f"local minima of the {criterion}: {minima}",
    ]
    if result.noise is not None:
        lines.append(f"  noise model: {noise_text(result.noise)}")
    if any(result.offsets) or getattr(result, "offset_fitted", False):  # (an estimated 0 too)
        lines.append("  output offset at rest: " + ", ".join(f"{v:.6g}" for v in result.offsets))
    return "\n".join(lines)


def prediction_error_lines(module, result) -> list[str]:
    """A nonlinear fit's figures after its estimates: the fit, how it was reached (the
    shooting, the Gauss-Newton steps, every start and the minimum each reached), the
    profile-likelihood intervals, and per record its initial state and output offset."""
    lines = [
        f"  fit {result.fit_percent:.4g} %, residual RMS {result.residual_rms:.3g}, "
        f"noise std {result.noise_std:.3g}",
        f"  method: prediction error with the nonlinear model ({result.shooting} shooting, "
        f"{result.iterations} Gauss-Newton steps)",
    ]
    profiled = [
        n for n, kind in zip(module.UNKNOWNS, result.intervals, strict=True) if kind == "profile"
    ]
    if profiled:
        lines.append(f"  95 % interval of {', '.join(profiled)}: profile likelihood (the cost is "
                     "far from quadratic there)")  # fmt: skip
    for origin, _, reached in result.starts:
        point = None if reached is None else np.ravel(reached)
        if point is not None and point.size == 1:
            point = point[0]  # one unknown: values.named takes a float
        end = "no minimum" if point is None else f"reached {values.named(module, point)}"
        lines.append(f"  start {origin}: {end}")
    for number, (x0, offset) in enumerate(zip(result.states, result.offsets, strict=True), 1):
        state = ", ".join(f"{name} = {v:.6g}" for name, v in zip(module.STATES, x0, strict=True))
        lines.append(f"  record {number}: initial state {state}; output offset {offset:.6g}")
    return lines


def validation_lines(compared) -> list[str]:
    """A line per held-out record, from (its name, the fit's Comparison on it)."""
    return [
        f"  validation on {name}: fit {c.fit_percent:.4g} %, residual RMS "
        f"{c.residual_rms:.3g} ({c.estimated})"
        for name, c in compared
    ]


def validation_label(name: str, comparison) -> str:
    """A held-out record's title in the compare plot."""
    return f"validation, fit {comparison.fit_percent:.4g} %: {name}"


def shown_fit(result, records) -> bool:
    """Whether the fit has a fitted output for every record (to draw and to write)."""
    return len(result.fitted) == len(records) and all(len(f) for f in result.fitted)


def plot_fit(path, module, result, records, held_out, compared, dpi: float) -> None:
    """`mtt fit --plot`: measured and fitted output and the residuals of each record, then
    each held-out record against the fit (an estimate that is not ok is drawn, and said
    to be)."""
    from mtt.present import plots  # matplotlib takes a quarter second to import

    shown = [
        plots.Record(data.note, data.t, data.y, fitted)
        for data, fitted in zip(records, result.fitted, strict=True)
    ]
    checked = [
        plots.Record(validation_label(data.note, c), data.t, data.y, c.fitted)
        for data, c in zip(held_out, compared, strict=False)
    ]
    plots.fit(
        path, shown, output_label=plots.signal_label(module, "output"), dpi=dpi,
        title=f"{module.MODEL}: {estimates(module, result)}, fit {result.fit_percent:.4g} %"
        + ("" if result.noise is None else f"; noise {noise_text(result.noise)}")
        + ("" if result.ok else " (not ok: see the warnings)"),
        validation=checked,
    )  # fmt: skip


def fit_csv(records, result) -> str:
    """`mtt fit --csv`: each sample's record, t, u, y, fitted output and residual."""
    rows = (
        (number, t, u, y, fitted, y - fitted)
        for number, (data, fitted) in enumerate(zip(records, result.fitted, strict=True), 1)
        for t, u, y, fitted in zip(data.t, data.u, data.y, fitted, strict=True)
    )
    return tables.csv_text(["record", "t", "u", "y", "fitted", "residual"], rows)


def fit_record(module, result, records, held_out, compared) -> dict:
    """`mtt fit --json`: the module's fit_record, the records and the held-out records."""
    record = {"model": module.MODEL, "unknown": module.UNKNOWN, **module.fit_record(result)}
    record["data"] = [data.note for data in records]
    if held_out:
        record["validation"] = validation_records(module, held_out, compared)
    return record


def validation_records(module, held_out: list, compared: list) -> list[dict]:
    """--json's "validation": per held-out record, its figures (only "data" without a model)."""
    return [
        {"data": data.note, **(module.comparison_record(c) if c is not None else {})}
        for data, c in zip_longest(held_out, compared)
    ]


def files_named(message: str, records) -> str:
    """The module's "record i" (from 0, in the order of the records) followed by its file."""
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


def signals_fit_text(module, records, result) -> str:
    """A fit of several inputs and outputs (`fit_signals`) as `fit_text` prints one: the
    records, each unknown's estimate and interval, then per output its fit, residual RMS
    and noise model."""
    sources = "; ".join(data.note for data in records)
    lines = [
        f"{module.MODEL}: from {', '.join(module.INPUTS)} to {', '.join(module.OUTPUTS)}; {sources}"
    ]
    if not result.ok:
        lines.append(f"  not ok: {result.message}")
    lines += uncertainty_lines(module, result.k, result.k_se, result.ci)
    lines.append(f"  method: {METHOD_NAMES[result.method]} of every output, "
                 f"{result.iterations} Gauss-Newton steps")  # fmt: skip
    for name, fit, rms, noise in zip(module.OUTPUTS, result.fit_percent, result.residual_rms,
                                     result.noise, strict=True):  # fmt: skip
        lines.append(
            f"  {name}: fit {fit:.4g} %, residual RMS {rms:.3g}, noise {noise_text(noise)}"
        )
    return "\n".join(lines)


def signals_validation_lines(module, compared) -> list[str]:
    """A line per held-out record and output, from (its name, the SignalsFit's
    SignalsComparison on it)."""
    return [
        f"  validation on {name}: {output}: fit {fit:.4g} %, residual RMS {rms:.3g}"
        + (f" ({c.estimated})" if i == len(module.OUTPUTS) - 1 else "")
        for name, c in compared
        for i, (output, fit, rms) in enumerate(
            zip(module.OUTPUTS, c.fit_percent, c.residual_rms, strict=True)
        )
    ]


def _finite(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def signals_fit_record(module, result, paths) -> dict:
    """`mtt fit --json` of a fit of several signals: the estimates and each output's noise
    model and figures."""
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


def signals_comparison_record(module, record: str, comparison) -> dict:
    """--json's "validation" of a fit of several signals: per held-out record, each
    output's figures (only "data" without a fitted model)."""
    if comparison is None:
        return {"data": record}
    return {
        "data": record, "samples": comparison.samples, "estimated": comparison.estimated,
        "signals": {name: {"fit_percent": _finite(fit), "residual_rms": _finite(rms),
                           "offset": _finite(offset)}
                    for name, fit, rms, offset in zip(module.OUTPUTS, comparison.fit_percent,
                                                      comparison.residual_rms,
                                                      comparison.offset, strict=True)},
    }  # fmt: skip


def signals_fit_csv(module, records, result) -> str:
    """A row per sample of each record: its inputs, then each output measured, at the
    estimate (its own initial state and offset fitted) and the residual."""
    outputs = [f"{name}{part}" for name in module.OUTPUTS for part in ("", " fitted", " residual")]
    header = ["record", "t", *module.INPUTS, *outputs]
    rows = (
        (number, t, *u, *(value for triple in zip(y, fitted, y - fitted, strict=True)
                          for value in triple))
        for number, (data, fitted) in enumerate(zip(records, result.fitted, strict=True), 1)
        for t, u, y, fitted in zip(data.t, data.u, data.y, fitted, strict=True)
    )  # fmt: skip
    return tables.csv_text(header, rows)
