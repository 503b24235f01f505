"""Bode diagrams of a model for several values of its unknowns (scipy.signal, matplotlib),
of every entry of its transfer matrix with several inputs or outputs.

One frequency grid serves every value, wide enough for the poles and zeros of each
(scipy.signal.findfreqs), so that the curves compare point by point.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from scipy import signal

from mtt.language.diagnostics import MttError

POINTS = 400


@dataclass(frozen=True)
class Bode:
    """Magnitude and phase of G(jw) on one frequency grid, one row per value of k."""

    values: tuple[float, ...]  # the unknown's values
    frequency: np.ndarray  # rad/s
    magnitude_db: np.ndarray  # (len(values), len(frequency))
    phase_deg: np.ndarray


def bode(systems: Sequence[tuple[float, np.ndarray, np.ndarray]]) -> Bode:
    """The Bode data of (k, num, den) for each value of k (num, den highest power first,
    without leading zeros). A ValueError when floating point cannot hold them (coefficients
    of very different sizes, as for k = 1e-308: the roots overflowed in LAPACK)."""
    with np.errstate(all="ignore"):
        try:
            grids = [signal.findfreqs(num, den, POINTS) for _, num, den in systems]
            low = min(float(grid[0]) for grid in grids)
            high = max(float(grid[-1]) for grid in grids)
            w = np.logspace(np.log10(low), np.log10(high), POINTS)
            magnitude, phase = [], []
            for _, num, den in systems:
                _, mag, ph = signal.bode((num, den), w)
                magnitude.append(mag)
                phase.append(ph)
        except (ValueError, ArithmeticError):  # LinAlgError is a ValueError
            magnitude = [np.array([np.nan])]
    # (a zero exactly on the grid is -inf dB, and null in --json)
    if not (np.all(np.asarray(magnitude) < np.inf) and np.isfinite(w).all() and w[0] > 0):
        values = ", ".join(f"{k:g}" for k, _, _ in systems)
        raise ValueError(
            f"the frequency response for {values} is beyond floating point (the transfer "
            "function's coefficients differ too much in size): choose values nearer 1"
        )
    return Bode(tuple(k for k, _, _ in systems), w, np.array(magnitude), np.array(phase))


def figure(data: Bode, *, labels: Sequence[str], title: str) -> Figure:
    """The magnitude and phase of each curve, labelled (`k = 5`, `ra = 1, jl = 10`)."""
    fig = Figure(figsize=(7.0, 5.6), layout="constrained")
    FigureCanvasAgg(fig)
    magnitude, phase = fig.subplots(2, 1, sharex=True)
    for label, mag, ph in zip(labels, data.magnitude_db, data.phase_deg, strict=True):
        magnitude.semilogx(data.frequency, mag, label=label)
        phase.semilogx(data.frequency, ph, label=label)
    magnitude.set_ylabel("magnitude [dB]")
    phase.set_ylabel("phase [deg]")
    phase.set_xlabel("angular frequency [rad/s]")
    for ax in (magnitude, phase):
        ax.grid(True, which="both", alpha=0.3)
    magnitude.legend(loc="best")
    magnitude.set_title(title, fontsize=10)
    return fig


@dataclass(frozen=True)
class BodeMatrix:
    """The Bode data of every entry of a transfer matrix on one frequency grid."""

    inputs: tuple[str, ...]  # labels, one per column
    outputs: tuple[str, ...]  # one per row
    frequency: np.ndarray  # rad/s
    magnitude_db: np.ndarray  # (outputs, inputs, values, frequency): nan for a zero entry
    phase_deg: np.ndarray


def bode_matrix(
    entries: dict[tuple[int, int], Sequence[tuple[float, np.ndarray, np.ndarray]]],
    inputs: tuple[str, ...],
    outputs: tuple[str, ...],
) -> BodeMatrix:
    """`bode` of every entry that is not zero ((k, num, den) at each point, by (output,
    input)), all on one grid."""
    found = bode([system for systems in entries.values() for system in systems])
    count = len(next(iter(entries.values())))
    shape = (len(outputs), len(inputs), count, found.frequency.size)
    magnitude, phase = np.full(shape, np.nan), np.full(shape, np.nan)
    for index, (i, j) in enumerate(entries):
        rows = slice(index * count, (index + 1) * count)
        magnitude[i, j], phase[i, j] = found.magnitude_db[rows], found.phase_deg[rows]
    return BodeMatrix(inputs, outputs, found.frequency, magnitude, phase)


def matrix_figure(data: BodeMatrix, *, labels: Sequence[str], title: str) -> Figure:
    """A column per input, a magnitude and a phase row per output."""
    rows, columns = len(data.outputs), len(data.inputs)
    fig = Figure(figsize=(1.0 + 3.6 * columns, 0.8 + 3.2 * rows), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(2 * rows, columns, sharex=True, squeeze=False)
    for i, output in enumerate(data.outputs):
        for j, input_ in enumerate(data.inputs):
            magnitude, phase = axes[2 * i, j], axes[2 * i + 1, j]
            if i == 0:
                magnitude.set_title(f"from {input_}", fontsize=9)
            if j == 0:
                magnitude.set_ylabel(f"to {output}\nmagnitude [dB]", fontsize=8)
                phase.set_ylabel("phase [deg]", fontsize=8)
            if np.isnan(data.magnitude_db[i, j]).all():  # a zero entry
                magnitude.text(0.5, 0.5, "G = 0", ha="center", va="center",
                               transform=magnitude.transAxes)  # fmt: skip
            for label, mag, ph in zip(labels, data.magnitude_db[i, j], data.phase_deg[i, j],
                                      strict=True):  # fmt: skip
                magnitude.semilogx(data.frequency, mag, label=label)
                phase.semilogx(data.frequency, ph, label=label)
            for ax in (magnitude, phase):
                ax.grid(True, which="both", alpha=0.3)
                ax.tick_params(labelsize=8)
    for ax in axes[-1]:
        ax.set_xlabel("angular frequency [rad/s]", fontsize=8)
    next(ax for ax in axes.flat if ax.lines).legend(loc="best", fontsize=7)
    fig.suptitle(title, fontsize=10)
    return fig


@dataclass(frozen=True)
class ModelBode:
    """A model's Bode diagram at some values of its unknowns: a curve per point (`labels`:
    `k = 5`, `ra = 1, jl = 10`, or the model's name; `values`: each point's unknowns, a
    number for one, a list for several, else None), one panel pair per entry of G(s)."""

    model: object  # mtt.api.Model
    labels: tuple[str, ...]
    values: tuple[object, ...]
    data: Bode | BodeMatrix

    @property
    def several(self) -> bool:
        return isinstance(self.data, BodeMatrix)

    def figure(self) -> Figure:
        model, labels = self.model, list(self.labels)
        if not self.several:
            title = f"{model.name}: Bode diagram from {model.input} to {model.output}"
            return figure(self.data, labels=labels, title=title)
        title = (f"{model.name}: Bode diagrams from {', '.join(model.inputs)} to "
                 f"{', '.join(model.outputs)}")  # fmt: skip
        return matrix_figure(self.data, labels=labels, title=title)

    def record(self) -> dict:
        """`mtt bode --json` (after ok, file and out): the curves' magnitudes and phases on
        one frequency grid."""
        unknowns = self.model.unknowns
        signals = {}
        if self.several:
            signals = {"inputs": list(self.model.inputs), "outputs": list(self.model.outputs)}
        return {
            "model": self.model.name, "unknown": unknowns[0] if len(unknowns) == 1 else None,
            "unknowns": list(unknowns), "k": list(self.values), **signals,
            "frequency": self.data.frequency.tolist(),
            "magnitude_db": json_lists(self.data.magnitude_db),
            "phase_deg": json_lists(self.data.phase_deg),
        }  # fmt: skip


def json_lists(array) -> list:
    """An array as JSON lists, null where a value is not finite (a zero of G(jw) exactly on
    the grid is -inf dB): JSON has no infinities."""
    return np.where(np.isfinite(array), array, None).tolist()


def point_label(model, point: dict) -> tuple[str, object]:
    """A point's label (`k = 5`, `ra = 1, jl = 10`; the model's name without unknown) and
    its unknowns' values (a number for one, a list for several, else None)."""
    values = {name: float(point.get(name, model.parameters[name])) for name in model.unknowns}
    label = ", ".join(f"{name} = {value:g}" for name, value in values.items())
    k = list(values.values())
    return label or model.name, k[0] if len(k) == 1 else k or None


def model_bode(model, points: Sequence[dict]) -> ModelBode:
    """The Bode diagram of `model` (an mtt.api.Model) at each point (values of unknowns by
    name; the others the file's), of every entry of G(s) with several inputs or outputs.
    MttError bad_value when G(s) is zero (no magnitude in dB), out_of_range when floating
    point cannot hold the response."""
    labels = [point_label(model, point) for point in points]
    names, values = tuple(label for label, _ in labels), tuple(k for _, k in labels)
    if model.bondgraph.several:
        return ModelBode(model, names, values, _matrix(model, points))
    systems = []
    for point, (label, k) in zip(points, labels, strict=True):
        num, den = model.transfer_function.at(**point)
        if not num.any():  # no magnitude in dB, no phase (scipy warns and gives -inf)
            at = f" at {label}" if model.unknowns else ""
            raise MttError(f"G(s) is zero{at}: there is no Bode diagram", kind="bad_value")
        systems.append((k if isinstance(k, float) else float("nan"), num, den))
    try:
        return ModelBode(model, names, values, bode(systems))
    except ValueError as exc:
        raise MttError(str(exc), kind="out_of_range") from None


def _matrix(model, points: Sequence[dict]) -> BodeMatrix:
    """`bode_matrix` of every entry of the model's transfer matrix that is not zero."""
    matrix = model.transfer_matrix
    entries = {}
    for i, j in ((i, j) for i in range(len(model.outputs)) for j in range(len(model.inputs))):
        entry = matrix.entry(i, j)
        systems = [(float("nan"), *entry.at(**point)) for point in points]
        if all(num.any() for _, num, _ in systems):  # a zero has no magnitude in dB
            entries[i, j] = systems
    if not entries:
        raise MttError("every entry of G(s) is zero: there is no Bode diagram", kind="bad_value")
    try:
        return bode_matrix(entries, model.inputs, model.outputs)
    except ValueError as exc:
        raise MttError(str(exc), kind="out_of_range") from None
