"""The recursive estimates of `mtt estimate` as people and tools read them: a run per
starting value and filter, their table (final estimates, local and global minima, standard
errors), notes, JSON record and trajectories (CSV)."""

from __future__ import annotations

from dataclasses import dataclass
from types import ModuleType

import numpy as np

from mtt.present import tables, values
from mtt.present.fits import uncertainty_lines


@dataclass(frozen=True)
class Run:
    k0: float | np.ndarray  # several unknowns: in the module's UNKNOWNS order
    filter: str  # C(s) as the user wrote it (or the default)
    result: object  # the generated module's Estimate
    k_se: float | np.ndarray | None = None  # see `_least_squares`
    k_ls: float | np.ndarray | None = None  # the record's least-squares minimum (no prior)

    @property
    def ci(self):
        """The approximate 95 % interval about the final estimate (None without k_se)."""
        if self.k_se is None:
            return None
        k, half = np.atleast_1d(self.result.k), 1.96 * np.atleast_1d(self.k_se)
        return np.stack([k - half, k + half], 1)


def start_text(module: ModuleType, run: Run) -> str:
    """`k0 = 5`, or `k0: ra = 0.5, jl = 5` for several unknowns."""
    if len(module.UNKNOWNS) == 1:
        return f"k0 = {run.k0:g}"
    return f"k0: {values.text(module, run.k0)}"


def labels(module: ModuleType, runs: list[Run]) -> list[str]:
    several_k0 = len({values.text(module, run.k0) for run in runs}) > 1
    several_filters = len({run.filter for run in runs}) > 1
    labels = []
    for run in runs:
        parts = [start_text(module, run)] if several_k0 or not several_filters else []
        parts += [f"C(s) = {run.filter}"] if several_filters else []
        labels.append(", ".join(parts))
    return labels


def minima(module: ModuleType, result) -> np.ndarray:
    """The local minima of a run's cost at its end (several unknowns: within its bounds;
    none without them)."""
    if len(module.UNKNOWNS) > 1 and result.bounds is None:
        return np.zeros((0, len(module.UNKNOWNS)))
    return result.minima()


def notes(module: ModuleType, run: Run) -> list[tuple[str, str]]:
    """What a run's table cannot say: it stopped, it is not at the global minimum, or the
    data stopped informing it."""
    result = run.result
    notes = [] if result.ok else [("warning", result.message)]
    if not result.at_global:
        best = result.global_k[-1]
        here, there = values.text(module, result.k, ".6g"), values.text(module, best, ".6g")
        notes.append((
            "warning",
            f"the estimate {values.named(module, result.k)} is a local minimum of J at t = "
            f"{result.t[-1]:g}, with J({here}) - J({there}) = {-float(result.cost(best)):.3g}: "
            f"the global minimum is at {values.named(module, best)}",
        ))  # fmt: skip
    if result.informed_until is not None:
        notes.append((
            "note",
            f"the data stopped informing the estimate at t = {result.informed_until:.6g}: "
            "after that they are rounding noise, which leaves it unchanged",
        ))  # fmt: skip
    return notes


def record(module: ModuleType, runs: list[Run]) -> dict:
    """The --json record (its shape is a public contract): k0, k, minima and global_k are
    numbers for one unknown, lists in the order of `unknowns` for several."""
    plain = values.plain
    single = len(module.UNKNOWNS) == 1
    return {
        "ok": all(run.result.ok for run in runs),
        "model": module.MODEL,
        "unknown": module.UNKNOWN,
        "unknowns": list(module.UNKNOWNS),
        "runs": [
            {
                "k0": plain(run.k0),
                "filter": run.filter,
                "k": plain(run.result.k),
                "minima": plain(minima(module, run.result)),
                "global_k": plain(run.result.global_k[-1]),
                "global_cost": _global_cost(run.result),
                "ok": run.result.ok,
                "stopped_at": run.result.stopped_at,
                "informed_until": run.result.informed_until,
                "k_se": plain(run.k_se),
                "ci": plain(None if run.ci is None else (run.ci[0] if single else run.ci)),
                "k_ls": plain(run.k_ls),
                "warnings": list(run.result.warnings),
            }
            for run in runs
        ],
    }


def _global_cost(result) -> float | None:
    """J(global) - J(estimate); None where J has no global minimiser."""
    best = result.global_k[-1]
    return None if np.isnan(best).any() else values.plain(result.cost(best))


def table(module: ModuleType, note: str, t_end: float, runs: list[Run]) -> str:
    """The final estimates and local minima, then the global minimum of each run's cost."""
    end = f"t = {t_end:g}"
    several = len(module.UNKNOWNS) > 1
    final = tuple(f"{name} at {end}" for name in module.UNKNOWNS)
    estimates = [("k0", "C(s)", *final, "local minima of J")]
    globals_ = [("k0", "C(s)", f"global minimum of J at {end}", "J(global) - J(estimate)", "ok")]
    for run in runs:
        result = run.result
        found = minima(module, result)
        if several:
            listed = f"{len(found)} within the bounds" if result.bounds is not None else "-"
        else:
            listed = ", ".join(f"{value:.6g}" for value in found)
        stopped = "" if result.ok else " (stopped)"
        finals = [f"{value:.6g}" for value in np.atleast_1d(result.k)]
        finals[-1] += stopped
        start = values.text(module, run.k0)
        estimates.append((start, run.filter, *finals, listed))
        best = result.global_k[-1]
        if several and np.isnan(best).any():
            where, cost = "none (no bounds)" if result.bounds is None else "none", "-"
        else:
            where = values.text(module, best, ".6g")
            where += "" if result.at_global else " (not the estimate)"
            cost = f"{float(result.cost(best)):.3g}"
        where += "" if result.ok else f" (at t = {result.t[-1]:g}, where it stopped)"
        ok = "yes" if result.ok else f"no: stopped at t = {result.stopped_at:.6g}"
        globals_.append((start, run.filter, where, cost, ok))
    errors = [f"standard errors at {end} (of least squares on the same cost over the record):"]
    for run in runs:
        start = f"  {start_text(module, run)}, C(s) = {run.filter}"
        if run.k_se is None:
            why = ("stopped" if not run.result.ok else "not at the global minimum"
                   if not run.result.at_global else "not determined")  # fmt: skip
            errors.append(f"{start}: none ({why})")
            continue
        errors += [f"{start}:", *uncertainty_lines(module, run.result.k, run.k_se, run.ci, "    ")]
        held = np.asarray(run.result.k) - np.asarray(run.k_ls)  # a number for one unknown
        if np.any(np.abs(held) > np.asarray(run.k_se)):
            errors.append(
                f"    the prior S0 holds it {values.text(module, held, '+.3g')} from the "
                f"record's least-squares minimum, {values.named(module, run.k_ls)}, more "
                "than a standard error: lower S0 (--S0-relative) or use a longer record"
            )
    return "\n".join(
        [
            f"{module.MODEL}: {note}",
            *tables.rows(estimates),
            "",
            *tables.rows(globals_),
            "",
            *errors,
        ]
    )


def trajectories_csv(module: ModuleType, runs: list[Run]) -> str:
    """k^(t) of every run, and for one unknown J_2..J_2N."""
    if len(module.UNKNOWNS) == 1:
        header = ["run", "k0", "filter", "t", "khat"]
        header += [f"J{i}" for i in range(2, 2 * module.N + 1)]
        rows = (
            [number, run.k0, run.filter, t, khat, *J]
            for number, run in enumerate(runs, start=1)
            for t, khat, J in zip(run.result.t, run.result.khat, run.result.J.T, strict=True)
        )
    else:
        header = ["run", "k0", "filter", "t", *(f"khat_{name}" for name in module.UNKNOWNS)]
        rows = (
            [number, values.text(module, run.k0), run.filter, t, *khat]
            for number, run in enumerate(runs, start=1)
            for t, khat in zip(run.result.t, run.result.khat, strict=True)
        )
    return tables.csv_text(header, rows)


def cost_range(runs: list[Run], k, given: list[float] | None) -> tuple[float, float]:
    """The range of k the cost figure shows: `given`, else the starts, the minima and the
    true value `k` (None: not known) with a margin."""
    if given is not None:
        return given[0], given[1]
    points = [run.k0 for run in runs] + [value for run in runs for value in run.result.minima()]
    points += [] if k is None else [k]
    low, high = min(points), max(points)
    margin = max(0.25 * (high - low), 0.5)
    return low - margin, high + margin


def curves(module: ModuleType, runs: list[Run], banded: bool) -> list:
    """The figures' curves (mtt.present.plots.Curve), one per run: the estimate against
    time, the local minima, the cost (one unknown), the global minimum and, when `banded`,
    the estimate's band."""
    from mtt.present import plots  # matplotlib: a quarter second, paid by plotting only

    several = len(module.UNKNOWNS) > 1
    return [
        plots.Curve(label, run.result.t, run.result.khat, minima(module, run.result),
                    None if several else run.result.normalised_cost, run.result.global_k,
                    band(module, run) if banded else None)
        for label, run in zip(labels(module, runs), runs, strict=True)
    ]  # fmt: skip


def settings(runs: list[Run], beta: float, S0: float, S0_relative: float | None) -> str:
    """The estimator's settings for a figure's title (the filter when every run has one)."""
    weight = f"{S0:g}" if S0_relative is None else f"{S0_relative:g} relative"
    text = f"\u03b2 = {beta:g}, S\u2080 = {weight}"
    if len({run.filter for run in runs}) == 1:
        text += f", C(s) = {runs[0].filter}"
    return text


def band(module: ModuleType, run: Run) -> np.ndarray | None:
    """Half-width of an approximate 95 % band about k^(t) (drawn for a single run: several
    would hide one another; one unknown): the final standard error scaled by the
    information gathered, 1/sqrt(J_2)."""
    if run.k_se is None or len(module.UNKNOWNS) > 1:
        return None
    J2 = run.result.J[0]
    return 1.96 * run.k_se * np.sqrt(J2[-1] / J2)
