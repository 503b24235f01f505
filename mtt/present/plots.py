"""The figures of an experiment, drawn as the paper draws them (matplotlib's Agg backend).

Each function takes plain arrays and labels, so that it serves measured and simulated
data alike, and writes its file atomically.
"""

from __future__ import annotations

import io
import textwrap
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from mtt.files import write_atomic


def signal_label(module: ModuleType, role: str) -> str:
    """What a plot calls the input or the output: the model's words for the source or
    detector, else what it is (the effort or flow of the component), with its label."""
    label = getattr(module, role.upper())
    description = getattr(module, f"{role.upper()}_DESCRIPTION", None)
    if description:
        return f"{description} ({label})"
    kind, _, name = label.partition(":")
    if not name:  # a simulator names its signals by their symbols (u, y)
        return f"{role} ({label})"
    quantity = "effort" if kind in ("Se", "De") else "flow"
    where = "of the source" if role == "input" else "at the detector"
    return f"{role}: {quantity} {where} {name} ({label})"


def _hat(name: str) -> str:
    """The estimate of `name`, with a hat, in matplotlib's mathtext (names are identifiers;
    a combining circumflex does not render in matplotlib's default font)."""
    escaped = name.replace("_", r"\_")
    return rf"$\hat{{{escaped}}}$"


@dataclass(frozen=True)
class Curve:
    """One run of the estimator, as the plots need it."""

    label: str
    t: np.ndarray
    khat: np.ndarray
    minima: np.ndarray  # local minima of the cost at the last time
    normalised_cost: object  # k -> (J(k) - J(k^)) / J_2(k^) at the last time (one unknown)
    global_k: np.ndarray  # the global minimiser of the cost at each time
    band: np.ndarray | None = None  # half-width of an approximate 95 % band about khat


def _figure(heights: tuple[int, ...] = (1,)) -> tuple[Figure, list]:
    size = 4.2 if len(heights) == 1 else 5.6 if len(heights) == 2 else 2.4 * len(heights)
    figure = Figure(figsize=(7.0, size), layout="constrained")
    FigureCanvasAgg(figure)
    axes = figure.subplots(len(heights), 1, sharex=True, squeeze=False, height_ratios=heights)
    axes = axes[:, 0]
    for ax in axes:
        ax.grid(True, alpha=0.3)
    return figure, list(axes)


def _save(figure: Figure, path: str | Path, dpi: float) -> None:
    if not (np.isfinite(dpi) and 10 <= dpi <= 2400):
        raise ValueError(f"--dpi must be from 10 to 2400, not {dpi:g}")
    buffer = io.BytesIO()
    suffix = Path(path).suffix.lstrip(".").lower() or "png"
    figure.savefig(buffer, format=suffix, dpi=dpi)
    write_atomic(path, buffer.getvalue())


def estimates(
    path: str | Path,
    curves: Sequence[Curve],
    *,
    title: str,
    unknowns: Sequence[str],
    true_value,
    dpi: float = 120.0,
) -> None:
    """The estimate against time, one line per run (the paper's Figs. 2, 6 and 7), its
    approximate 95 % band shaded, and, dotted where it differs from the estimate, the
    global minimiser of the cost. Several unknowns: a panel each (the global minimiser is
    known at the end only: a marker there)."""
    figure, axes = _figure(heights=(1,) * len(unknowns))
    truths = np.broadcast_to(np.nan if true_value is None else true_value, (len(unknowns),))
    for index, (ax, unknown, truth) in enumerate(zip(axes, unknowns, truths, strict=True)):
        for curve in curves:
            khat = curve.khat if curve.khat.ndim == 1 else curve.khat[:, index]
            best = curve.global_k if curve.global_k.ndim == 1 else curve.global_k[:, index]
            (line,) = ax.plot(curve.t, khat, label=curve.label, linewidth=1.4)
            if curve.band is not None:
                ax.fill_between(curve.t, khat - curve.band, khat + curve.band,
                                color=line.get_color(), alpha=0.15, linewidth=0)  # fmt: skip
            apart = np.abs(best - khat) > 1e-6 * (np.abs(khat) + 1e-300)
            if apart.sum() == 1:
                ax.plot(curve.t[apart], best[apart], "x", color=line.get_color())
            elif apart.any():
                ax.plot(curve.t, np.where(apart, best, np.nan), ":", linewidth=1.0,
                        color=line.get_color())  # fmt: skip
        if any(_apart(c, index) for c in curves):
            ax.plot([], [], ":", color="gray", label="global minimum of J")
        if any(curve.band is not None for curve in curves):
            ax.fill_between([], [], [], color="gray", alpha=0.15, label="approximate 95 % band")
            last = truth if np.isfinite(truth) else curves[-1].khat[-1]
            values = np.concatenate([curve.khat for curve in curves] + [[last]])
            low, high = float(values.min()), float(values.max())
            pad = 0.1 * (high - low) or 0.1 * abs(high) or 1.0
            ax.set_ylim(low - pad, high + pad)  # the early band is wide: keep the estimates in view
        if np.isfinite(truth):
            ax.axhline(truth, color="black", linestyle="--", linewidth=0.9,
                       label=f"true value {unknown} = {truth:g}")  # fmt: skip
        ax.set_ylabel(f"estimate {_hat(unknown)} of {unknown}")
        ax.legend(loc="best", fontsize="small")
    axes[-1].set_xlabel("time t (s)")
    axes[0].set_title(title, fontsize="medium")
    _save(figure, path, dpi)


def _apart(curve: Curve, index: int) -> bool:
    khat = curve.khat if curve.khat.ndim == 1 else curve.khat[:, index]
    best = curve.global_k if curve.global_k.ndim == 1 else curve.global_k[:, index]
    return bool((np.abs(best - khat) > 1e-6 * np.abs(khat)).any())


def cost(
    path: str | Path,
    curves: Sequence[Curve],
    *,
    k_range: tuple[float, float],
    title: str,
    unknown: str,
    true_value: float | None,
    dpi: float = 120.0,
) -> None:
    """The normalised cost against k at the last time, minima marked (the paper's Fig. 8);
    the legend beside the axes, where it covers no curve."""
    figure, (ax,) = _figure()
    k = np.linspace(*k_range, 801)
    for curve in curves:
        (line,) = ax.plot(k, curve.normalised_cost(k), label=curve.label, linewidth=1.4)
        inside = curve.minima[(curve.minima >= k_range[0]) & (curve.minima <= k_range[1])]
        ax.plot(inside, curve.normalised_cost(inside), "o", color=line.get_color(), markersize=5)
    if true_value is not None and k_range[0] <= true_value <= k_range[1]:
        ax.axvline(true_value, color="black", linestyle="--", linewidth=0.9,
                   label=f"true value {unknown} = {true_value:g}")  # fmt: skip
    ax.set_xlim(*k_range)
    ax.set_xlabel(unknown)
    hat = _hat(unknown)
    ax.set_ylabel(f"normalised cost  (J({unknown}) \u2212 J({hat})) / J\u2082({hat})")
    ax.set_title(title, fontsize="medium")
    figure.legend(loc="outside right upper", fontsize="small", title="dots: local minima",
                  title_fontsize="small")  # fmt: skip
    _save(figure, path, dpi)


def data(
    path: str | Path,
    t: np.ndarray,
    u: np.ndarray,
    y: np.ndarray,
    *,
    title: str,
    input_label: str,
    output_label: str,
    clean: np.ndarray | None = None,
    dpi: float = 120.0,
) -> None:
    """Input and output samples against time (the paper's Fig. 5), and the noise-free output.
    The labels say what the signals are (the model's words for the source and detector)."""
    figure, (top, bottom) = _figure(heights=(1, 3))
    top.plot(t, u, color="tab:gray", linewidth=1.2)
    top.set_ylabel("\n".join(textwrap.wrap(input_label, 24)))
    top.set_title("\n".join(textwrap.wrap(title, 80)), fontsize="medium")
    bottom.plot(t, y, linewidth=0.9, label="output samples")
    if clean is not None and not np.array_equal(clean, y):
        bottom.plot(t, clean, color="black", linestyle="--", linewidth=1.0, label="without noise")
        bottom.legend(loc="best", fontsize="small")
    bottom.set_ylabel("\n".join(textwrap.wrap(output_label, 30)))
    bottom.set_xlabel("time t (s)")
    _save(figure, path, dpi)


@dataclass(frozen=True)
class Record:
    """One record of a fit, as the plot needs it."""

    label: str
    t: np.ndarray
    y: np.ndarray
    fitted: np.ndarray


def fit(path: str | Path, records: Sequence[Record], *, title: str, output_label: str,
        dpi: float = 120.0, validation: Sequence[Record] = ()) -> None:  # fmt: skip
    """Measured and simulated output, and the residuals below, one column per record (at
    most four, held-out `validation` records last, their model in green): what the compare
    plots of system-identification toolboxes show."""
    held = len(validation[: 4 - min(len(records), 2)])
    shown = [*records[: 4 - held], *validation[:held]]
    figure = Figure(figsize=(min(4.0 + 3.0 * len(shown), 14.0), 5.6), layout="constrained")
    FigureCanvasAgg(figure)
    axes = figure.subplots(2, len(shown), sharex="col", squeeze=False, height_ratios=(3, 1))
    for column, record in enumerate(shown):
        top, bottom = axes[0, column], axes[1, column]
        held_out = column >= len(shown) - held
        top.plot(record.t, record.y, color="tab:gray", linewidth=0.8, label="measured")
        top.plot(record.t, record.fitted, color="tab:green" if held_out else "tab:blue",
                 linewidth=1.2, label="model")  # fmt: skip
        bottom.plot(record.t, record.y - record.fitted, color="tab:red", linewidth=0.6)
        bottom.axhline(0.0, color="black", linewidth=0.6)
        top.set_title(
            "\n".join(textwrap.wrap(record.label, 40 if len(shown) > 1 else 90)), fontsize="small"
        )
        bottom.set_xlabel("time t (s)")
        for ax in (top, bottom):
            ax.grid(True, alpha=0.3)
    axes[0, 0].set_ylabel("\n".join(textwrap.wrap(output_label, 30)))
    axes[1, 0].set_ylabel("residual")
    axes[0, 0].legend(loc="best", fontsize="small")
    left = len(records) + len(validation) - len(shown)
    more = f" ({left} more records not shown)" if left else ""
    figure.suptitle("\n".join(textwrap.wrap(title + more, 90)), fontsize="medium")
    _save(figure, path, dpi)


def fit_signals(path: str | Path, records: Sequence[Record], *, title: str,
                outputs: Sequence[str], dpi: float = 120.0,
                validation: Sequence[Record] = ()) -> None:  # fmt: skip
    """A fit of several outputs: one panel per output (a row each: measured and model), one
    column per record (at most four, held-out `validation` records last, their model in
    green). Each Record's y and fitted are (samples, outputs)."""
    held = len(validation[: 4 - min(len(records), 2)])
    shown = [*records[: 4 - held], *validation[:held]]
    figure = Figure(figsize=(min(4.0 + 3.0 * len(shown), 14.0), 1.0 + 2.4 * len(outputs)),
                    layout="constrained")  # fmt: skip
    FigureCanvasAgg(figure)
    axes = figure.subplots(len(outputs), len(shown), sharex="col", squeeze=False)
    for column, record in enumerate(shown):
        held_out = column >= len(shown) - held
        for row, _ in enumerate(outputs):
            ax = axes[row, column]
            ax.plot(record.t, record.y[:, row], color="tab:gray", linewidth=0.8, label="measured")
            ax.plot(record.t, record.fitted[:, row], color="tab:green" if held_out else "tab:blue",
                    linewidth=1.2, label="model")  # fmt: skip
            ax.grid(True, alpha=0.3)
        axes[0, column].set_title(
            "\n".join(textwrap.wrap(record.label, 40 if len(shown) > 1 else 90)), fontsize="small"
        )
        axes[-1, column].set_xlabel("time t (s)")
    for row, label in enumerate(outputs):
        axes[row, 0].set_ylabel("\n".join(textwrap.wrap(label, 30)))
    axes[0, 0].legend(loc="best", fontsize="small")
    left = len(records) + len(validation) - len(shown)
    more = f" ({left} more records not shown)" if left else ""
    figure.suptitle("\n".join(textwrap.wrap(title + more, 90)), fontsize="medium")
    _save(figure, path, dpi)


def signals_data(path: str | Path, t: np.ndarray, columns: Sequence[tuple], *, title: str,
                 dpi: float = 120.0) -> None:  # fmt: skip
    """Every signal of a record against time, a panel each (inputs grey, outputs blue):
    `columns` (label, samples, is_input)."""
    figure, axes = _figure(heights=(1,) * len(columns))
    for ax, (label, values, is_input) in zip(axes, columns, strict=True):
        ax.plot(t, values, color="tab:gray" if is_input else "tab:blue", linewidth=0.9)
        ax.set_ylabel("\n".join(textwrap.wrap(label, 24)))
    axes[0].set_title("\n".join(textwrap.wrap(title, 80)), fontsize="medium")
    axes[-1].set_xlabel("time t (s)")
    _save(figure, path, dpi)
