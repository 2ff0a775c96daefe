"""One way to run many independent jobs: a thread pool by default, Dask behind the same interface.

``simulate`` (its trace jobs) and ``sweep`` (its cases) hand a picklable, module-level
function and a list of jobs to an :class:`Executor`; :meth:`Executor.run` yields one
:class:`Finished` per job **as the jobs complete** (not in order), carrying the job, its
result or the exception it raised, and the seconds it ran (wall clock, measured where it ran).
Leaving the loop early (an error, an interrupt) cancels every job not started and shuts the
pool or the cluster down.

Kinds (:func:`make_executor`): ``None`` → :class:`ThreadExecutor` (``workers`` threads in this
process), ``"sequential"`` → :class:`SequentialExecutor` (one after another in this thread),
``"local"`` → :class:`DaskExecutor` on a :class:`dask.distributed.LocalCluster` (``workers``
single-threaded processes on 127.0.0.1, default one per core, no dashboard), or a scheduler
address ``"tcp://HOST:PORT"`` → :class:`DaskExecutor` on that cluster (its workers must have
radtree installed and see the project folder). A Dask executor is :attr:`~Executor.remote`:
its jobs are pickled to other processes.
"""

from __future__ import annotations

import os
import time
import uuid
import warnings
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import Future, ThreadPoolExecutor, as_completed
from dataclasses import dataclass
from functools import partial
from importlib.util import find_spec
from typing import Any, ClassVar

from radtree.errors import ConfigError, RadtreeError, install_extra

__all__ = ["Executor", "Finished", "ThreadExecutor", "SequentialExecutor", "DaskExecutor",
           "make_executor", "default_workers", "scheduler_problem"]


def default_workers() -> int:
    """One worker per CPU core."""
    return max(1, os.cpu_count() or 1)


@dataclass(frozen=True)
class Finished:
    """One job done: its ``result``, or the ``error`` it raised (an :class:`Exception`; an
    interrupt is raised, not recorded); ``seconds`` it ran (0 when it failed)."""

    job: Any
    result: Any = None
    error: Exception | None = None
    seconds: float = 0.0

    def value(self) -> Any:
        """The result; the job's exception raised here when it failed."""
        if self.error is not None:
            raise self.error
        return self.result


def _timed(fn: Callable[[Any], Any], job: Any) -> tuple[Any, float]:
    """``fn(job)`` and the seconds it took (module level: Dask pickles it)."""
    t0 = time.perf_counter()
    out = fn(job)
    return out, time.perf_counter() - t0


def _from_future(job: Any, fut: Any) -> Finished:
    """A finished future (concurrent or Dask) → :class:`Finished`; an interrupt is raised."""
    try:
        out, seconds = fut.result()
    except Exception as exc:  # noqa: BLE001 - the caller decides: raise, or record the job
        return Finished(job, error=exc)
    return Finished(job, out, None, seconds)


class Executor:
    """Runs ``fn(job)`` for every job; :meth:`run` yields :class:`Finished` in completion order."""

    #: the jobs are pickled to other processes (state held only in memory does not travel)
    remote: ClassVar[bool] = False
    #: what the executor is, for a message ("8 threads", "dask tcp://…")
    describe: str = ""

    def run(self, fn: Callable[[Any], Any], jobs: Sequence[Any], *,
            label: str = "job") -> Iterator[Finished]:
        raise NotImplementedError


class SequentialExecutor(Executor):
    """Every job in this thread, one after another."""

    describe = "sequential"

    def run(self, fn: Callable[[Any], Any], jobs: Sequence[Any], *,
            label: str = "job") -> Iterator[Finished]:
        for job in jobs:
            try:
                out, seconds = _timed(fn, job)
            except Exception as exc:  # noqa: BLE001 - recorded; the caller decides
                yield Finished(job, error=exc)
                continue
            yield Finished(job, out, None, seconds)


class ThreadExecutor(Executor):
    """``workers`` threads of this process (the engines release the GIL or run programs)."""

    def __init__(self, workers: int = 1) -> None:
        self.workers = max(1, int(workers))
        self.describe = f"{self.workers} thread(s)"

    def run(self, fn: Callable[[Any], Any], jobs: Sequence[Any], *,
            label: str = "job") -> Iterator[Finished]:
        if not jobs:
            return
        pool = ThreadPoolExecutor(max_workers=self.workers, thread_name_prefix=f"radtree-{label}")
        futures: dict[Future, Any] = {pool.submit(_timed, fn, job): job for job in jobs}
        try:
            for fut in as_completed(futures):
                yield _from_future(futures[fut], fut)
        finally:
            for fut in futures:
                fut.cancel()
            pool.shutdown(wait=True)


class DaskExecutor(Executor):
    """One Dask task per job on ``scheduler``: ``"local"`` (a LocalCluster of ``workers``
    single-threaded processes, at most one per job) or a scheduler address."""

    remote = True

    def __init__(self, scheduler: str = "local", workers: int | None = None) -> None:
        self.scheduler, self.workers = scheduler, workers
        self.describe = f"dask {scheduler}"

    def run(self, fn: Callable[[Any], Any], jobs: Sequence[Any], *,
            label: str = "job") -> Iterator[Finished]:
        if not jobs:
            return
        from dask.distributed import as_completed as dask_completed

        client, cluster = open_client(self.scheduler, self.workers, len(jobs))
        token = uuid.uuid4().hex[:8]
        timed = partial(_timed, fn)
        futures = [client.submit(timed, job, key=f"radtree-{label}-{i}-{token}", pure=False)
                   for i, job in enumerate(jobs)]
        by_key = {fut.key: job for fut, job in zip(futures, jobs, strict=True)}
        try:
            for fut in dask_completed(futures):
                yield _from_future(by_key[fut.key], fut)
        finally:
            for fut in futures:
                if not fut.done():
                    fut.cancel()
            client.close()
            if cluster is not None:
                cluster.close()


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


def scheduler_problem(scheduler: str) -> str:
    """Why ``scheduler`` names no executor ("" when it does)."""
    if scheduler == "sequential":
        return ""
    if scheduler == "local" or "://" in scheduler:
        if find_spec("distributed") is None:
            return (f"scheduler {scheduler!r} runs on dask, which is not installed: "
                    f"{install_extra('sweep')}")
        return ""
    return (f"scheduler {scheduler!r}: expected 'local', 'sequential' or a dask scheduler "
            "address such as tcp://127.0.0.1:8786")


def make_executor(scheduler: str | None, workers: int | None) -> Executor:
    """The executor for ``scheduler`` (see the module text): None → a thread pool of
    ``workers`` (default 1)."""
    if scheduler is None:
        return ThreadExecutor(workers or 1)
    if scheduler == "sequential":
        return SequentialExecutor()
    problem = scheduler_problem(scheduler)
    if problem:
        raise ConfigError(problem, field="scheduler")
    return DaskExecutor(scheduler, workers)
