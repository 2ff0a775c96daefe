"""Independent traces in worker processes, the cores shared out.

A scan or a scenario list made of many small traces (8 façade sensors × ~1000 paths an hour)
gains little from the NumPy engine's threads: its batches are too small, so two threads take
~1.35 × the CPU time of one for the same wall time (measured on the diagnosis's runs,
:mod:`radtree.diagnose.parallel`). :func:`spawned_map` runs such traces in *spawned* worker
processes (a fresh interpreter each: no ray-tracer thread state is forked), each with
``engine.workers`` = the usable cores ÷ the processes. The NumPy engine's numbers do not
depend on its thread count (:mod:`radtree.engines.common.streams`), so the results are those
of the same calls in this process, in the same order.
"""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace
from typing import TypeVar

from radtree.config import Project

J = TypeVar("J")
R = TypeVar("R")


def usable_cores() -> int:
    """The CPU cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def with_threads(project: Project, threads: int) -> Project:
    """``project`` with ``engine.workers`` = ``threads`` (not hashed: same numbers)."""
    return replace(project, engine=replace(project.engine, workers=max(1, int(threads))))


def spawned_map(fn: Callable[[J], R], jobs: Sequence[J], workers: int | None = None
                ) -> list[R]:
    """``[fn(job) for job in jobs]``, computed in ``workers`` spawned processes (default: the
    usable cores, at most 4 and at most one per job); in this process when that is ≤ 1.
    ``fn`` must be a module-level function and each job picklable; a job's exception is
    raised here, as it would be in a loop."""
    n = min(len(jobs), usable_cores() if workers is None else max(1, int(workers)), 4)
    if n <= 1:
        return [fn(job) for job in jobs]
    with ProcessPoolExecutor(n, mp_context=multiprocessing.get_context("spawn")) as pool:
        return list(pool.map(fn, jobs))
