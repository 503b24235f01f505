"""Many records, one model: per-record fits (or estimates), or one fit pooled over them all,
on this machine's cores (concurrent.futures) or on a dask.distributed cluster.

    import mtt.batch
    batch = mtt.batch.fit_many(mtt.example("dc_drive"), "logs/*.csv", hold="zoh")
    for outcome in batch:
        print(outcome.name, outcome.error or outcome.result.k)

See docs/batch.md. Worker processes import only mtt.batch.worker (the standard library);
the estimator reaches them as source. So this package imports its API when first used.
"""

__all__ = ["Batch", "Outcome", "estimate_many", "fit_many"]


def __getattr__(name: str):
    if name in __all__:
        from mtt.batch import api

        return getattr(api, name)
    raise AttributeError(f"module 'mtt.batch' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
