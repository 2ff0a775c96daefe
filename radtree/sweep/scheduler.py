"""Run the cases of a sweep on an :class:`~radtree.pipeline.executor.Executor`.

Execution: a :class:`dask.distributed.LocalCluster` by default (one single-threaded worker
process per core, loopback only, no dashboard), or ``scheduler="tcp://host:port"`` for an
existing cluster (its workers must have radtree installed and see the output folder), or
``scheduler="sequential"`` to run the same case function in this process — the executors of
:func:`radtree.pipeline.executor.make_executor`, which ``simulate`` runs its trace jobs on too.
Every path runs :func:`run_case` once per case and collects results as they complete; a
failing case is recorded and the others go on.
"""

from __future__ import annotations

from collections.abc import Callable

from radtree.pipeline.executor import Executor, default_workers, make_executor
from radtree.sweep.cases import CaseResult, CaseSpec, run_case

__all__ = ["default_workers", "execute", "make_executor"]


def execute(specs: list[CaseSpec], executor: Executor,
            on_result: Callable[[CaseResult], None] | None = None) -> list[CaseResult]:
    """Run :func:`run_case` for every spec on ``executor``; return results in completion
    order (``on_result`` called with each as it comes). A task that failed outside
    :func:`run_case` (a lost Dask worker) becomes a ``failed`` result of its case."""
    results: list[CaseResult] = []
    for done in executor.run(run_case, specs, label="case"):
        res = done.result if done.error is None else _lost(done.job, done.error)
        results.append(res)
        if on_result is not None:
            on_result(res)
    return results


def _lost(spec: CaseSpec, exc: Exception) -> CaseResult:
    """The result of a case whose task failed (:func:`run_case` itself never raises)."""
    what = (f"every Dask worker that ran it died (killed, or out of memory?): {exc}; its "
            f"finished hours are kept in {spec.folder}/results/parts and a rerun resumes"
            if type(exc).__name__ == "KilledWorker"
            else f"the dask task failed: {type(exc).__name__}: {exc}")
    return CaseResult(spec.case_id, spec.case_hash, dict(spec.params), "failed", error=what,
                      error_type=type(exc).__name__)
