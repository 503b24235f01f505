"""Computer algebra that may not end: sympy.solve on a model's equations, within a budget.

Solving nonlinear equations exactly (a steady state, a nonlinear algebraic loop) can take
sympy unbounded time on some models (an exponential beside a linear term, say), and a
model file is untrusted input. Such a solve runs in a forked child process that is
stopped when it has used its processor time (measured in processor seconds, so that the
same model gets the same answer on a busy machine; a generous wall-clock limit backs it
up); the caller then falls back (to a numeric solution, or a located error). Where fork
is not available the solve runs in process, unbounded.
"""

from __future__ import annotations

import multiprocessing
from collections.abc import Callable

SECONDS = 3  # of processor time, for one exact solve
WALL = 20  # times SECONDS: the wall-clock limit, on a machine busy with other work


def _child(connection, function, args, seconds: int) -> None:
    import resource

    used = resource.getrusage(resource.RUSAGE_SELF)
    limit = int(used.ru_utime + used.ru_stime) + seconds + 1
    resource.setrlimit(resource.RLIMIT_CPU, (limit, limit + 1))
    try:
        connection.send(("ok", function(*args)))
    except Exception as exc:  # noqa: BLE001 - reported to the parent, which falls back
        connection.send(("error", repr(exc)))
    finally:
        connection.close()


def within(function: Callable, *args, seconds: int = SECONDS):
    """function(*args), or None when it fails or takes more than `seconds` of processor
    time."""
    try:
        context = multiprocessing.get_context("fork")
    except ValueError:  # no fork (Windows): in process
        try:
            return function(*args)
        except Exception:  # noqa: BLE001 - the caller falls back
            return None
    receive, send = context.Pipe(duplex=False)
    child = context.Process(target=_child, args=(send, function, args, seconds), daemon=True)
    child.start()
    send.close()
    try:
        if not receive.poll(seconds * WALL):
            return None
        status, value = receive.recv()
    except (EOFError, OSError):
        return None
    finally:
        if child.is_alive():
            child.kill()
        child.join()
        receive.close()
    return value if status == "ok" else None
