"""Run the cases of a sweep on ``dask.distributed`` or in this process.

Execution: a :class:`dask.distributed.LocalCluster` by default (one single-threaded worker
process per core, loopback only, no dashboard), or ``scheduler="tcp://host:port"`` for an
existing cluster (its workers must have radtree installed and see the output folder), or
``scheduler="sequential"`` to run the same case function in this process. Every path submits
:func:`run_case` once per case and collects results as they complete; a failing case is
recorded and the others go on.
"""

from __future__ import annotations

import os
import uuid
import warnings
from collections.abc import Callable, Iterator
from typing import Any

from radtree.errors import RadtreeError
from radtree.sweep.cases import CaseResult, CaseSpec, run_case


def default_workers() -> int:
    """One worker process per CPU core."""
    return max(1, os.cpu_count() or 1)


def execute(specs: list[CaseSpec], scheduler: str = "local", workers: int | None = None,
            on_result: Callable[[CaseResult], None] | None = None) -> list[CaseResult]:
    """Run :func:`run_case` for every spec; return results in completion order.

    ``scheduler``: ``"sequential"`` (this process), ``"local"`` (a LocalCluster of ``workers``
    single-threaded processes on 127.0.0.1, default one per core), or a scheduler address.
    """
    results: list[CaseResult] = []

    def take(res: CaseResult) -> None:
        results.append(res)
        if on_result is not None:
            on_result(res)

    if not specs:
        return results
    if scheduler == "sequential":
        for spec in specs:
            take(run_case(spec))
        return results

    from dask.distributed import as_completed

    client, cluster = open_client(scheduler, workers, len(specs))
    token = uuid.uuid4().hex[:8]
    futures = []
    try:
        by_future = {}
        for spec in specs:
            fut = client.submit(run_case, spec, key=f"radtree-case-{spec.case_hash}-{token}",
                                pure=False)
            futures.append(fut)
            by_future[fut.key] = spec
        for fut in as_completed(futures):
            spec = by_future[fut.key]
            try:
                res = fut.result()
            except Exception as exc:  # noqa: BLE001 - a lost worker fails this case only
                what = (f"every Dask worker that ran it died (killed, or out of memory?): "
                        f"{exc}; its finished hours are kept in {spec.folder}/results/parts "
                        "and a rerun resumes" if type(exc).__name__ == "KilledWorker"
                        else f"the dask task failed: {type(exc).__name__}: {exc}")
                res = CaseResult(spec.case_id, spec.case_hash, dict(spec.params), "failed",
                                 error=what, error_type=type(exc).__name__)
            take(res)
    finally:
        _shut_down(futures, client, cluster)
    return results


def open_client(scheduler: str, workers: int | None, tasks: int) -> tuple[Any, Any]:
    """A dask Client (and the LocalCluster it owns, or None) for ``scheduler``: ``"local"``
    (``workers`` single-threaded processes on 127.0.0.1, default one per core) or an address."""
    import logging

    from dask.distributed import Client, LocalCluster

    if scheduler == "local":
        n = max(1, min(workers or default_workers(), tasks))
        with warnings.catch_warnings():  # "port 8787 in use": the scheduler picks another
            warnings.simplefilter("ignore", UserWarning)
            cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                                   dashboard_address=None, host="127.0.0.1",
                                   silence_logs=logging.ERROR)
        return Client(cluster), cluster
    try:
        return Client(scheduler, timeout=30), None
    except (OSError, TimeoutError) as exc:
        raise RadtreeError(f"cannot connect to the dask scheduler at {scheduler}: {exc}"
                           ) from exc


def _shut_down(futures: list[Any], client: Any, cluster: Any) -> None:
    """Cancel what has not finished, close the client and (when we started it) the cluster."""
    for fut in futures:
        if not fut.done():
            fut.cancel()
    client.close()
    if cluster is not None:
        cluster.close()


def map_jobs(fn: Callable[[Any], Any], jobs: list[Any], scheduler: str = "local",
             workers: int | None = None) -> Iterator[Any]:
    """Yield ``fn(job)`` for every job as the Dask tasks complete (``simulate --scheduler``:
    one task per scenario × hour × realisation × façade chunk). A failed task raises (the
    parts finished so far stay on disk: the next run resumes)."""
    if not jobs:
        return
    from dask.distributed import as_completed

    client, cluster = open_client(scheduler, workers, len(jobs))
    token = uuid.uuid4().hex[:8]
    futures = [client.submit(fn, job, key=f"radtree-trace-{i}-{token}", pure=False)
               for i, job in enumerate(jobs)]
    try:
        for fut in as_completed(futures):
            yield fut.result()
    finally:
        _shut_down(futures, client, cluster)
