"""A model at given values as another library's linear system: scipy.signal (continuous,
or discrete with a hold) and python-control (transfer function or state space, with the
names mtt knows: the system's, its input's, its output's and its states')."""

from __future__ import annotations

import math
from collections.abc import Mapping

from mtt.language.diagnostics import MttError

METHODS = ("zoh", "foh", "bilinear", "impulse")  # discretisations scipy and control share
OPTIONS = ("dt", "method", "form")  # keywords of to_scipy and to_control, not parameters


def check_options(model, k: object, used: Mapping[str, object]) -> None:
    """Refuse an option keyword that is also the name of one of the model's free
    parameters, unless that parameter's value is in k (a dict): which was meant?"""
    free = model.transfer_function.unknowns + model.transfer_function.symbols
    for name, value in used.items():
        if value is not None and name in free and not (isinstance(k, Mapping) and name in k):
            raise MttError(
                f"{name}= is ambiguous: an option here and a parameter of {model.name}; give "
                f"the parameter in a dict, ({{{name!r}: ...}}, {name}=...)",
                kind="bad_argument",
            )


def _sampling(dt: object, method: str) -> float:
    if method not in METHODS:
        raise MttError(
            f"method must be one of {', '.join(METHODS)}, not {method!r}", kind="bad_argument"
        )
    if isinstance(dt, bool) or not isinstance(dt, int | float) or not 0 < dt < math.inf:
        raise MttError(f"dt must be a positive sampling interval, not {dt!r}", kind="bad_value")
    return float(dt)


def to_scipy(model, k: object, known: Mapping[str, object], dt: float | None, method: str):
    import scipy.signal

    check_options(model, k, {"dt": dt, "method": None if method == "zoh" else method})
    system = scipy.signal.TransferFunction(*model.transfer_function.at(k, **known))
    return system if dt is None else system.to_discrete(_sampling(dt, method), method=method)


def to_control(
    model, k: object, known: Mapping[str, object], form: str, dt: float | None, method: str
):
    try:
        import control
    except ImportError:
        raise MttError(
            "to_control needs python-control: pip install -e '.[control]' in mtt's clone",
            kind="missing_dependency",
        ) from None
    check_options(model, k, {"dt": dt, "form": None if form == "tf" else form,
                             "method": None if method == "zoh" else method})  # fmt: skip
    names = {"name": model.name, "inputs": [model.input], "outputs": [model.output]}
    if form == "tf":
        system = control.tf(*model.transfer_function.at(k, **known), **names)
    elif form == "ss":
        A, B, C, D = model.state_space.at(k, **known)
        system = control.ss(A, B, C, D, states=list(model.state_space.states), **names)
    else:
        raise MttError(f'form must be "tf" or "ss", not {form!r}', kind="bad_argument")
    if dt is None:
        return system
    return control.sample_system(system, _sampling(dt, method), method=method, name=model.name)
