"""Where chunks of records run: in this process, on a concurrent.futures executor, or on a
dask.distributed cluster; each yields chunks' results as they finish.

A chunk whose worker dies (a killed process: concurrent.futures' BrokenProcessPool, dask's
KilledWorker) is sent again, to a fresh process pool if the pool broke. A chunk that has
been running at ATTEMPTS deaths is split into single records, each then run alone (nothing
else running), so that a record that kills its worker is known: its death is its error.
Every record ends exactly once, as a result or as an error.
"""

from __future__ import annotations

import math
import multiprocessing
import os
import threading
from collections import deque
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import FIRST_COMPLETED, CancelledError, Executor, ProcessPoolExecutor
from concurrent.futures import wait as wait_for
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass

from mtt.batch import worker
from mtt.language.diagnostics import MttError

ATTEMPTS = 3  # deaths of the workers running a chunk before its records run one by one
IN_FLIGHT = 2  # chunks given per worker at a time: one running, one waiting


@dataclass
class Chunk:
    """Records (position, name, spec) sent to a worker at once. `deaths`: workers that died
    while running it; `suspect`: a single record split from a chunk that kept dying."""

    number: int
    items: list
    deaths: int = 0
    suspect: bool = False


class Died(Exception):
    """The worker running this record died, with the record alone in the pool."""


Call = Callable[[Chunk], tuple[Callable, tuple]]


def default_jobs() -> int:
    """As many workers as cores this process may use."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


class Runner:
    """The loop shared by the pools: keep IN_FLIGHT chunks per worker submitted (so that an
    iterator of records is read as it goes), yield results, send dead chunks again."""

    workers = 1

    def results(self, chunks: Iterable[Chunk], call: Call) -> Iterator[tuple[Chunk, object]]:
        source, queue, running = iter(chunks), deque(), {}
        while True:
            while len(running) < IN_FLIGHT * self.workers and not any(
                chunk.suspect for chunk in running.values()
            ):
                if queue and queue[0].suspect and running:
                    break  # a suspect runs alone
                chunk = queue.popleft() if queue else next(source, None)
                if chunk is None:
                    break
                running[self._submit(*call(chunk))] = chunk
            if not running:
                return
            deaths = 0
            for handle, result, death in self._finished(running):
                chunk = running.pop(handle)
                if death is None:
                    yield chunk, result
                    continue
                deaths += 1
                if chunk.suspect:
                    yield (
                        chunk,
                        Died(f"the worker process died while fitting this record alone ({death})"),
                    )
                elif chunk.deaths + 1 < ATTEMPTS:
                    chunk.deaths += 1
                    queue.appendleft(chunk)
                else:
                    queue.extendleft(
                        Chunk(chunk.number, [item], suspect=True) for item in reversed(chunk.items)
                    )
            if deaths:
                self._recover()

    def hold(self, function, args):
        """function(*args) kept where it ran, for the tasks given it later (None: this pool
        keeps nothing between tasks)."""
        return None

    def _submit(self, function, args):
        raise NotImplementedError

    def _finished(self, running) -> list[tuple[object, object, str | None]]:
        """(handle, result, None) or (handle, None, why the worker died) for finished chunks."""
        raise NotImplementedError

    def _recover(self) -> None:
        pass

    def close(self) -> None:
        pass


class InProcess(Runner):
    """Chunks run here, one after another (jobs=1)."""

    def hold(self, function, args):
        return function(*args)

    def results(self, chunks: Iterable[Chunk], call: Call) -> Iterator[tuple[Chunk, object]]:
        for chunk in chunks:
            function, args = call(chunk)
            yield chunk, function(*args)


class Futures(Runner):
    """Chunks on a concurrent.futures executor; a broken process pool is replaced by a
    fresh one of the same size (shut down by this batch at its end)."""

    def __init__(self, executor: Executor, own: bool):
        self.executor, self.own = executor, own
        self.workers = getattr(executor, "_max_workers", None) or default_jobs()

    broken = False

    def _submit(self, function, args):
        try:
            return self.executor.submit(function, *args)
        except BrokenProcessPool:
            self.broken = True
            self._recover()
            return self.executor.submit(function, *args)

    def _finished(self, running):
        done, _ = wait_for(running, return_when=FIRST_COMPLETED)
        if any(not f.cancelled() and isinstance(f.exception(), BrokenProcessPool) for f in done):
            done, _ = wait_for(running)  # a broken pool fails all its futures at once: take them
        out = []
        for future in done:
            try:
                out.append((future, future.result(), None))
            except (BrokenProcessPool, CancelledError) as error:
                self.broken = True
                out.append((future, None, f"{type(error).__name__}: {error}"))
        return out

    def _recover(self) -> None:
        if not self.broken:
            return
        self.broken = False
        if self.own:
            self.executor.shutdown(wait=False, cancel_futures=True)
        context = getattr(self.executor, "_mp_context", None)  # a pool like the broken one
        self.executor, self.own = ProcessPoolExecutor(self.workers, mp_context=context), True

    def close(self) -> None:
        if self.own:
            self.executor.shutdown(wait=True, cancel_futures=True)


def process_pool(jobs: int) -> ProcessPoolExecutor:
    """jobs worker processes, forked from this one while it runs no other thread (they
    start at once, with numpy, scipy and the module already imported); else started by a
    fork server where there is one (forking a process that runs threads may deadlock its
    child), else the platform's way."""
    methods = multiprocessing.get_all_start_methods()
    if "fork" in methods and threading.active_count() == 1:
        method = "fork"  # the pool forks all its workers at its first task, still one thread
    else:
        method = "forkserver" if "forkserver" in methods else None
    return ProcessPoolExecutor(jobs, mp_context=multiprocessing.get_context(method))


def is_dask_client(executor: object) -> bool:
    return type(executor).__module__.split(".")[0] == "distributed" and hasattr(
        executor, "nthreads"
    )


class Dask(Runner):
    """Chunks on a dask.distributed cluster, through a Client. The workers import mtt's
    worker module alone (standard library only; the estimator arrives as source). Dask
    itself runs again the tasks of a worker that died; a chunk it gives up on
    (KilledWorker) is sent again as above."""

    def __init__(self, client):
        from distributed import as_completed

        self.client = client
        self.workers = max(sum(client.nthreads().values()), 1)
        self.pending = as_completed(loop=client.loop)

    def share(self, value):
        """A future of `value` on the cluster (recomputed there if the workers holding it die)."""
        return self.client.submit(worker.same, value, pure=False)

    def hold(self, function, args):
        return self.client.submit(function, *args, pure=False)

    def _submit(self, function, args):
        future = self.client.submit(function, *args, pure=False)
        self.pending.add(future)
        return future

    def _finished(self, running):
        from distributed import KilledWorker

        future = next(self.pending)
        try:
            return [(future, future.result(), None)]
        except (KilledWorker, CancelledError) as error:
            return [(future, None, f"{type(error).__name__}: {error}")]


CHUNK = 32  # records per chunk at most
CHUNKS = 64  # a batch of known size is cut into about this many chunks (few: small ones)
STREAMED_CHUNK = 8  # records per chunk when their number is not known in advance


def chunks(specs: list | Iterator, size: int | None) -> Iterator[Chunk]:
    """The (name, spec) pairs in chunks of `size` records (None: a size for their number)."""
    if size is None:
        size = (
            max(1, min(CHUNK, math.ceil(len(specs) / CHUNKS)))
            if isinstance(specs, list)
            else STREAMED_CHUNK
        )
    elif not (isinstance(size, int) and size >= 1):
        raise MttError(f"chunk_size must be a whole number >= 1, not {size!r}", kind="bad_value")
    items: list = []
    number = 0
    for position, (name, spec) in enumerate(specs):
        items.append((position, name, spec))
        if len(items) == size:
            yield Chunk(number, items)
            number, items = number + 1, []
    if items:
        yield Chunk(number, items)
