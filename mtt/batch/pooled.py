"""A fit pooled over records that workers hold: the generated module's `fit_records` runs
in this process over `Pooled`, its Records protocol, whose every answer (moments,
validation sums) is summed over chunks of records that the workers read once and keep. Each
step of the fit is one round trip of small matrices; the steps themselves are the module's.
"""

from __future__ import annotations

import inspect
from typing import TYPE_CHECKING

from mtt.batch import run, worker
from mtt.language.diagnostics import MttError

if TYPE_CHECKING:
    from mtt.batch.api import Estimator, Progress


class _OptionsChecked(Exception):
    pass


class _NoRecords:
    def shapes(self):
        raise _OptionsChecked


def check_options(module, options: dict) -> None:
    """The module's own checks of fit's options, once, before any record is sent: fit_records
    checks them before it asks the records anything (a nonlinear model's simulator has
    none: its fit's signature checks their names, each record's fit their values; several
    signals: `fit_signals`' own options, bound to its signature)."""
    if worker.several(module):
        _check_signal_options(module, options)
        return
    try:
        if not hasattr(module, "fit_records"):
            signature = inspect.signature(module.fit)
            signature.bind(None, None, None, **options)
            module._known_values({name: value for name, value in options.items()
                                  if name not in signature.parameters})  # fmt: skip
            return
        module.fit_records(_NoRecords(), **options)
    except _OptionsChecked:
        return
    except (TypeError, ValueError) as error:
        raise MttError(str(error), kind="bad_argument") from None


def _check_signal_options(module, options: dict) -> None:
    signature = inspect.signature(module.fit_signals)
    named = {name for name, p in signature.parameters.items() if p.kind is p.KEYWORD_ONLY}
    if "method" in options and options["method"] != "pem":
        raise MttError(
            f"method={options['method']!r}: several inputs or outputs are fitted by the exact "
            "prediction error only (method='pem')", kind="bad_argument",
        )  # fmt: skip
    options = {name: value for name, value in options.items() if name != "method"}
    try:
        signature.bind(None, None, None, **options)
        module._known_values({n: v for n, v in options.items() if n not in named})
    except (TypeError, ValueError) as error:
        raise MttError(f"fit_signals: {error}", kind="bad_argument") from None


def signals(found: Estimator, specs: list, columns, options: dict):
    """A pooled fit of several inputs and outputs, here: every record read (a record that
    cannot be read is an error of its own, as in `Pooled`), then one `fit_signals` over
    them all; (the fit or None, position -> error)."""
    module, records, errors = found.module, [], {}
    for position, (_, spec) in enumerate(specs):
        try:
            records.append(worker.read(module, spec, tuple(columns)))
        except (OSError, ValueError) as error:
            errors[position] = worker.message(error)
    options = {name: value for name, value in options.items() if name != "method"}
    if not records:
        return None, errors
    arrays = [list(part) for part in zip(*records, strict=True)]
    if len(records) == 1:
        arrays = [part[0] for part in arrays]
    with worker.one_thread():
        return module.fit_signals(*arrays, **options), errors


def _summed(method: str, parts: bool = False):
    """A Records method of `Pooled`: the chunks' answers summed (parts: lists, joined)."""
    return lambda self, *args: sum(self._ask(method, args), [] if parts else 0)


class Pooled:
    """The module's Records protocol over chunks of records that workers hold: each answer
    is the sum of the chunks' answers in chunk order (the same chunks give the same sums
    wherever they run). Made, it has read the records once: `errors` (position -> message)
    are those that could not be read or are too short, left out of every later step."""

    def __init__(self, found: Estimator, pool: run.Runner, chunks: list[run.Chunk], columns,
                 progress: Progress | None, offset: bool, initial_state: bool):  # fmt: skip
        self.found, self.pool, self.columns, self.progress = found, pool, tuple(columns), progress
        self.source = pool.share(found.source) if isinstance(pool, run.Dask) else found.source
        self.chunks = chunks
        self.held = {  # each chunk's records read where they stay (None: read at each step)
            chunk.number: pool.hold(worker.load, (found.name, self.source, chunk.items,
                                                  self.columns, offset, initial_state))
            for chunk in self.chunks
        }  # fmt: skip
        self.rounds = 0
        self.errors: dict[int, str] = {}
        self._shapes: list = []
        for _, shapes, errors in self._ask("shapes", (offset, initial_state)):
            self._shapes += shapes
            self.errors.update(errors)
        self.chunks = [
            run.Chunk(chunk.number, [item for item in chunk.items if item[0] not in self.errors])
            for chunk in self.chunks
        ]
        self.chunks = [chunk for chunk in self.chunks if chunk.items]

    def _ask(self, method: str, args: tuple) -> list:
        def call(chunk: run.Chunk):
            held = None if chunk.suspect else self.held.get(chunk.number)
            held = list(chunk.items) if held is None else held
            return worker.pooled, (self.found.name, self.source, held, self.columns, method, args)

        answers: dict[int, list] = {}
        for chunk, answer in self.pool.results(
            [run.Chunk(c.number, c.items) for c in self.chunks], call
        ):
            if isinstance(answer, run.Died):
                raise MttError(f"{chunk.items[0][1]}: {answer}", kind="worker_died")
            answers.setdefault(chunk.number, []).append(answer)
        self.rounds += 1
        if self.progress is not None:
            self.progress(self.rounds, None)
        return [answer for number in sorted(answers) for answer in answers[number]]

    def shapes(self) -> list:
        return self._shapes

    moments, residual_sum, noise_sums = (_summed(name) for name in ("moments", "residual_sum",
                                                                     "noise_sums"))  # fmt: skip
    validate, prediction, chord = (_summed(name, parts=True) for name in ("validate", "prediction",
                                                                          "chord"))  # fmt: skip


def refuse_estimate(module) -> None:
    """estimate_many's refusal of a module of several inputs or outputs."""
    if worker.several(module):
        raise MttError(
            f"the recursive estimate follows one input and one output; {module.MODEL} has "
            f"{', '.join(module.INPUTS)} -> {', '.join(module.OUTPUTS)}: fit each record of "
            "every signal with fit_many (fit_signals), or load the model with one input and "
            "one output", kind="bad_argument",
        )  # fmt: skip
