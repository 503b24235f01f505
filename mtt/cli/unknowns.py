"""The values of the unknowns on the command line and in what the commands print.

`--k0`, `--true` and `--bounds` take a bare value for a model with one unknown (`--k0 5`,
`--bounds 0:20` or `--bounds 0 20`) and values by name for several (`--k0 ra=1,jl=5`,
`--bounds ra=0.1:10,jl=1:100`; see mtt/cli/value_options.py). Here they become what the generated
module takes: a float for one unknown, an array in the order of its UNKNOWNS for several
(mtt/present/values.py writes them back as text and JSON).
"""

from __future__ import annotations

from types import ModuleType

import numpy as np

from mtt.cli.value_options import in_unknowns_order


def point(module: ModuleType, given, option: str):
    """A value of the unknowns from the command line: a float (one unknown) or an array."""
    values = in_unknowns_order(given, module.UNKNOWNS, option)
    return float(values[0]) if len(values) == 1 else np.array(values, dtype=float)


def bounds(module: ModuleType, given):
    """--bounds as the module's functions take them: (lo, hi) for one unknown; for several
    a dict by name of those given (the module searches the others around the model's values)."""
    if given is None:
        return None
    values = in_unknowns_order(given, module.UNKNOWNS, "--bounds", complete=False)
    if len(values) == 1:
        return values[0]
    return {name: pair for name, pair in zip(module.UNKNOWNS, values, strict=True) if pair}


def true_point(module: ModuleType, given):
    """The unknowns' values to simulate with: --true, else the model file's."""
    if given is not None:
        return point(module, given, "--true")
    value, count = module.TRUE_VALUE, len(module.UNKNOWNS)
    values = (value,) if count == 1 else tuple(value or (None,) * count)
    missing = [name for name, v in zip(module.UNKNOWNS, values, strict=True) if v is None]
    if missing:
        return missing
    return point(module, dict(zip(module.UNKNOWNS, values, strict=True)), "--true")
