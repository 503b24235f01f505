"""A fit as people read it: each unknown's estimate with its standard error and 95 %
interval, the fit, the method and the local minima of the criterion."""

from __future__ import annotations

import numpy as np

from mtt.present import values


def estimates(module, result) -> str:
    """`k = 10 ± 0.02`, or `ra = 1 ± 0.01, jl = 10 ± 0.2` for several unknowns."""
    return ", ".join(
        f"{name} = {value:.6g} \u00b1 {se:.3g}"
        for name, value, se in zip(
            module.UNKNOWNS, np.atleast_1d(result.k), np.atleast_1d(result.k_se), strict=True
        )  # fmt: skip
    )


def uncertainty_lines(module, k, k_se, ci, indent: str = "  ") -> list[str]:
    """A line per unknown: its estimate, standard error and 95 % interval."""
    return [
        f"{indent}{name} = {value:.6g} \u00b1 {se:.3g} (standard error; 95 % interval "
        f"{low:.6g} to {high:.6g})"
        for name, value, se, (low, high) in zip(
            module.UNKNOWNS,
            np.atleast_1d(k),
            np.atleast_1d(k_se),
            np.reshape(ci, (-1, 2)),
            strict=True,
        )  # fmt: skip
    ]


def fit_text(module, records, result) -> str:
    sources = "; ".join(data.note for data in records)
    lines = [f"{module.MODEL}: {sources}"]
    if not result.ok:
        lines.append(f"  no estimate: {result.message}")
        return "\n".join(lines)
    method = "refined instrumental variables" if result.method == "iv" else "least squares"
    steps = f", {result.iterations} iterations" if result.method == "iv" else ""
    lines += uncertainty_lines(module, result.k, result.k_se, result.ci)
    if len(module.UNKNOWNS) == 1:
        minima = ", ".join(f"{value:.6g}" for value in result.minima)
    else:
        minima = "; ".join(f"({values.text(module, point, '.6g')})" for point in result.minima)
    minima = minima or "none within the bounds"
    lines += [
        f"  fit {result.fit_percent:.4g} %, residual RMS {result.residual_rms:.3g}, "
        f"noise std {result.noise_std:.3g}",
        f"  method: {method}{steps}; local minima of the criterion: {minima}",
    ]
    if any(result.offsets):
        lines.append("  output offset at rest: " + ", ".join(f"{v:.6g}" for v in result.offsets))
    return "\n".join(lines)


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
