"""Many records on many cores (issue 13): records of the DC drive fitted one by one in this
process, with --jobs 2 (a process pool) and on a dask LocalCluster of 2 worker processes.

Records: 1e4 samples each (dt 0.02, PRBS with a 1-s hold, 20 dB output noise, each its own
seed), given as arrays in memory and as CSV files (what `mtt fit --data 'logs/*.csv'`
reads). Each configuration runs `repeat` times, interleaved; the table shows the median
wall time, samples per second and the speed-up over this process. Every configuration must
give the same numbers, bit for bit (checked). Then the scaling on paper: a 64-worker
cluster and 1e6 records, from the measured CPU time per record, the dask scheduler's time
per task and this process's time per result.

    .venv/bin/python bench/batch.py [--records 1000] [--samples 10000] [--repeat 3]
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np
from _generated import generated

from mtt.batch import fit_many, worker

FIT = dict(hold="zoh")


def records(module, count: int, samples: int) -> list:
    out = []
    for seed in range(count):
        t = 0.02 * np.arange(samples)
        u = module.input_signal("prbs", t, period=1.0, seed=seed)
        y = module.with_noise(module.simulate(t, u, 10.0, hold="zoh"), 20.0, seed=seed)
        out.append((f"record {seed}", (t, u, y)))
    return out


def write(folder: Path, data: list) -> str:
    for name, (t, u, y) in data:
        number = int(name.split()[1])
        np.savetxt(folder / f"run_{number:05d}.csv", np.c_[t, u, y], delimiter=",",
                   header="t,u,y", comments="", fmt="%.17g")  # fmt: skip
    return str(folder / "run_*.csv")


def timed(function):
    wall, cpu = time.perf_counter(), time.process_time()
    result = function()
    return result, time.perf_counter() - wall, time.process_time() - cpu


def scheduler_cost(client, tasks: int = 2000) -> float:
    """Seconds of the cluster per task that does nothing (submit, schedule, run, gather)."""
    futures = client.map(worker.same, range(tasks), pure=False)
    client.gather(futures)  # warm up
    start = time.perf_counter()
    client.gather(client.map(worker.same, range(tasks), pure=False))
    return (time.perf_counter() - start) / tasks


REFERENCE: dict = {}


def run_all(configurations: dict, kinds, module, repeat: int) -> dict:
    """(kind, configuration) -> [(wall, this process's CPU, median CPU per record)], each
    configuration `repeat` times, interleaved; the estimates checked against the first."""
    times = {}
    for kind, given in kinds:
        for _ in range(repeat):
            for name, where in configurations.items():
                batch, wall, cpu = timed(lambda g=given, w=where: fit_many(module, g, **w, **FIT))
                ks = [outcome.result.k for outcome in batch]
                assert REFERENCE.setdefault(kind, ks) == ks, f"{name}: different numbers"
                per_record = statistics.median(outcome.seconds for outcome in batch)
                times.setdefault((kind, name), []).append((wall, cpu, per_record))
    return times


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records", type=int, default=1000)
    parser.add_argument("--samples", type=int, default=10000)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    from distributed import Client, LocalCluster

    module = generated("dc_drive")
    print(f"load average before: {os.getloadavg()[0]:.2f} (2 cores)")
    data = records(module, args.records, args.samples)
    samples = args.records * args.samples
    folder = tempfile.TemporaryDirectory(prefix="mtt-bench-")
    pattern = write(Path(folder.name), data)
    kinds = (("arrays", data), ("CSV files", pattern))
    # the pools first, while this process runs one thread (they fork it, as `mtt fit` does)
    times = run_all({"this process": dict(jobs=1), "--jobs 2": dict(jobs=2)}, kinds, module,
                    args.repeat)  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                               dashboard_address=None, silence_logs=40)  # fmt: skip
    with cluster, Client(cluster) as client:
        fit_many(module, data[:4], executor=client, **FIT)  # the workers import the module
        times |= run_all({"LocalCluster, 2 workers": dict(executor=client)}, kinds, module,
                         args.repeat)  # fmt: skip
        task = scheduler_cost(client)
    folder.cleanup()
    rows = []
    for kind, _ in kinds:
        base = statistics.median(wall for wall, _, _ in times[kind, "this process"])
        for (of, name), runs in times.items():
            if of == kind:
                wall = statistics.median(w for w, _, _ in runs)
                cpu = statistics.median(c for _, c, _ in runs)
                per_record = statistics.median(p for _, _, p in runs)
                rows.append((kind, name, wall, samples / wall, base / wall, cpu, per_record))
    print(f"load average after: {os.getloadavg()[0]:.2f}")
    print(f"\n{args.records} records of {args.samples} samples, median of {args.repeat} runs; "
          "every configuration gave the same estimates, bit for bit\n")  # fmt: skip
    print(
        "| records as | where | wall | samples/s | speed-up | this process's CPU | CPU per record |"
    )
    print("|---|---|---|---|---|---|---|")
    for kind, name, wall, rate, speedup, cpu, per_record in rows:
        print(f"| {kind} | {name} | {wall:.1f} s | {rate:.3g} | {speedup:.2f}x | {cpu:.1f} s | "
              f"{1000 * per_record:.1f} ms |")  # fmt: skip
    paper(rows, task, args.records)


def paper(rows, task: float, count: int) -> None:
    """1e6 records on 64 workers: the compute spread over them, against what stays serial
    (the scheduler's time per task and this process's time per result)."""
    workers, total, chunk = 64, 1_000_000, 32
    for kind in ("arrays", "CSV files"):
        (per_record,) = [r[6] for r in rows if r[0] == kind and r[1] == "this process"]
        (driver,) = [r[5] for r in rows if r[0] == kind and r[1] == "LocalCluster, 2 workers"]
        driver /= count  # this process's CPU per record on the cluster (results, tasks)
        compute = total * per_record / workers
        tasks = total / chunk * task
        serial = total * driver
        wall = max(compute, tasks, serial)
        print(f"\n{kind}: 1e6 records on {workers} workers (chunks of {chunk}): compute "
              f"{total:.0e} x {1000 * per_record:.1f} ms / {workers} = {compute:.0f} s; scheduler "
              f"{total // chunk} tasks x {1000 * task:.2f} ms = {tasks:.0f} s; this process "
              f"{1e6 * driver:.0f} us per result = {serial:.0f} s; so about {wall:.0f} s "
              f"({total * per_record / wall:.0f}x one core, {total / wall:.0f} records/s)")  # noqa: E501  # fmt: skip


if __name__ == "__main__":
    main()
