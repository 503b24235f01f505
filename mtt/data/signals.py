"""Records of several inputs and outputs: a CSV file whose columns are the time and every
signal, named by the signals' own labels (t,Se:v,Se:tl,Df:speed) or by the names given in
that order (t,u1,u2,y1), for `mtt fit` and `Model.read_csv` alike.
"""

from __future__ import annotations

from collections.abc import Sequence
from types import ModuleType

import numpy as np

from mtt import files
from mtt.data import DataError
from mtt.data.records import Record


def signal_columns(module: ModuleType, given: str | Sequence[str] | None) -> tuple[str, ...]:
    """The CSV columns of the time, each input and each output, in that order (a list of
    names, or text with commas; None: the signals' labels)."""
    default = ("t", *module.INPUTS, *module.OUTPUTS)
    if given is None:
        return default
    parts = given.split(",") if isinstance(given, str) else list(given)
    names = tuple(str(name).strip() for name in parts)
    shown = ",".join(names)
    if len(names) != len(default) or not all(names) or len(set(names)) != len(names):
        raise DataError(
            f"columns takes {len(default)} different names: the time, then the inputs "
            f"{', '.join(module.INPUTS)}, then the outputs {', '.join(module.OUTPUTS)} (now "
            f"{shown!r}; by default {','.join(default)})",
            "columns",
        )
    return names


def read_signals(module: ModuleType, path: str, names: Sequence[str]) -> Record:
    """A measured record of every signal: `t`, then `u` and `y` with a column per input and
    per output (the columns `names`, as `signal_columns` gives them)."""
    files.check_input(path, "data")  # a regular file of bounded size, not an output
    try:
        t, *signals = module.read_csv(path, tuple(names))
    except ValueError as error:  # the module's CSVError: its file, line and kind kept
        if "no column" not in str(error):
            raise
        default = ",".join(signal_columns(module, None))
        raise DataError(
            f"{error}: name the time, each input and each output with columns (by default "
            f"{default})",
            "columns", path=str(path), line=getattr(error, "line", None),
        ) from None  # fmt: skip
    inputs = len(module.INPUTS)
    u, y = np.column_stack(signals[:inputs]), np.column_stack(signals[inputs:])
    return Record(t, u, y, None, None, f"{t.size} samples from {path}")
