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
    params = model.state_space.equations.parametrisation
    free = params.unknowns + params.symbols
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


def state_space(model, k: object, known: Mapping[str, object]):
    """(A, B, C, D, states) of x' = A x + B u, y = C x + D u at the values given: the bond
    graph's own (its energy variables, named) when E is invertible there, else a
    realisation of the transfer matrix (exact, not minimal: n states per input, or per
    output when there are fewer outputs; states None)."""
    try:
        return (*model.state_space.at(k, **known), list(model.state_space.states))
    except MttError as exc:
        if exc.kind != "singular_model":
            raise
    try:
        return (*_realisation(*model.transfer_matrix.at(k, **known)), None)
    except ValueError as exc:  # a numerator of higher degree than A: no state space
        raise MttError(f"{model.name} has no state-space form here: {exc}",
                       kind="singular_model") from None  # fmt: skip


def _realisation(B, A):
    """A controllable canonical form per input of G = B / A (B: outputs x inputs x
    coefficients), side by side; with fewer outputs than inputs, G's transpose's,
    transposed (an observable form per output)."""
    import numpy as np
    import scipy.signal
    from scipy.linalg import block_diag

    if B.shape[0] < B.shape[1]:
        a, b, c, d = _realisation(B.transpose(1, 0, 2), A)
        return a.T, c.T, b.T, d.T
    parts = []
    for j in range(B.shape[1]):
        num = B[:, j, :]
        lead = np.flatnonzero(num.any(axis=0))  # leading zeros of every row: a lower degree
        parts.append(scipy.signal.tf2ss(num[:, lead[0] if lead.size else -1 :], A))
    return (
        block_diag(*(part[0] for part in parts)),
        block_diag(*(part[1] for part in parts)),
        np.hstack([part[2] for part in parts]),
        np.hstack([part[3] for part in parts]),
    )


def to_scipy(model, k: object, known: Mapping[str, object], dt: float | None, method: str):
    import scipy.signal

    check_options(model, k, {"dt": dt, "method": None if method == "zoh" else method})
    if model.bondgraph.several:
        system = scipy.signal.StateSpace(*state_space(model, k, known)[:4])
    else:
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
    names = {"name": model.name, "inputs": list(model.inputs), "outputs": list(model.outputs)}
    if form == "tf" and model.bondgraph.several:  # each entry reduced
        rows, columns = range(len(model.outputs)), range(len(model.inputs))
        entries = [[model.transfer_matrix.entry(i, j).at(k, **known) for j in columns]
                   for i in rows]  # fmt: skip
        num = [[entry[0] for entry in row] for row in entries]
        system = control.tf(num, [[entry[1] for entry in row] for row in entries], **names)
    elif form == "tf":
        system = control.tf(*model.transfer_function.at(k, **known), **names)
    elif form == "ss":
        A, B, C, D, states = state_space(model, k, known)
        system = control.ss(A, B, C, D, **({"states": states} if states else {}), **names)
    else:
        raise MttError(f'form must be "tf" or "ss", not {form!r}', kind="bad_argument")
    if dt is None:
        return system
    if form == "tf" and model.bondgraph.several:  # control samples MIMO systems as ss only
        sampled = to_control(model, k, known, "ss", dt, method)
        return control.ss2tf(sampled, name=model.name)
    return control.sample_system(system, _sampling(dt, method), method=method, name=model.name)
