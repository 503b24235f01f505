"""The committed estimator modules (generated/), imported as a user imports them."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def generated(name: str):
    spec = importlib.util.spec_from_file_location(name, ROOT / "generated" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # so that its dataclasses (and pickles) find their module
    spec.loader.exec_module(module)
    return module
