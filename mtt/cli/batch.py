"""`mtt fit --data 'logs/*.csv' --jobs N`: many records, through mtt.batch.

Which fit: each --data is a file or a glob pattern (expanded here, each pattern's matches
sorted). Files named one by one are experiments of one pooled fit (their moments add), as
`mtt fit` has always done; a pattern stands for a set of logs, each fitted on its own.
--per-record and --pooled say it explicitly. --jobs N runs N worker processes and
--scheduler ADDRESS a running dask.distributed cluster, in either mode; a pooled fit in
this process is the plain `mtt fit` (fitting.py).
"""

from __future__ import annotations

import glob
import json
import sys

from mtt.cli.running import EXIT_OK, EXIT_STOPPED, UsageError, say, warn

SHOWN_WARNINGS = 20  # per-record warnings printed on stderr before a count of the rest
CONNECT_TIMEOUT = 10.0  # seconds to reach a --scheduler


def mode(args) -> str | None:
    """ "each" (per record), "pooled" (pooled by workers), or None (pooled here: fitting.py).
    Expands the patterns of --data in place."""
    from mtt import files
    from mtt.batch.api import expand
    from mtt.language.diagnostics import MttError

    data = getattr(args, "data", None) or []
    chosen = args.per_record or args.pooled or args.jobs is not None or args.scheduler
    if not data:
        if chosen:
            raise UsageError("--per-record, --pooled, --jobs and --scheduler apply to --data")
        return None
    if args.jobs is not None and args.jobs < 1:
        raise UsageError(f"--jobs must be at least 1, not {args.jobs}")
    patterns = any(glob.has_magic(text) for text in data)
    try:
        args.data = [path for text in data for path in expand(text)]
    except MttError as error:
        raise UsageError(str(error)) from None
    for path in args.data:  # before any work: each a regular file, none of them an output
        files.check_input(path, "data")
    if args.per_record or (patterns and not args.pooled):
        return "each"
    return "pooled" if (args.jobs or 1) > 1 or args.scheduler else None


def cmd_fit_many(args, kind: str) -> int:
    from mtt import files
    from mtt.batch import api
    from mtt.cli.experiment import checked_module
    from mtt.cli.fit_options import options, signal_options
    from mtt.cli.options import choice_from_args
    from mtt.data import records
    from mtt.data.signals import signal_columns
    from mtt.derivation import pipeline
    from mtt.estimator import codegen
    from mtt.language.diagnostics import MttError
    from mtt.present import batch as table

    if args.plot or (args.csv and kind == "pooled"):
        flag = "--plot" if args.plot else "--csv"
        raise UsageError(
            f"{flag} draws the fitted outputs, which stay with the workers: "
            + (
                "fit the records in this process (no --jobs/--scheduler)"
                if kind == "pooled"
                else "fit one record, or pass --pooled without --jobs"
            )  # fmt: skip
        )
    found = api.from_source(codegen.render(pipeline.theta_for(args.file, choice_from_args(args))))
    several = hasattr(found.module, "fit_signals")  # several inputs or outputs: fit_signals
    module = found.module if several else checked_module(found.module)
    chosen = signal_options(module, args) if several else options(module, args)
    names = signal_columns(module, args.columns) if several else records.columns(args.columns)
    client = _client(args.scheduler) if args.scheduler else None
    try:
        with _bar(len(args.data), kind) as bar:
            batch = api.fit_many(
                found, args.data, executor=client, jobs=None if client else (args.jobs or 1),
                pooled=kind == "pooled", columns=names,
                progress=lambda done, total: bar.update(done - bar.n),
                validate=args.validate or (), **chosen,
            )  # fmt: skip
    except MttError as error:
        raise UsageError(str(error)) from None
    finally:
        if client is not None:
            client.close()
    errors = [table.named(outcome) for outcome in batch.errors]
    if kind == "pooled":
        return _pooled(module, args, batch, errors)
    for error in errors:  # one line each, naming the record
        say(f"mtt fit: error: {error}", stderr=True)
    _warnings(batch)
    if args.csv:
        files.write_atomic(args.csv, table.table_csv(module, batch))
    if args.json:
        say(json.dumps(table.record(module, batch)))
    else:
        say(table.table(module, batch, _where(args), args.method))
    return EXIT_OK if batch.ok else EXIT_STOPPED


def _client(address: str):
    try:
        from distributed import Client
    except ImportError:
        raise UsageError(
            "--scheduler needs dask.distributed: pip install -e '.[dask]' in mtt's clone"
        ) from None
    try:
        return Client(address, timeout=CONNECT_TIMEOUT)
    except (OSError, TimeoutError, ValueError) as error:
        raise UsageError(f"--scheduler {address}: cannot connect ({error})") from None


def _bar(total: int, kind: str):
    from tqdm import tqdm

    tqdm.monitor_interval = 0  # no monitor thread: the process pool forks a single thread

    if kind == "pooled":  # the fit's steps, each a round trip over all the records
        return tqdm(desc="fitting (steps over all records)", unit="step", leave=False,
                    disable=not sys.stderr.isatty(), delay=1.0)  # fmt: skip
    return tqdm(total=total, desc="fitting", unit="record", leave=False,
                disable=not sys.stderr.isatty(), delay=1.0)  # fmt: skip


def _warnings(batch) -> None:
    from mtt.present.batch import warning_lines

    lines = warning_lines(batch)
    warn("fit", lines[:SHOWN_WARNINGS])
    if len(lines) > SHOWN_WARNINGS:
        warn("fit", [f"{len(lines) - SHOWN_WARNINGS} more warnings (--json or --csv lists them)"])


def _where(args) -> str:
    if args.scheduler:
        return f"on {args.scheduler}"
    return f"{args.jobs} processes" if (args.jobs or 1) > 1 else "in this process"


def _pooled(module, args, batch, errors: list[str]) -> int:
    from mtt.present import batch as table

    if errors:  # as in this process: a bad record is the error (named, also in --json)
        for error in errors[1:]:
            say(f"mtt fit: error: {error}", stderr=True)
        more = f" ({len(errors)} of {len(batch)} records could not be read)"
        first = next(outcome for outcome in batch if outcome.error is not None)
        raise UsageError(errors[0] + (more if len(errors) > 1 else ""), *table.place(first))
    if batch.pooled is None:
        raise UsageError("no records to fit")
    result = batch.pooled
    warn("fit", result.warnings)
    if args.validate and not batch.validation[0].comparison:
        warn("fit", [f"no validation: {result.message}"])
    if args.json:
        say(json.dumps(table.record(module, batch)))
    else:
        say(table.pooled_text(module, batch))
    return EXIT_OK if result.ok else EXIT_STOPPED
