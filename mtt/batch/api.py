"""fit_many and estimate_many: one model, many records, on this machine's cores or a cluster.

The records are cut into chunks; each chunk goes to a worker with the generated module's
source (see worker.py). Per record, the worker runs the module's `fit` (or `estimate`) and
returns its result without the per-sample signals. Pooled, the module's `fit_records`
runs here over records that the workers hold (pooled.py).
"""

from __future__ import annotations

import glob
import inspect
import sys
from collections.abc import Callable, Iterator, Mapping
from concurrent.futures import Executor
from dataclasses import dataclass, field, replace
from pathlib import Path
from types import ModuleType

from mtt import files
from mtt.batch import pooled as pooled_fits
from mtt.batch import run, validation, worker
from mtt.batch.validation import Validation, plain
from mtt.language.diagnostics import MttError


@dataclass(frozen=True)
class Outcome:
    """One record's result: `result` the module's Fit (or Estimate) without its per-sample
    signals, None where the record failed; `error` why there is no estimate (the record could
    not be read, its fit raised, or the fit found no estimate: then `result` says more);
    `seconds` the worker's CPU time on it (reading included). Pooled, `result` is None."""

    name: str
    result: object | None
    error: str | None
    seconds: float = 0.0
    validation: tuple[Validation, ...] = ()

    @property
    def ok(self) -> bool:
        return self.error is None

    def record(self) -> dict:
        """The JSON record of `mtt fit --json` for many records (k a list once it is a vector)."""
        result = None if self.error is not None else self.result
        return {
            "file": self.name,
            "k": plain(getattr(result, "k", None)),
            "k_se": plain(getattr(result, "k_se", None)),
            "fit_percent": plain(getattr(result, "fit_percent", None)),
            "warnings": list(getattr(self.result, "warnings", ()) or ()),
            "error": self.error,
            **({"validation": [v.record() for v in self.validation]} if self.validation else {}),
        }


@dataclass(frozen=True)
class Batch:
    """The outcomes of a batch, one per record in the records' order; `pooled` the Fit over
    all the records that could be read (pooled=True), else None. Iterating a Batch gives the
    outcomes."""

    outcomes: tuple[Outcome, ...]
    pooled: object | None = None
    validation: tuple[Validation, ...] = ()  # pooled: the pooled fit on the held-out records
    module: ModuleType | None = field(default=None, repr=False, compare=False)  # fit_many's

    def table(self) -> str:
        """fit_many's batch as `mtt fit` prints it: a row per record (estimates, standard
        errors, fit %, warnings), or the pooled fit; also str(batch)."""
        from mtt.present import batch as text

        if self.module is None:
            raise MttError("only fit_many's batches print as a table", kind="bad_argument")
        if self.pooled is not None:
            return text.pooled_text(self.module, self)
        return text.table(self.module, self)

    def __str__(self) -> str:
        return self.table() if self.module is not None else repr(self)

    def to_csv(self, path: str | Path) -> Path:
        """Write fit_many's per-record table as `mtt fit --csv` does (one row per record:
        k, k_se, ci_low, ci_high of each unknown, fit %, warnings, error); the path. A
        record's file is never written over (`mtt.files.FileClash`)."""
        from mtt.present.batch import table_csv

        if self.module is None or self.pooled is not None:
            raise MttError("to_csv writes fit_many's per-record fits", kind="bad_argument")
        read = [o.name for o in self.outcomes if Path(o.name).is_file()]  # never over a record
        files.write_atomic(path, table_csv(self.module, self), inputs=read)
        return Path(path)

    def __iter__(self) -> Iterator[Outcome]:
        return iter(self.outcomes)

    def __len__(self) -> int:
        return len(self.outcomes)

    def __getitem__(self, index: int) -> Outcome:
        return self.outcomes[index]

    @property
    def errors(self) -> tuple[Outcome, ...]:
        return tuple(outcome for outcome in self.outcomes if not outcome.ok)

    @property
    def ok(self) -> bool:
        return not self.errors and (self.pooled is None or bool(self.pooled.ok))


# the model: the module the results belong to, and its source for the workers -------------


@dataclass(frozen=True)
class Estimator:
    module: ModuleType
    source: str
    name: str  # the module's name in every process (the source's hash)


def from_source(source: str) -> Estimator:
    """The generated module of this source text, imported here as the workers import it."""
    name = worker.module_name(source)
    return Estimator(worker.module_for(name, source), source, name)


def estimator(model) -> Estimator:
    """A Model (mtt.load), a model file (.bg), a generated module's file (.py), or a
    generated module imported from its file."""
    from mtt.api.loading import load
    from mtt.api.model import Model
    from mtt.estimator import codegen, nonlinear_codegen

    if isinstance(model, Estimator):
        return model
    if isinstance(model, str | Path) and str(model).endswith(".py"):
        return from_source(files.source_text(model, "a generated module", files.MAX_MODULE_BYTES))
    if isinstance(model, str | Path):
        model = load(model)
    if isinstance(model, Model) and model.nonlinear and model.choice.at is None:
        system, values = model._system  # a nonlinear model: its simulator's prediction error
        source = nonlinear_codegen.render(system, values=values, description=model.description)
        module = model.simulator()
    elif isinstance(model, Model):
        source = codegen.render(model._checked_theta())
        module = model.estimator()
    elif isinstance(model, ModuleType) and hasattr(model, "fit"):
        path = getattr(model, "__file__", None)
        if not path or not Path(path).is_file():
            raise MttError(
                f"the module {model.__name__} has no source file to send to workers: pass the "
                "Model (mtt.load) or the model file instead",
                kind="bad_argument",
            )
        source, module = Path(path).read_text(encoding="utf-8"), model
    else:
        raise MttError(
            "model must be a Model (mtt.load), a model file, or a generated estimator module "
            f"(or its .py file), not {type(model).__name__}",
            kind="bad_argument",
        )
    name = worker.module_name(source)
    sys.modules[name] = module  # results pickled by workers come back as its classes
    return Estimator(module, source, name)


# the records ----------------------------------------------------------------------------


def records_of(records) -> Iterator[tuple[str, object]]:
    """(name, spec) per record: a path (a str or Path; a str with a pattern such as
    "logs/*.csv" is expanded, sorted), a (t, u, y) triple (named "record i"), a pair
    (name, (t, u, y)), or a mapping name -> (t, u, y)."""
    if isinstance(records, str | Path):
        records = [records]
    elif isinstance(records, Mapping):
        records = list(records.items())
    for i, record in enumerate(records):
        if isinstance(record, Path):
            yield str(record), str(record)
        elif isinstance(record, str):
            yield from ((path, path) for path in expand(record))
        elif isinstance(record, tuple | list) and len(record) == 2 and isinstance(record[0], str):
            yield record[0], tuple(record[1])
        elif isinstance(record, tuple | list) and len(record) == 3:
            yield f"record {i}", tuple(record)
        else:
            raise MttError(
                f"record {i}: expected a path, (t, u, y) or (name, (t, u, y)), not "
                f"{type(record).__name__}",
                kind="bad_argument",
            )


def expand(pattern: str) -> list[str]:
    """A path, or the sorted paths a glob pattern matches (none: an error; see files.glob)."""
    if not glob.has_magic(pattern):
        return [pattern]
    paths = files.glob(pattern)
    if not paths:
        raise MttError(f"no file matches {pattern!r}", kind="io", file=pattern)
    return paths


# the executors ----------------------------------------------------------------------------


def runner(executor, jobs: int | None) -> run.Runner:
    """Where the chunks run: executor (a concurrent.futures Executor or a dask Client), or
    jobs processes (None: one per core; 1: this process)."""
    if executor is not None:
        if jobs is not None:
            raise MttError("give an executor or jobs, not both", kind="bad_argument")
        if run.is_dask_client(executor):
            return run.Dask(executor)
        if isinstance(executor, Executor):
            return run.Futures(executor, own=False)
        raise MttError(
            "executor must be a concurrent.futures.Executor or a dask.distributed.Client, not "
            f"{type(executor).__name__}",
            kind="bad_argument",
        )
    jobs = run.default_jobs() if jobs is None else jobs
    if not (isinstance(jobs, int) and jobs >= 1):
        raise MttError(f"jobs must be a whole number >= 1, not {jobs!r}", kind="bad_value")
    return run.InProcess() if jobs == 1 else run.Futures(run.process_pool(jobs), own=True)


Progress = Callable[[int, int | None], None]  # (records done, records in all or None)


def _each(found: Estimator, records, action: str, executor, jobs, columns, chunk_size,
          progress, options) -> Batch:  # fmt: skip
    specs = records_of(records)
    specs = list(specs) if isinstance(records, list | tuple | Mapping | str | Path) else specs
    total = len(specs) if isinstance(specs, list) else None
    pool = runner(executor, jobs)
    source = pool.share(found.source) if isinstance(pool, run.Dask) else found.source
    outcomes: dict[int, Outcome] = {}

    def call(chunk: run.Chunk):
        return worker.run, (found.name, source, action, chunk.items, tuple(columns), options)

    try:
        for chunk, result in pool.results(run.chunks(specs, chunk_size), call):
            names = {position: name for position, name, _ in chunk.items}
            if isinstance(result, run.Died):
                ((position, name, _),) = chunk.items
                outcomes[position] = Outcome(name, None, str(result))
            else:
                for position, value, error, seconds in result:
                    if error is None and not value.ok:
                        error = value.message
                    outcomes[position] = Outcome(names[position], value, error, seconds)
            if progress is not None:
                progress(len(outcomes), total)
    finally:
        pool.close()
    return Batch(tuple(outcomes[position] for position in sorted(outcomes)))


def fit_many(model, records, *, executor=None, jobs: int | None = None, pooled: bool = False,
             columns=None, chunk_size: int | None = None,
             progress: Progress | None = None, validate=(), **fit_options) -> Batch:  # fmt: skip
    """The generated module's `fit` on each record (or, pooled=True, one fit over them all).

    model: a Model (mtt.load), a model file, or a generated module (or its .py file).
    records: paths (CSV with the named `columns`, or Parquet with pandas installed; a str
    pattern such as "logs/*.csv" is expanded, sorted), (t, u, y) arrays, (name, (t, u, y))
    pairs, or a mapping name -> (t, u, y); an iterator of them is read as the work goes.
    columns: the time's, input's and output's (default t, u, y). A model of several inputs
    or outputs: each record fitted by its module's `fit_signals` (see docs/batch.md).
    executor: a concurrent.futures.Executor or a dask.distributed.Client; else `jobs`
    processes (default: one per core; jobs=1 runs here). fit_options: the module's `fit`
    options (method, C, k0, bounds, offset, initial_state, hold, beta, known parameters).

    The outcomes keep the records' names and order; a record that fails is an error of its
    own and the others go on. Each record's numbers are the same wherever it runs (BLAS on
    one thread everywhere). pooled=True: the records' moments add into one estimate, each
    step computed by the workers where the records are (a record that cannot be read or is
    too short is an error and left out); the same as `fit` given them all as a list.

    validate: held-out records (as `records`, read here): each fit (pooled: the pooled fit,
    in `Batch.validation`) is compared with each of them by the module's `Fit.compare` (its
    fit % and residual RMS with the held-out record's own initial state and offset
    estimated), in each Outcome's `validation`.
    """
    found = estimator(model)
    pooled_fits.check_options(found.module, fit_options)
    columns = worker.default_columns(found.module) if columns is None else tuple(columns)
    held_out = validation.held_out(found.module, records_of(validate or ()), columns)
    if pooled and worker.several(found.module):
        specs = list(records_of(records))
        result, errors = pooled_fits.signals(found, specs, columns, fit_options)
        outcomes = tuple(Outcome(name, None, errors.get(i)) for i, (name, _) in enumerate(specs))
        return Batch(outcomes, result, validation.compared(result, held_out), found.module)
    if pooled and not hasattr(found.module, "fit_records"):  # a nonlinear model's simulator
        batch = _joint(found, records, columns, fit_options)
        return replace(batch, validation=validation.compared(batch.pooled, held_out),
                       module=found.module)  # fmt: skip
    if pooled:
        batch = _pooled(found, records, executor, jobs, columns, chunk_size, progress,
                        fit_options)  # fmt: skip
        return replace(batch, validation=validation.compared(batch.pooled, held_out),
                       module=found.module)  # fmt: skip
    batch = _each(found, records, "fit", executor, jobs, columns, chunk_size, progress,
                  fit_options)  # fmt: skip
    batch = replace(batch, module=found.module)
    if not held_out:
        return batch
    return replace(batch, outcomes=tuple(
        replace(o, validation=validation.compared(o.result, held_out)) for o in batch.outcomes
    ))  # fmt: skip


def estimate_many(model, records, *, executor=None, jobs: int | None = None,
                  pooled: bool = False, columns=("t", "u", "y"), chunk_size: int | None = None,
                  progress: Progress | None = None, trajectories: bool = False,
                  **estimate_options) -> Batch:  # fmt: skip
    """The generated module's recursive `estimate` (the paper's tracker) on each record, as
    `fit_many` runs `fit` (estimate_options: k0 and the others of `estimate`, their names
    checked once here, their values by each record's estimate). Each Estimate is kept at
    its last sample (k, global_k, minima and the cost there), unless trajectories=True
    brings back k^(t) at every sample. pooled=True is an error: the recursive estimate
    follows one record in time; fit_many(..., pooled=True) pools records."""
    found = estimator(model)
    if pooled:
        raise MttError("the recursive estimate follows one record in time: pool records with "
                       "fit_many(..., pooled=True)", kind="bad_argument")  # fmt: skip
    pooled_fits.refuse_estimate(found.module)  # several inputs or outputs
    signature = inspect.signature(found.module.estimate)
    named = {name for name, p in signature.parameters.items() if p.kind is p.KEYWORD_ONLY}
    try:  # a missing k0 or a misspelt option: one error, not one per record
        signature.bind(None, None, None, **estimate_options)
        found.module._known_values({name: value for name, value in estimate_options.items()
                                    if name not in named})  # fmt: skip
    except (TypeError, ValueError) as error:
        raise MttError(f"estimate: {error}", kind="bad_argument") from None
    return _each(found, records, "estimate", executor, jobs, columns, chunk_size, progress,
                 {**estimate_options, "trajectories": bool(trajectories)})  # fmt: skip


# pooled -------------------------------------------------------------------------------------


def _pooled(found: Estimator, records, executor, jobs, columns, chunk_size, progress,
            options) -> Batch:  # fmt: skip
    specs = list(records_of(records))
    pool = runner(executor, jobs)
    try:
        nuisances = bool(options.get("offset", True)), bool(options.get("initial_state", True))
        chunks = list(run.chunks(specs, chunk_size))
        steps = pooled_fits.Pooled(found, pool, chunks, columns, progress, *nuisances)
        result = found.module.fit_records(steps, keep=False, **options) if steps.shapes() else None
    finally:
        pool.close()
    outcomes = tuple(
        Outcome(name, None, steps.errors.get(position)) for position, (name, _) in enumerate(specs)
    )
    return Batch(outcomes, result)


def _joint(found: Estimator, records, columns, options) -> Batch:
    """A nonlinear model's records pooled: read here and fitted jointly by its simulator's
    `fit` (the unknowns common, each record's initial state and offset its own), since its
    prediction errors do not sum from parts as the linear fit's moments do."""
    specs, read, errors = list(records_of(records)), [], {}
    for position, (_, spec) in enumerate(specs):
        try:
            read.append(worker.read(found.module, spec, tuple(columns)))
        except (OSError, ValueError) as error:
            errors[position] = worker.message(error)
    result = None
    if read:
        with worker.one_thread():
            result = found.module.fit(*map(list, zip(*read, strict=True)), **options)
    outcomes = tuple(
        Outcome(name, None, errors.get(position)) for position, (name, _) in enumerate(specs)
    )
    return Batch(outcomes, result)
