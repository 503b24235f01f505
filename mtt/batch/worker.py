"""What a worker process runs: a chunk of records through the generated estimator module.

Workers receive the module's source text (never a pickled function of the caller) and
import it once per process, under a name made from the text's hash (`module_name`): the
module's results (Fit, Moments, ...) pickle by that name, and the caller registers its own
copy of the module under the same name, so that they come back as its classes.

This file needs only the standard library and what the generated module needs (numpy and
scipy; pandas for Parquet records): importing it is all a worker process does of mtt.
"""

from __future__ import annotations

import contextlib
import hashlib
import importlib
import linecache
import os
import sys
import time
import types
import warnings
from collections import OrderedDict

PREFIX = "_mtt_batch_"
PARQUET = (".parquet", ".pq")
CACHE_BYTES = 1 << 29  # records kept by a process between the steps of a pooled fit
_READ: OrderedDict = OrderedDict()


def module_name(source: str) -> str:
    return PREFIX + hashlib.sha256(source.encode("utf-8")).hexdigest()[:20]


def same(value):
    """value itself (a task whose result the cluster keeps, and can make again)."""
    return value


def module_for(name: str, source: str) -> types.ModuleType:
    """The generated module of this source, imported once per process (sys.modules keeps it).

    The caller may have registered its own copy under `name` (api.estimator), and a forked
    worker inherits it: it is used while its classes still pickle, that is while it is the
    module of its own name. A copy imported again since (a notebook cell run twice, models
    of one name with other values) is replaced by the source run under `name`."""
    module = sys.modules.get(name)
    if module is None or not _pickles(module):
        module = types.ModuleType(name)
        module.__file__ = f"<{name}>"
        linecache.cache[module.__file__] = (len(source), None, source.splitlines(True), "")
        sys.modules[name] = module  # before running it: its dataclasses look themselves up
        try:
            exec(compile(source, module.__file__, "exec"), module.__dict__)
        except BaseException:
            del sys.modules[name]
            raise
    return module


def _pickles(module: types.ModuleType) -> bool:
    """Whether objects of this module's classes pickle: it is the module of its own name."""
    return sys.modules.get(module.__name__) is module


def one_thread():
    """BLAS on one thread: a worker per core already uses the cores, and the estimator's
    matrices are small (more threads make it several times slower and change the last
    bits of its sums)."""
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:  # a cluster's worker without it: dask's nanny sets OPENBLAS_NUM_THREADS=1
        return contextlib.nullcontext()
    return threadpool_limits(limits=1, user_api="blas")


def several(module) -> bool:
    """Whether the module has several inputs or outputs: its records are (t, U, Y), a
    column per signal, fitted by `fit_signals`."""
    return hasattr(module, "fit_signals")


def default_columns(module) -> tuple[str, ...]:
    """The columns of a module's records: t, u, y, or the time and every signal's label."""
    if several(module):
        return ("t", *module.INPUTS, *module.OUTPUTS)
    return ("t", "u", "y")


def read(module, spec, columns, cache: bool = False):
    """A record's (t, u, y) arrays: spec is a path (CSV, or Parquet through pandas) or the
    arrays themselves; then checked as `fit` checks them (several signals: (t, U, Y), the
    columns the time, every input and every output, as `fit_signals` checks them). cache:
    keep a file's arrays in this process (a pooled fit's every step reads its records
    again)."""
    if isinstance(spec, str) and cache:
        status = os.stat(spec)
        key = (spec, tuple(columns), status.st_mtime_ns, status.st_size)
        if key not in _READ:
            _READ[key] = read(module, spec, columns)
            while sum(t.nbytes * 3 for t, _, _ in _READ.values()) > CACHE_BYTES and len(_READ) > 1:
                _READ.popitem(last=False)
        return _READ[key]
    if isinstance(spec, str):
        parquet = spec.lower().endswith(PARQUET)
        t, *signals = _parquet(spec, columns) if parquet else module.read_csv(spec, columns)
        if not several(module):
            return module._records(t, *signals)[0]
        inputs = len(module.INPUTS)
        u, y = module.np.column_stack(signals[:inputs]), module.np.column_stack(signals[inputs:])
    else:
        t, u, y = spec
    return (module._signal_records if several(module) else module._records)(t, u, y)[0]


def _parquet(path: str, columns):
    try:
        pandas = importlib.import_module("pandas")
    except ImportError:
        raise ValueError(
            f"{path}: reading Parquet needs pandas: pip install -e '.[parquet]' in mtt's clone"
        ) from None
    try:
        frame = pandas.read_parquet(path, columns=list(columns))
    except (OSError, ValueError, KeyError, ImportError) as error:
        raise ValueError(f"{path}: {error}") from None
    arrays = []
    for name in columns:
        values = pandas.to_numeric(frame[name], errors="coerce").to_numpy(dtype=float)
        bad = ~(values == values) | (abs(values) == float("inf"))
        if bad.any():
            row = int(bad.argmax())
            cell = frame[name].iloc[row]
            raise ValueError(f"{path}: row {row}: column {name!r} holds {cell!r}, not a number")
        arrays.append(values)
    return arrays


def message(error: BaseException) -> str:
    if isinstance(error, ValueError | OSError):
        if isinstance(error, OSError) and error.filename:
            return f"{error.filename}: {error.strerror}"
        return str(error)
    return f"{type(error).__name__}: {error}"  # not a data error: say what it was


def _each(module, chunk, columns, work):
    """[(position, value, error, seconds)] for each (position, name, spec) of the chunk:
    work(module, t, u, y) per record, a record's failure its error message."""
    out = []
    for position, _, spec in chunk:
        start = time.process_time()
        try:
            value, error = work(module, *read(module, spec, columns)), None
        except Exception as caught:  # one record's failure is its own, the others go on
            value, error = None, message(caught)
        out.append((position, value, error, time.process_time() - start))
    return out


def _fitted(module, t, u, y, options):
    result = (module.fit_signals if several(module) else module.fit)(t, u, y, **options)
    return module.replace(result, fitted=(), residuals=())  # the sums travel, not the signals


def _estimated(module, t, u, y, options, trajectories):
    result = module.estimate(t, u, y, **options)
    if trajectories:
        return result
    last = slice(-1, None)  # the estimate at the record's end, its cost around it included
    return module.replace(result, t=result.t[last], khat=result.khat[last],
                          global_k=result.global_k[last], _shape=result._shape[:, last],
                          _log_J2=result._log_J2[last])  # fmt: skip


def run(name: str, source: str, action: str, chunk, columns, options):
    """One chunk of records, per record: action "fit" or "estimate" (options: theirs, and
    for estimate "trajectories"); results as in `_each`."""
    module = module_for(name, source)
    options = dict(options)
    with warnings.catch_warnings(), one_thread(), _quiet(module):
        warnings.simplefilter("ignore")  # the results list their warnings
        if action == "fit":
            return _each(module, chunk, columns, lambda m, *r: _fitted(m, *r, options))
        trajectories = options.pop("trajectories", False)
        return _each(module, chunk, columns, lambda m, *r: _estimated(m, *r, options, trajectories))


def _quiet(module):
    return module.np.errstate(all="ignore")


class Loaded:
    """A chunk's records read and checked for a pooled fit: their arrays stay where they were
    read (a dask worker keeps this object), only shapes and errors are reported."""

    def __init__(self, module, chunk, columns, offset, initial_state, cache: bool = False):
        self.records, self.positions, self.shapes, self.errors = [], [], [], []
        for position, label, spec in chunk:
            try:
                record = read(module, spec, columns, cache=cache)
                shape = module.replace(module.Shape.of(record[0], record[1]), label=label)
                module._check_sizes([shape], offset, initial_state)
            except Exception as caught:
                self.errors.append((position, message(caught)))
                continue
            self.records.append(record)
            self.positions.append(position)
            self.shapes.append(shape)


def load(name: str, source: str, chunk, columns, offset: bool, initial_state: bool) -> Loaded:
    module = module_for(name, source)
    with warnings.catch_warnings(), one_thread(), _quiet(module):
        warnings.simplefilter("ignore")
        return Loaded(module, chunk, columns, offset, initial_state)


def pooled(name: str, source: str, held, columns, method: str, args):
    """One step of a pooled fit over a chunk: `held` is its `Loaded` records (a dask worker
    keeps them) or the list of its record specs, read here (a concurrent.futures worker
    keeps nothing between tasks). method "shapes" (args: offset, initial_state): the good
    records' positions and shapes, and the others' errors; "moments", "validate",
    "residual_sum", "prediction", "chord" or "noise_sums": module.Records' answer over the
    chunk."""
    module = module_for(name, source)
    with warnings.catch_warnings(), one_thread(), _quiet(module):
        warnings.simplefilter("ignore")
        if method == "shapes":
            loaded = (
                Loaded(module, held, columns, *args, cache=True) if isinstance(held, list) else held
            )
            return loaded.positions, loaded.shapes, loaded.errors
        if isinstance(held, list):
            records = module.Records(
                [read(module, spec, columns, cache=True) for _, _, spec in held]
            )
        else:
            records = module.Records(held.records)
        return getattr(records, method)(*args)
