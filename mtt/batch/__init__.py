"""Many records, one model: per-record fits (or estimates), or one fit pooled over them all,
on this machine's cores (concurrent.futures) or on a dask.distributed cluster.

    import mtt.batch
    batch = mtt.batch.fit_many(mtt.example("dc_drive"), "logs/*.csv", hold="zoh")
    for outcome in batch:
        print(outcome.name, outcome.error or outcome.result.k)

See docs/batch.md. The workers receive the generated module's source and need only numpy
and scipy (and pandas for Parquet records).
"""

from mtt.batch.api import Batch, Outcome, estimate_many, fit_many

__all__ = ["Batch", "Outcome", "estimate_many", "fit_many"]
