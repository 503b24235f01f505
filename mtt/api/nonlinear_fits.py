"""The fit of a nonlinear model (issue 20): its simulator's prediction-error `fit`, started
where the paper's method is global, at the small-signal model's estimate.

About an operating point the nonlinear model is linear, and there mtt's linear chain
(Theta, the paper's polynomial-in-k cost) finds the global minimum of its criterion. A
record that swings across the nonlinearity is not fitted exactly by that small-signal
model, but its estimate is usually in the basin of the nonlinear fit's minimum: it is the
first start (then k0, the model file's values and a small multistart over the bounds).
"""

from __future__ import annotations

import warnings
import weakref
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from mtt.language.diagnostics import MttError

if TYPE_CHECKING:
    from mtt.api.model import Model

BRANCHES = 4  # steady-state branches tried for the small-signal model, at most
KEPT = 8  # small-signal estimators kept per model (operating points and branches)

# model -> {(branch, input level): its small-signal estimator, or the MttError deriving it
# raised}: what depends on the model and the operating point alone is derived once (the
# steady state, the linearisation, Theta and the generated estimator: most of a repeated
# start's time), the record's fit each time.
_ESTIMATORS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _small_signal(model: Model, branch: int | None, level: float):
    """The estimator of the model linearised at the steady state for the input `level`
    (that branch of it), kept per model; the MttError deriving it raised, raised again."""
    kept = _ESTIMATORS.setdefault(model, {})
    key = (branch, level)
    if key not in kept:
        try:
            kept[key] = model.linearise(branch=branch, u=level).estimator()
        except MttError as error:
            kept[key] = error
        while len(kept) > KEPT:
            del kept[next(iter(kept))]
    if isinstance(kept[key], MttError):
        raise kept[key]
    return kept[key]


@dataclass(frozen=True)
class Start:
    """The small-signal model's estimate as a start of the nonlinear fit: the point (None
    when there is none) and what it is, or why there is none."""

    k: np.ndarray | None
    note: str


def linearised_start(model: Model, t, u, y, *, hold: str = "linear") -> Start:
    """The small-signal model's fit to the (first) record, about the steady state at its
    mean input; where there are several (a pendulum hanging or upright), each branch's
    small-signal model is fitted and the one that fits best is taken."""
    record = (t, u, y) if np.ndim(t[0]) == 0 else (t[0], u[0], y[0])
    level = float(np.mean(record[1]))
    branches: tuple = (None,)
    fits, why = [], "no steady state"
    while branches:
        branch, branches = branches[0], branches[1:]
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                found = _small_signal(model, branch, level).fit(*record, hold=hold)
        except MttError as error:
            if error.kind == "several_equilibria" and branch is None:
                branches = tuple(range(1, BRANCHES + 1))
            elif not (error.kind == "bad_point" and fits):  # past the last branch
                why = str(error).splitlines()[0]
            continue
        except ValueError as error:  # a record the linear estimator refuses
            why = str(error).splitlines()[0]
            break
        if found.ok and np.all(np.isfinite(found.k)):
            fits.append((found.residual_rms, branch, found.k))
        else:
            why = found.message
    if not fits:
        return Start(None, f"no small-signal start at u = {level:.6g}: {why}")
    _, branch, k = min(fits, key=lambda fit: fit[0])
    shown = f"u = {level:.6g}" + (f", branch {branch}" if branch is not None else "")
    return Start(np.atleast_1d(np.asarray(k, dtype=float)), f"the small-signal model at {shown}")


LINEAR = dict(method="pem", C="auto", beta=0.0)  # Model.fit's options of a linear model only


def fit(model: Model, t, u, y, *, k0=None, starts=(), linearised: bool = True,
        hold: str = "linear", **options):  # fmt: skip
    """The simulator's `fit` (its options: noise, starts, multistart, shooting, segments,
    profile, x0...), its starts led by the small-signal model's estimate (`linearised`); the
    Fit as `Model.fit` gives it. The options of a linear model's fit only (method, C, beta)
    are refused unless at their defaults."""
    from mtt.api.fits import Fit, delegate

    for name, default in LINEAR.items():
        if options.pop(name, default) != default:
            raise MttError(
                f"{name} is an option of a linear model's fit; {model.name} is nonlinear "
                "(its fit is by prediction error)",
                kind="bad_argument",
            )
    module = model.simulator()
    given = [starts] if isinstance(starts, dict) or np.ndim(starts) == 0 else list(starts)
    notes = []
    if linearised:
        start = linearised_start(model, t, u, y, hold=hold)
        if start.k is not None:
            given.insert(0, (start.note, start.k))
        else:
            notes.append(start.note)
    try:
        result = delegate(module.fit, t, u, y, k0=k0, starts=given, hold=hold, **options)
    except TypeError as exc:  # an option the fit does not take
        raise MttError(str(exc), kind="bad_argument") from exc
    records = [t] if np.ndim(t[0]) == 0 else t
    if notes:  # no small-signal start: the multistart had to do without it
        result = replace(result, warnings=(*result.warnings, *notes))
    return Fit(result, module, tuple(f"{np.size(r)} samples" for r in records))
