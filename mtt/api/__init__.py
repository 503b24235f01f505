"""mtt's Python API: `load` a bond graph model, then read its stages as attributes.

See docs/api.md. Everything here is also `mtt.NAME`.
"""

from mtt.api.examples import Example, copy_examples, examples
from mtt.api.loading import example, load
from mtt.api.matrix import TransferMatrix
from mtt.api.model import Model
from mtt.api.results import Causality, StateSpace, Theta, TransferFunction
from mtt.derivation.identifiability import Identifiability
from mtt.language.diagnostics import MttError

__all__ = [
    "Causality",
    "Example",
    "Identifiability",
    "Model",
    "MttError",
    "StateSpace",
    "Theta",
    "TransferFunction",
    "TransferMatrix",
    "copy_examples",
    "example",
    "examples",
    "load",
]
