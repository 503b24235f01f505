"""mtt: from a bond graph with an unknown parameter to an estimator for that parameter.

>>> import mtt
>>> model = mtt.load(mtt.example("dc_drive"))
>>> model.transfer_function.den
k*s**4 + 10*k*s**3 + 11*k*s**2 + 10*k*s + s**2 + 10*s + 10

The API lives in mtt.api (docs/api.md); `import mtt` stays light (no sympy, numpy or
scipy) until one of its names is used, so that the `mtt` command starts at once.
"""

from mtt.language.diagnostics import MttError
from mtt.version import __version__ as __version__

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


def __getattr__(name: str):
    if name in __all__:
        from mtt import api

        return getattr(api, name)
    if name == "batch":  # mtt.batch.fit_many: many records on many cores (docs/batch.md)
        import importlib

        return importlib.import_module("mtt.batch")
    raise AttributeError(f"module 'mtt' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
