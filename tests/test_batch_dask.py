"""mtt.batch on a dask.distributed cluster: a LocalCluster of 2 worker processes, started
once for the module. Per-record and pooled fits give the numbers of this process; a worker
killed mid-run costs nothing but time; the workers import mtt's worker module alone.

`pip install -e '.[dask]'` in mtt's clone (the test extra has it); without dask they are skipped.
"""

from __future__ import annotations

import json
import sys
import warnings

import pytest
from batch_records import CORRUPT, kill, logs, same_numbers

from mtt.batch import fit_many

distributed = pytest.importorskip(
    "distributed", reason="dask.distributed is not installed: pip install -e '.[dask]'"
)

__all__ = ["logs"]  # the fixture


@pytest.fixture(scope="module")
def client():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # dask's notes on ports and dashboards
        cluster = distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
        )
    with cluster, distributed.Client(cluster) as client:
        yield client


def paths_of(folder) -> list[str]:
    return sorted(str(path) for path in folder.glob("*.csv"))


def test_per_record_on_the_cluster_equals_this_process(dc_drive, logs, client):
    here = fit_many(dc_drive, paths_of(logs), jobs=1, hold="zoh")
    there = fit_many(dc_drive, str(logs / "*.csv"), executor=client, chunk_size=2, hold="zoh")
    assert [o.name for o in there] == [o.name for o in here] == paths_of(logs)
    for a, b in zip(here, there, strict=True):
        assert a.error == b.error
        assert a.result is b.result is None or same_numbers(a.result, b.result)
    assert [o.name for o in there.errors] == [str(logs / CORRUPT)]
    # the workers ran the module from its source, and of mtt imported its worker module alone
    imported = client.run(lambda: sorted(name for name in sys.modules if name.startswith("mtt")))
    for names in imported.values():
        assert names == ["mtt", "mtt.batch", "mtt.batch.worker", "mtt.language",
                         "mtt.language.diagnostics", "mtt.version"]  # fmt: skip
    assert not any(client.run(lambda: "sympy" in sys.modules).values())


def test_pooled_on_the_cluster_equals_this_process(dc_drive, logs, client):
    here = fit_many(dc_drive, paths_of(logs), jobs=1, pooled=True, chunk_size=3, hold="zoh")
    there = fit_many(dc_drive, paths_of(logs), executor=client, pooled=True, chunk_size=3,
                     hold="zoh")  # fmt: skip
    assert same_numbers(there.pooled, here.pooled) and there.pooled.ok
    assert [o.name for o in there.errors] == [str(logs / CORRUPT)]


def test_a_killed_dask_worker_costs_only_time(dc_drive, logs, client):
    pids = client.run(lambda: __import__("os").getpid())
    killed = []

    def progress(done, total):
        if not killed:
            killed.append(next(iter(pids.values())))
            kill(killed[0])

    here = fit_many(dc_drive, paths_of(logs), jobs=1, hold="zoh")
    there = fit_many(dc_drive, paths_of(logs), executor=client, chunk_size=1, progress=progress,
                     hold="zoh")  # fmt: skip
    assert killed and len(there) == len(here)
    for a, b in zip(here, there, strict=True):
        assert a.name == b.name and a.error == b.error
        assert a.result is b.result is None or same_numbers(a.result, b.result)
    client.wait_for_workers(2, timeout=60)  # the nanny restarts it, for the next tests


def test_the_command_line_on_a_running_scheduler(capsys, logs, client, monkeypatch):
    from mtt.cli import batch
    from mtt.cli.main import main

    monkeypatch.setattr(batch, "CONNECT_TIMEOUT", 0.5)
    pattern = str(logs / "run_0[0-3].csv")
    address = client.scheduler.address
    statuses = [main(["fit", "models/dc_drive.bg", "--data", pattern, "--hold", "zoh", "--json",
                      *where]) for where in ([], ["--scheduler", address])]  # fmt: skip
    here, there = (json.loads(line) for line in capsys.readouterr().out.splitlines())
    assert statuses == [0, 0] and here == there and len(here["records"]) == 4
    assert (
        main(["fit", "models/dc_drive.bg", "--data", pattern, "--scheduler", "tcp://127.0.0.1:1"])
        == 2
    )
    assert "--scheduler tcp://127.0.0.1:1: cannot connect" in capsys.readouterr().err
