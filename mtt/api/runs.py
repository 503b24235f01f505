"""Several recursive estimates of one record: the generated module's `estimate` from each
start with each filter C(s), as `mtt estimate` prints and draws them (mtt.present.estimates).

Each run that ends at the global minimum gets its final estimate's standard error from the
least-squares fit of the same cost over the record (one fit per filter, shared by the
starts).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from types import ModuleType

import numpy as np

from mtt.data.records import Record
from mtt.present.estimates import Run


def run_all(
    module: ModuleType,
    data: Record,
    filters: Sequence[tuple[str, object]],
    starts: Sequence[object],
    *,
    S0_relative: float | None = None,
    progress: Callable[[float], None] | None = None,
    **options,
) -> list[Run]:
    """One estimate per (label, C) of `filters` and start of `starts`, in that order.

    options: the module's `estimate` options (beta, S0, hold, engine, bounds, rtol, atol);
    S0_relative: S0 for each run from the module's `prior_weight` (a fraction of the
    information in the record) instead of options' S0; progress(seconds): the seconds of
    data estimated so far, over all the runs.
    """
    span = float(data.t[-1] - data.t[0])
    runs: list[Run] = []
    fits: dict[bytes, object] = {}  # the least-squares fit per filter: runs from each k0 share it
    for label, C in filters:
        for k0 in starts:
            done = span * len(runs)
            if S0_relative is not None:
                options["S0"] = module.prior_weight(
                    data.t, data.u, data.y, k0=k0, fraction=S0_relative, C=C,
                    hold=options.get("hold", "linear"),
                )  # fmt: skip
            result = module.estimate(
                data.t, data.u, data.y, k0=k0, C=C, **options,
                progress=None if progress is None
                else lambda now, done=done: progress(done + now - data.t[0]),
            )  # fmt: skip
            if progress is not None:
                progress(done + span)
            runs.append(Run(k0, label, result, *_least_squares(module, data, result, options,
                                                                fits)))  # fmt: skip
    return runs


def _least_squares(module: ModuleType, data: Record, result, options: dict, fits: dict) -> tuple:
    """(k_se, k_ls): the final estimate's standard error (a vector for several unknowns),
    that of the least-squares fit of the same cost J over the record, with the same filter
    and forgetting (its sandwich variance, which counts the colour of the equation error),
    and that fit's minimiser, where the estimate would be without the prior S0. (None, None)
    when the run stopped, ended at a local minimum that is not the global one (whose basin
    the fit's figures do not describe), or the data do not determine k. `fits` keeps the
    fit of each filter (C="auto" may choose another for another k0)."""
    if not (result.ok and result.at_global):  # stopped, or in another minimum's basin
        return None, None
    key = np.asarray(result.filter, dtype=float).tobytes()
    if key not in fits:
        fits[key] = module.fit(data.t, data.u, data.y, method="ls", C=result.filter,
                               beta=options.get("beta", 0.0), hold=options.get("hold", "linear"),
                               offset=False, initial_state=False)  # fmt: skip
    final = fits[key]  # (its ok also weighs the exact output error, not J's own figures)
    if not (np.all(np.isfinite(final.k)) and np.all(np.isfinite(final.k_se))):
        return None, None
    return final.k_se, final.k
