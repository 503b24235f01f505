"""The derivation's work budget: how large what it builds may grow, checked as it grows.

A valid model can ask for an exponentially large result: an RC ladder whose resistances
and capacitances all stay symbolic has a transfer function with Fibonacci-many terms
(121393 for 12 sections). The limits on the text (language.md) bound the input, not what
the derivation makes of it; this bounds the derivation. Every stage that builds
polynomials in the symbols reports each one it builds to a `Meter` (`hold`) and the work
it is about to do (`spend`, in products of two terms), so the derivation stops with
`too_large` before the work or the memory gets out of hand, never with a MemoryError.

One `Budget` is chosen per derivation (`--max-terms`, `mtt.load(max_terms=...)`); the
`Meter` is its running account. `refusal` turns the stop into the located model error:
which stage, how big, and how to make the result smaller.
"""

from __future__ import annotations

from dataclasses import dataclass

from mtt.derivation import deadline
from mtt.language.bondgraph import BondGraph
from mtt.language.diagnostics import ModelError, MttError, error

# A polynomial of 30000 terms in some 20 variables takes some 30 MB as sympy's polynomial,
# ten times that as a sympy expression: a 10-section ladder with every parameter symbolic
# (17711 terms in its result, 20295 in the largest polynomial on the way) derives and
# prints within the default budget in some 20 s of processor time; 12 sections (121393
# terms) are refused.
DEFAULT_MAX_TERMS = 30_000
# Products of two terms (each a dictionary update in sympy's sparse polynomials, about a
# microsecond) allowed per term of the budget: 30000 terms allow 1.5e7, some 15-30 s.
WORK_PER_TERM = 500


@dataclass(frozen=True)
class Budget:
    """How large the polynomials of one derivation may grow (terms of one polynomial), and
    so how much work it may do (`WORK_PER_TERM` products of two terms per term)."""

    max_terms: int = DEFAULT_MAX_TERMS

    def __post_init__(self) -> None:
        if not isinstance(self.max_terms, int) or self.max_terms < 1:
            raise ValueError(f"max_terms must be a positive integer, not {self.max_terms!r}")

    @property
    def max_work(self) -> int:
        return WORK_PER_TERM * self.max_terms


DEFAULT_BUDGET = Budget()


class TooLarge(Exception):
    """The derivation stopped before exceeding its budget: in which stage, what measure
    (`terms` of one polynomial, or `work`), the size reached or about to be, and the
    limit."""

    def __init__(self, stage: str, measure: str, size: int, limit: int):
        super().__init__(f"{stage}: {measure} {size} > {limit}")
        self.stage, self.measure, self.size, self.limit = stage, measure, size, limit


class Meter:
    """The running account of one derivation against its `Budget`."""

    def __init__(self, budget: Budget, stage: str):
        self.budget = budget
        self.stage = stage  # the stage now spending, named in the refusal
        self.work = 0
        self.largest = 0  # the most terms of one polynomial built so far

    def hold(self, terms: int) -> None:
        """A polynomial of `terms` terms is about to be kept (or was just built)."""
        self.largest = max(self.largest, terms)
        if terms > self.budget.max_terms:
            raise TooLarge(self.stage, "terms", terms, self.budget.max_terms)

    def spend(self, work: int) -> None:
        """`work` products of two terms are about to be done (and the time limit, the
        other side of the budget, is checked: mtt.derivation.deadline)."""
        deadline.check()
        self.work += work
        if self.work > self.budget.max_work:
            raise TooLarge(self.stage, "work", self.work, self.budget.max_work)


def chosen_budget(max_terms: object) -> Budget:
    """The budget of `max_terms` as a caller gives it (None: the default)."""
    if max_terms is None:
        return DEFAULT_BUDGET
    if not isinstance(max_terms, int) or isinstance(max_terms, bool) or max_terms < 1:
        raise MttError(f"max_terms takes a positive integer, not {max_terms!r}", kind="bad_value")
    return Budget(max_terms)


def refusal(graph: BondGraph, symbols: tuple[str, ...], stop: TooLarge) -> ModelError:
    """The `too_large` error for a derivation stopped by its budget, with the stage, the
    size and what to do about it; at the declaration of the first parameter kept symbolic
    (the symbols make results grow: `symbols` are the unknowns and the kept ones)."""
    terms = stop.limit if stop.measure == "terms" else stop.limit // WORK_PER_TERM
    if stop.measure == "terms":
        what = f"a polynomial of {stop.size} terms, more than the {stop.limit} allowed"
    else:
        what = f"more than {stop.limit} products of terms, the work {terms} terms allow"
    kept = [name for name in symbols if name not in graph.unknowns]
    advice = []
    if kept:
        shown = ", ".join(kept[:6]) + (", ..." if len(kept) > 6 else "")
        are = "s are" if len(kept) > 1 else " is"
        advice.append(
            f"{len(kept)} parameter{are} symbolic ({shown}): give some of them values (in the "
            "model or with --set) or keep fewer symbolic (--keep, --symbolic)"
        )
    if len(symbols) - len(kept) > 1:
        advice.append("identify fewer unknowns at once (--unknown)")
    advice.append(f"or allow more with --max-terms (now {terms})")
    message = f"the {stop.stage} would need {what}; " + "; ".join(advice)
    first = (kept or list(symbols) or [None])[0]
    where = graph.parameters[first].position if first in graph.parameters else None
    return ModelError(graph.source, [error("too_large", message, where or graph.name_position)])
