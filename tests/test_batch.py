"""mtt.batch on this machine: per-record fits and a pooled fit, in this process and in a
process pool; a corrupt record; a worker killed mid-run; a record that kills its worker.

The reference is the generated module's own `fit`, called here on each record (or on the
list of records, pooled): the batch layer must give the same numbers, bitwise per record.
"""

from __future__ import annotations

import csv
import os
import warnings
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pytest
from batch_records import CORRUPT, direct_fits, kill, logs, same_numbers, simulated

import mtt
from mtt.batch import fit_many, run
from mtt.batch.api import estimate_many

__all__ = ["logs"]  # the fixture


def paths_of(folder) -> list[str]:
    return sorted(str(path) for path in folder.glob("*.csv"))


def check_against_direct(batch, module, folder):
    paths = paths_of(folder)
    direct = direct_fits(module, paths, hold="zoh")
    assert [outcome.name for outcome in batch] == paths  # the sorted paths' order
    for outcome in batch:
        if outcome.name.endswith(CORRUPT):
            assert outcome.result is None
            assert outcome.error == f"{outcome.name}:18: column 'y' holds 'oops', not a number"
        else:
            assert outcome.error is None and same_numbers(outcome.result, direct[outcome.name])
            assert abs(outcome.result.k - 10.0) < 0.5 and outcome.seconds > 0


def test_records_in_this_process_and_in_a_pool_give_the_same_numbers(dc_drive, logs, tmp_path):
    pattern = str(logs / "run_*.csv")
    here = fit_many(dc_drive, pattern, jobs=1, hold="zoh")
    check_against_direct(here, dc_drive, logs)
    # printed and written as `mtt fit --data PATTERN` prints and writes it (mtt.present.batch)
    lines = str(here).splitlines()
    assert (
        lines[0] == "dc_drive: 12 records, one fit each (exact prediction error, in this process)"
    )
    assert lines[-1] == "  11 of 12 records fitted; 1 failed" and "failed" in lines[2 + 7]
    with open(here.to_csv(tmp_path / "records.csv"), newline="") as file:
        rows = list(csv.DictReader(file))
    assert [row["file"] for row in rows] == paths_of(logs)
    assert float(rows[0]["k"]) == here[0].result.k and rows[7]["error"] == here[7].error
    pooled_processes = fit_many(dc_drive, pattern, jobs=2, chunk_size=2, hold="zoh")
    check_against_direct(pooled_processes, dc_drive, logs)
    assert [o.error for o in here.errors] == [o.error for o in pooled_processes.errors]
    assert not here.ok and len(here.errors) == 1
    record = here[7].record()
    assert record == {"file": str(logs / CORRUPT), "k": None, "k_se": None,
                      "fit_percent": None, "warnings": [], "error": here[7].error}  # fmt: skip
    good = here[3].record()
    assert good["k"] == here[3].result.k and good["error"] is None
    assert set(good) == {"file", "k", "k_se", "fit_percent", "warnings", "error"}
    # the results are the module's own classes, without the per-sample signals
    assert isinstance(here[0].result, dc_drive.Fit) and here[0].result.fitted == ()


def test_a_spreadsheet_s_records_are_read_by_the_workers_too(dc_drive, logs, tmp_path):
    """The module's reader, which the workers call, reads ';' and tab as mtt.data does."""
    first = paths_of(logs)[0]
    text = Path(first).read_text()
    for name, delimiter in (("semicolons.csv", ";"), ("tabs.csv", "\t")):
        (tmp_path / name).write_text(text.replace(",", delimiter))
    batch = fit_many(dc_drive, [first, *paths_of(tmp_path)], jobs=2, hold="zoh")
    assert batch.ok and batch[1].result.k == batch[2].result.k == batch[0].result.k


def test_records_as_arrays_names_and_an_iterator(dc_drive):
    data = [simulated(dc_drive, seed, samples=401) for seed in range(4)]
    named = fit_many(dc_drive, [("first", data[0]), ("second", data[1])], jobs=1, hold="zoh")
    assert [o.name for o in named] == ["first", "second"]
    plain = fit_many(dc_drive, iter(data), jobs=2, hold="zoh")  # read as it goes
    assert [o.name for o in plain] == [f"record {i}" for i in range(4)]
    assert same_numbers(plain[0].result, named[0].result)
    mapping = fit_many(dc_drive, {"a": data[2], "b": (data[3][0][:3], *data[3][1:])}, jobs=1)
    assert (
        mapping[0].ok and mapping[1].error == "t, u, y must have the same length, not [3, 401, 401]"
    )


def test_pooled_fit_equals_fit_on_the_list(dc_drive, logs):
    paths = [path for path in paths_of(logs) if not path.endswith(CORRUPT)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        records = [dc_drive.read_csv(path) for path in paths]
        whole = dc_drive.fit(*[list(part) for part in zip(*records, strict=True)], hold="zoh")
    here = fit_many(dc_drive, paths_of(logs), jobs=1, pooled=True, chunk_size=3, hold="zoh")
    assert [o.name for o in here.errors] == [str(logs / CORRUPT)]  # left out, named
    assert not here.ok and here.pooled.ok
    for name in ("k", "k_se", "fit_percent", "residual_rms", "noise_std"):
        assert getattr(here.pooled, name) == pytest.approx(getattr(whole, name), rel=1e-9)
    assert here.pooled.offsets == pytest.approx(whole.offsets, rel=1e-9, abs=1e-12)
    assert here.pooled.iterations == whole.iterations and here.pooled.fitted == ()
    assert str(here).splitlines()[0] == "dc_drive: " + "; ".join(paths_of(logs))
    assert f"{here.pooled.k:.6g}" in str(here)
    processes = fit_many(dc_drive, paths_of(logs), jobs=2, pooled=True, chunk_size=3, hold="zoh")
    assert same_numbers(processes.pooled, here.pooled)  # the same chunks: the same sums


def test_a_killed_worker_process_is_replaced_and_every_record_ends_once(dc_drive, logs):
    executor = ProcessPoolExecutor(2)
    pids = [executor.submit(os.getpid).result() for _ in range(4)]
    killed = []

    def progress(done, total):
        if not killed:
            killed.append(pids[0])
            kill(pids[0])

    try:
        batch = fit_many(dc_drive, paths_of(logs), executor=executor, chunk_size=1,
                         progress=progress, hold="zoh")  # fmt: skip
    finally:
        executor.shutdown(cancel_futures=True)
    assert killed
    check_against_direct(batch, dc_drive, logs)  # all COUNT, each once, right


def dies_on_poison(items):
    """A task that kills its worker process when its chunk holds the record "poison"."""
    if any(name == "poison" for _, name, _ in items):
        os._exit(3)
    return [name for _, name, _ in items]


def test_a_record_that_kills_its_worker_is_its_own_error():
    names = [f"r{i}" for i in range(9)]
    names[4] = "poison"
    chunks = [
        run.Chunk(i, [(j, names[j], None) for j in range(3 * i, 3 * i + 3)]) for i in range(3)
    ]
    pool = run.Futures(run.process_pool(2), own=True)
    try:
        results = list(pool.results(chunks, lambda chunk: (dies_on_poison, (chunk.items,))))
    finally:
        pool.close()
    ended = {}
    for chunk, result in results:
        if isinstance(result, run.Died):
            ended.setdefault(chunk.items[0][1], []).append("died")
        else:
            for name in result:
                ended.setdefault(name, []).append("ok")
    assert ended == {name: ["died" if name == "poison" else "ok"] for name in names}


def test_estimate_many_keeps_each_estimate_at_its_end(dc_drive):
    data = [simulated(dc_drive, seed, samples=401) for seed in range(3)]
    batch = estimate_many(dc_drive, data, jobs=1, k0=5.0, hold="zoh")
    full = estimate_many(dc_drive, data, jobs=1, k0=5.0, hold="zoh", trajectories=True)
    for outcome, whole, record in zip(batch, full, data, strict=True):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            direct = dc_drive.estimate(*record, k0=5.0, hold="zoh")
        assert outcome.result.k == whole.result.k == direct.k
        assert outcome.result.t.size == 1 and whole.result.t.size == record[0].size
        np.testing.assert_array_equal(outcome.result.minima(), direct.minima())


def test_parquet_records(dc_drive, logs, tmp_path):
    pandas = pytest.importorskip("pandas", reason="Parquet records need pandas (mtt[parquet])")
    path = tmp_path / "run_00.parquet"
    t, u, y = dc_drive.read_csv(logs / "run_00.csv")
    pandas.DataFrame({"time": t, "volts": u, "speed": y}).to_parquet(path)
    batch = fit_many(dc_drive, [path, logs / "run_00.csv"], jobs=1, hold="zoh",
                     columns=("time", "volts", "speed"))  # fmt: skip
    assert batch[1].error == f"{logs / 'run_00.csv'}:1: no column 'time' (the header names t, u, y)"
    direct = direct_fits(dc_drive, [logs / "run_00.csv"], hold="zoh")
    assert same_numbers(batch[0].result, direct[str(logs / "run_00.csv")])


def test_models_and_bad_arguments(dc_drive, logs):
    paths = paths_of(logs)[:2]
    from_file = fit_many(mtt.example("dc_drive"), paths, jobs=1, hold="zoh")
    from_module = fit_many(dc_drive, paths, jobs=1, hold="zoh")
    assert same_numbers(from_file[0].result, from_module[0].result)
    with pytest.raises(mtt.MttError, match="method must be one of"):
        fit_many(dc_drive, paths, jobs=1, method="fastest")
    with pytest.raises(mtt.MttError, match="no file matches"):
        fit_many(dc_drive, str(logs / "nothing_*.csv"))
    with pytest.raises(mtt.MttError, match="jobs must be a whole number"):
        fit_many(dc_drive, paths, jobs=0)
    with pytest.raises(mtt.MttError, match="executor must be"):
        fit_many(dc_drive, paths, executor=object())
    assert len(fit_many(dc_drive, [logs / "missing.csv"], jobs=1).errors) == 1
    # estimate_many: a missing k0 or an unknown option is one error, not one per record
    with pytest.raises(mtt.MttError, match="estimate: missing a required argument: 'k0'"):
        estimate_many(dc_drive, paths, jobs=1)
    with pytest.raises(mtt.MttError, match="estimate: unexpected parameter 'bta'"):
        estimate_many(dc_drive, paths, jobs=1, k0=5.0, bta=0.1)
    with pytest.raises(mtt.MttError, match="the recursive estimate follows one record"):
        estimate_many(dc_drive, paths, jobs=1, k0=5.0, pooled=True)


def test_a_module_imported_again_and_models_of_one_name(dc_drive):
    """A module imported again under its name (a notebook cell run twice; the test modules'
    fixtures), or a model of the same name loaded with other values, replaces the module its
    first batch registered: the next batches in a process pool still pickle their results
    (they raised PicklingError) and give the current module's classes."""
    from estimators import load

    data = [simulated(dc_drive, seed, samples=401) for seed in range(2)]
    first = fit_many(dc_drive, data, jobs=2, chunk_size=1, hold="zoh")
    again = load("dc_drive")  # generated_dc_drive is now another module object
    second = fit_many(again, data, jobs=2, chunk_size=1, hold="zoh")
    assert all(type(o.result) is again.Fit for o in second)
    assert [o.result.k for o in second] == [o.result.k for o in first]
    a = mtt.load("models/dc_drive.bg")
    b = mtt.load("models/dc_drive.bg", set={"ra": 2})
    before = fit_many(a, data, jobs=2, chunk_size=1, hold="zoh")
    assert [o.result.k for o in before] == [o.result.k for o in first]
    other = fit_many(b, data, jobs=2, chunk_size=1, hold="zoh")  # the name's module replaced
    assert abs(other[0].result.k - first[0].result.k) > 1
    # (ra = 2 for records made with ra = 1: a wrong model, whose fits are not ok, and say why)
    assert all("contradicted: the" in o.error for o in other)
    after = fit_many(a, data, jobs=2, chunk_size=1, hold="zoh")
    assert all(type(o.result) is a.estimator().Fit for o in after)
    assert [o.result.k for o in after] == [o.result.k for o in first]
