"""A time limit on the derivation: a model from someone else cannot keep mtt busy for
minutes. The limit is processor time of mtt's process, not time on the wall, so that the
same model ends the same way on an idle machine and on a busy one. The size limits
(mtt.language.measures, the derivation's own) bound the work they can foresee; this bounds
the rest: past its time, a stage of the derivation stops with `too_large`, placed at the
model's name.

Each stage (`derive`, `transfer_function`, identifiability) is `timed`: its loops call
`check()`, which works in any thread, and on the main thread a timer signal (SIGPROF,
counting processor time) interrupts a single long computation inside sympy as well. A
`budget` (one per command of the `mtt` program) is shared by the stages run inside it;
outside one, each stage has the whole limit: `MTT_TIME_LIMIT` seconds from the
environment, else `DEFAULT_SECONDS`.
"""

from __future__ import annotations

import contextlib
import functools
import math
import os
import signal
import threading
import time
from collections.abc import Callable, Iterator
from contextvars import ContextVar
from dataclasses import dataclass

from mtt.language.diagnostics import ModelError, error

DEFAULT_SECONDS = 30.0


class OutOfTime(Exception):
    """The running stage passed its deadline."""


@dataclass
class Budget:
    seconds: float  # for all the stages run inside it (inf: no limit)
    used: float = 0.0


_BUDGET: ContextVar[Budget | None] = ContextVar("mtt_time_budget", default=None)
_DEADLINE: ContextVar[float | None] = ContextVar("mtt_deadline", default=None)


def default_seconds() -> float:
    """MTT_TIME_LIMIT (seconds; 0 or "none" for no limit), else DEFAULT_SECONDS."""
    text = os.environ.get("MTT_TIME_LIMIT", "").strip().lower()
    if not text:
        return DEFAULT_SECONDS
    if text == "none":
        return math.inf
    try:
        seconds = float(text)
    except ValueError:
        return DEFAULT_SECONDS
    return math.inf if seconds == 0 else seconds if seconds > 0 else DEFAULT_SECONDS


@contextlib.contextmanager
def budget(seconds: float | None = None) -> Iterator[Budget]:
    """The stages run inside the block share `seconds` (None: the default; inf: none)."""
    token = _BUDGET.set(Budget(default_seconds() if seconds is None else seconds))
    try:
        yield _BUDGET.get()
    finally:
        _BUDGET.reset(token)


def check() -> None:
    """Raise `OutOfTime` when the running stage is past its deadline (cheap: call it in
    loops)."""
    deadline = _DEADLINE.get()
    if deadline is not None and time.process_time() > deadline:
        raise OutOfTime


def _alarm(signum, frame):
    raise OutOfTime


@contextlib.contextmanager
def _interrupting(seconds: float) -> Iterator[None]:
    """On the main thread, a SIGPROF after `seconds` of processor time (when no one else
    uses SIGPROF)."""
    usable = (
        hasattr(signal, "setitimer")
        and threading.current_thread() is threading.main_thread()
        and signal.getsignal(signal.SIGPROF) in (signal.SIG_DFL, None)
        and math.isfinite(seconds)
    )
    if not usable:
        yield
        return
    previous = signal.signal(signal.SIGPROF, _alarm)
    signal.setitimer(signal.ITIMER_PROF, max(seconds, 1e-3))
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_PROF, 0)
        signal.signal(signal.SIGPROF, previous)


def timed(stage: str, graph_of: Callable) -> Callable:
    """A stage of the derivation under the time limit; `graph_of(first argument)` is the
    bond graph its `too_large` error is placed in."""

    def decorate(function: Callable) -> Callable:
        @functools.wraps(function)
        def run(*args, **kwargs):
            if _DEADLINE.get() is not None:  # inside another timed stage: its deadline holds
                return function(*args, **kwargs)
            shared = _BUDGET.get()
            limit = shared.seconds if shared else default_seconds()
            left = limit - (shared.used if shared else 0.0)
            start = time.process_time()
            token = _DEADLINE.set(start + left)
            try:
                if left <= 0:
                    raise OutOfTime
                with _interrupting(left):
                    return function(*args, **kwargs)
            except OutOfTime:
                raise _too_slow(graph_of(args[0]), stage, limit) from None
            finally:
                _DEADLINE.reset(token)
                if shared:
                    shared.used += time.process_time() - start

        return run

    return decorate


def _too_slow(graph, stage: str, seconds: float) -> ModelError:
    message = (
        f"the derivation ({stage}) took more than {seconds:g} s of processor time (a limit): "
        "the model is too large, or its values too intricate, for exact algebra in that time; "
        "--time-limit SECONDS (MTT_TIME_LIMIT in the environment) allows more"
    )
    return ModelError(graph.source, [error("too_large", message, graph.name_position)])
