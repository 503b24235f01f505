"""The values of a model's unknowns as the commands print them: text (`5` in a column
that names the unknown, `ra = 1.2, jl = 9.8` for several) and JSON (a number, or a list in
the order of `unknowns`; null where not finite)."""

from __future__ import annotations

import math
from types import ModuleType

import numpy as np


def text(module: ModuleType, k, digits: str = "g") -> str:
    """`5` for one unknown (the tables' columns name it), `ra = 1.2, jl = 9.8` for several."""
    if len(module.UNKNOWNS) == 1:
        return format(float(k), digits)
    return ", ".join(
        f"{name} = {format(float(value), digits)}"
        for name, value in zip(module.UNKNOWNS, np.ravel(k), strict=True)
    )


def named(module: ModuleType, k, digits: str = ".6g") -> str:
    """`k = 5` or `ra = 1.2, jl = 9.8`: the values with their names."""
    if len(module.UNKNOWNS) == 1:
        return f"{module.UNKNOWNS[0]} = {format(float(k), digits)}"
    return text(module, k, digits)


def plain(value):
    """A float for JSON (None where not finite), a list of them for an array or a tuple."""
    if value is None:
        return None
    if isinstance(value, tuple | list) or np.ndim(value) > 0:
        return [plain(part) for part in value]
    value = float(value)
    return value if math.isfinite(value) else None
