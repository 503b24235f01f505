"""Records: measured ones read from CSV files, simulated ones from a test signal (or an
input read from a file) through the model's generated module, with optional noise.

The generated module does the numerical work (read_csv, input_signal, simulate,
with_noise); files are checked and noted by mtt.files first (a regular file, not one the
command writes); what is here chooses the grid, checks the settings, names the file a record
came from and says in a note how each record was made (tables and figures print it).
"""

from __future__ import annotations

import csv
from collections.abc import Sequence
from dataclasses import dataclass
from types import ModuleType

import numpy as np

from mtt import files
from mtt.data import (
    DEFAULT_DT,
    DEFAULT_SEED,
    DEFAULT_T_END,
    MAX_SAMPLES,
    SIGNAL_KINDS,
    DataError,
)
from mtt.present import values

COLUMNS = ("t", "u", "y")


@dataclass(frozen=True)
class Record:
    """One experiment's samples: times, input and output (float arrays of one length)."""

    t: np.ndarray
    u: np.ndarray
    y: np.ndarray
    clean: np.ndarray | None  # the output before noise, when simulated
    k: float | np.ndarray | None  # the true value(s), when simulated (an array: several)
    note: str  # where the record came from, for tables and titles


def columns(given: str | Sequence[str] | None) -> tuple[str, str, str]:
    """The names of the time, input and output columns: "T,U,Y" or three names."""
    if given is None:
        return COLUMNS
    parts = given.split(",") if isinstance(given, str) else list(given)
    names = tuple(str(name).strip() for name in parts)
    if len(names) != 3 or not all(names) or len(set(names)) != 3:
        shown = given if isinstance(given, str) else ",".join(map(str, given))
        raise DataError(f"columns takes three different names T,U,Y, not {shown!r}", "columns")
    return names


def read(module: ModuleType, path: str, names: Sequence[str] = COLUMNS) -> Record:
    """A measured record: the columns `names` (time, input, output) of a CSV file, its
    times increasing strictly."""
    files.check_input(path, "data")  # a regular file of bounded size, not an output
    try:  # (the module reads a comma, ';', tab or '|' as the header line is split)
        t, u, y = module.read_csv(path, tuple(names))
    except ValueError as error:  # the module's CSVError: its file, line and kind kept
        if "no column" not in str(error):
            raise
        raise DataError(
            f"{error}: name the time, input and output with columns T,U,Y (now {','.join(names)})",
            "columns", path=str(path), line=getattr(error, "line", None),
        ) from None  # fmt: skip
    _check_values(module, path, names, t, u, y)
    late = np.flatnonzero(np.diff(t) <= 0)
    if late.size:  # named here: the module's message cannot name the file
        i = int(late[0])
        later, earlier = float(t[i + 1]), float(t[i])
        line = _line_of_row(path, _delimiter(path), i + 1)
        raise DataError(
            f"{path}:{line}: the times (column {names[0]!r}) must increase strictly: "
            f"{later!r} (data row {i + 2}) follows {earlier!r} (data row {i + 1})",
            path=str(path), line=line,
        )  # fmt: skip
    return Record(t, u, y, None, None, f"{t.size} samples from {path}")


def _check_values(module: ModuleType, path: str, names: Sequence[str], *columns) -> None:
    """Every value within what the estimator takes (the module's MAX_TIME for times,
    MAX_SIGNAL for signals), else a DataError at the file's line."""
    limits = (getattr(module, "MAX_TIME", 1e15), *[getattr(module, "MAX_SIGNAL", 1e150)] * 2)
    whys = (
        "times must stay within {:g} in size; count time from the record's start",
        "signals must stay within {:g} in size; scale them to units nearer 1",
        "signals must stay within {:g} in size; scale them to units nearer 1",
    )
    for name, column, limit, why in zip(names, columns, limits, whys, strict=True):
        beyond = np.flatnonzero(np.abs(column) > limit)
        if beyond.size:
            i = int(beyond[0])
            line = _line_of_row(path, _delimiter(path), i)
            raise DataError(
                f"{path}:{line}: column {name!r} holds {column[i]:g}: {why.format(limit)}",
                path=str(path), line=line,
            )  # fmt: skip


def _line_of_row(path: str, delimiter: str, row: int) -> int | None:
    """The line (from 1) of data row `row` (from 0) of a CSV file, counted as the module's
    reader counts (blank rows skipped, the header first); None if the file changed."""
    with open(path, encoding="utf-8-sig", newline="") as file:
        rows = csv.reader(file, delimiter=delimiter)
        seen = -1  # the header
        for cells in rows:
            if any(cell.strip() for cell in cells):
                if seen == row:
                    return rows.line_num
                seen += 1
    return None


DELIMITERS = (",", ";", "\t", "|")
HEADER_BYTES = 1 << 16  # a header line longer than this is not sniffed (the reader says why)


def _delimiter(path: str) -> str:
    """The header line's delimiter: a comma, unless the line has none and splits on
    another of DELIMITERS (a spreadsheet's ';' or a tab)."""
    try:
        with open(path, encoding="utf-8-sig", errors="replace") as file:
            header = file.readline(HEADER_BYTES)
    except OSError:
        return ","  # the reader reports it, with the file's name
    if "," in header:
        return ","
    counts = {d: header.count(d) for d in DELIMITERS[1:]}
    best = max(counts, key=counts.get)
    return best if counts[best] else ","


def input_signal(
    module: ModuleType,
    signal: str | None = None,
    *,
    t_end: float | None = None,
    dt: float | None = None,
    period: float | None = None,
    amplitude: float | None = None,
    seed: int | None = None,
) -> tuple[np.ndarray, np.ndarray, str]:
    """The input samples and a description: a test signal (step, the default, prbs, square
    or multisine) on a regular grid from t = 0, or the t,u columns of the CSV file `signal`."""
    kind = signal or "step"
    if kind not in SIGNAL_KINDS:
        if t_end is not None or dt is not None or period is not None:
            raise DataError(
                "t_end, dt and period apply to the test signals (signal step|prbs|square|"
                "multisine); the file gives the times",
                *("t_end", "dt", "period", "signal"),
            )
        t, u = module.read_csv(files.check_input(kind, "an input signal"), ("t", "u"))
        return t, u if amplitude is None else amplitude * u, kind
    t_end = DEFAULT_T_END if t_end is None else t_end
    dt = DEFAULT_DT if dt is None else dt
    if not (0 < dt <= t_end < np.inf):
        raise DataError(f"need 0 < dt <= t_end, not dt {dt} and t_end {t_end}", "dt", "t_end")
    if not t_end / dt < MAX_SAMPLES:  # inf for dt = 5e-324: round() raised OverflowError
        raise DataError(
            f"t_end / dt = {t_end / dt:.3g} samples is too many (at most {MAX_SAMPLES})",
            *("t_end", "dt"),
        )
    if kind == "step" and period is not None:
        raise DataError("period applies to prbs, square and multisine, not to a step", "period")
    t = np.linspace(0.0, t_end, max(1, round(t_end / dt)) + 1)
    amplitude = 1.0 if amplitude is None else amplitude
    seed = DEFAULT_SEED if seed is None else seed
    u = module.input_signal(kind, t, amplitude=amplitude, period=period, seed=seed)
    described = (
        "a unit step" if kind == "step" and amplitude == 1 else f"{kind}, amplitude {amplitude:g}"
    )
    if period is not None:
        described += f", period {period:g}"
    return t, u, described


def simulate(
    module: ModuleType,
    t: np.ndarray,
    u: np.ndarray,
    k: float | np.ndarray,
    *,
    source: str,
    hold: str,
    noise_uniform: float | None = None,
    noise_snr: float | None = None,
    seed: int | None = None,
    x0: np.ndarray | None = None,
) -> Record:
    """A simulated record: the model's output at the unknowns' values k for the input u
    (`source` describes it), from rest or (a nonlinear model's simulator) from the state
    x0, with noise uniform in [-noise_uniform, noise_uniform] or white Gaussian at
    noise_snr dB."""
    start = {} if x0 is None else {"x0": x0}
    clean = module.simulate(t, u, k, hold=hold, **start)
    named = values.named(module, k, "g")
    bad = np.flatnonzero(~np.isfinite(clean))  # NaN or inf written as data, invalid JSON
    if bad.size:
        raise DataError(
            f"the simulated output overflows at t = {t[bad[0]]:g}: the model is unstable with "
            f"{named}, or its values are far from 1; shorten t_end, choose other true values, "
            "or give the parameters, the input and the noise in units nearer 1",
            "t_end",
        )
    seed = DEFAULT_SEED if seed is None else seed
    note = f"{t.size} samples simulated with {named}, input {source}"
    if x0 is not None:
        note += ", from x0 = " + ", ".join(
            f"{name} = {v:g}" for name, v in zip(module.STATES, x0, strict=True)
        )
    y = clean
    if noise_uniform:
        if not 0 <= noise_uniform <= module.MAX_SIGNAL / 100:
            raise DataError(
                f"noise_uniform must be from 0 to {module.MAX_SIGNAL / 100:g}, not "
                f"{noise_uniform:g}",
                "noise_uniform",
            )
        y = clean + np.random.default_rng(seed).uniform(-noise_uniform, noise_uniform, clean.size)
        note += f", noise uniform in [-{noise_uniform:g}, {noise_uniform:g}] (seed {seed})"
    elif noise_snr is not None:
        if not np.isfinite(noise_snr):
            raise DataError(
                f"noise_snr must be a finite number of dB, not {noise_snr}", "noise_snr"
            )
        y = module.with_noise(clean, noise_snr, seed=seed)
        note += f", white Gaussian noise at {noise_snr:g} dB SNR (seed {seed})"
    return Record(t, u, y, clean, k, note)


def initial_state(module: ModuleType, given, u0: float, k) -> np.ndarray | None:
    """The initial state x0 (values in the order of the simulator's STATES, or a dict by
    name: the others at 0) as an array in that order (None: from rest); a DataError for a
    count or a name that does not fit, a state where the model's equations have no value
    (at the first input u0 and the unknowns k), or a module without states (an estimator)."""
    if given is None:
        return None
    states = getattr(module, "STATES", None)
    if states is None:
        raise DataError(
            "x0 sets the initial state of a nonlinear model's simulator (a model with "
            "nonlinear relations, not linearised about an operating point); the transfer "
            "function of a linear or small-signal model is simulated from rest",
            "x0",
        )
    listed = f"{len(states)} state{'s' * (len(states) != 1)}: {', '.join(states)}"
    if isinstance(given, dict):
        strangers = [name for name in given if name not in states]
        if strangers:
            raise DataError(f"x0: {strangers[0]} is not a state of the model (its {listed})", "x0")
        x0 = np.array([given.get(name, 0.0) for name in states])
    elif len(given) != len(states):
        raise DataError(
            f"x0: {len(given)} value{'s' * (len(given) != 1)} for the model's {listed}: "
            f"give one per state in that order, or by name (x0 {states[0]}=...)",
            "x0",
        )
    else:
        x0 = np.array(given, dtype=float)
    with np.errstate(all="ignore"):
        rates = module.rhs(x0, u0, k)
    if not np.isfinite(rates).all():
        where = ", ".join(f"{name} = {value:g}" for name, value in zip(states, x0, strict=True))
        raise DataError(
            f"x0: the model's equations have no value at {where} (with the first input "
            f"{u0:g}): a state outside the domain of their functions (the square root of a "
            "negative level, say)",
            "x0",
        )
    return x0
