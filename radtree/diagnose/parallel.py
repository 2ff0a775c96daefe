"""Tracing a diagnosis's scenarios in worker processes.

A diagnosis or a self-test knows ahead which scenarios it will simulate (every candidate
effect switched on at each of its strengths, the self-test's truths); :class:`TracePool`
traces those in ``workers`` processes (``concurrent.futures``, *spawned*: a fresh interpreter,
so no ray-tracer thread state is forked) and hands the traced parts back to the
:class:`~radtree.diagnose.simulate.Simulator`, whose cache then serves every later
``run`` — the numbers are those of the same simulator in this process (same engine, rays,
seed, scene), only computed elsewhere. Each worker makes each simulator once (from
:meth:`~radtree.diagnose.simulate.Simulator.spec`) and keeps its scenes between tasks. The
workers trace with ``engine.workers`` = the cores ÷ the processes (at least 1): the NumPy
engine's threads would otherwise compete with the other processes for the same cores (the
numbers do not depend on it, :mod:`radtree.engines.common.streams`; measured on the rich
campaign's runs: 2 threads in one process take 1.35 × the CPU time of 1 for the same wall
time — a diagnosis's grids are too small for threads to pay).
:meth:`TracePool.loops` runs whole diagnosis loops in the workers (the self-test's hidden
effects are independent), each starting from everything traced so far.
"""

from __future__ import annotations

import multiprocessing
import os
import time
import uuid
from collections.abc import Iterable
from concurrent.futures import Future, ProcessPoolExecutor
from dataclasses import dataclass, replace
from typing import Any

from radtree.config import Project, Scenario
from radtree.diagnose.effects import EffectContext
from radtree.diagnose.loop import LoopOptions, LoopResult, run_loop
from radtree.diagnose.measured import Measured
from radtree.diagnose.simulate import Simulator

_SIMULATORS: dict[str, Simulator] = {}   # per worker process: token → simulator


def _cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def default_workers() -> int:
    """Worker processes by default: the usable CPU cores, at most 4."""
    return max(1, min(4, _cores()))


Spec = tuple[type, tuple[Any, ...], dict[str, Any]]


def threaded(spec: Spec, threads: int) -> Spec:
    """``spec`` with its project's ``engine.workers`` set to ``threads`` (not hashed: same
    cache keys, same numbers)."""
    cls, args, kwargs = spec
    project = args[0]
    project = replace(project, engine=replace(project.engine, workers=max(1, int(threads))))
    return cls, (project, *args[1:]), kwargs


def _simulator(token: str, spec: Spec) -> Simulator:
    sim = _SIMULATORS.get(token)
    if sim is None:
        cls, args, kwargs = spec
        sim = _SIMULATORS[token] = cls(*args, **kwargs)
    return sim


def _trace(token: str, spec: Spec, sc: Scenario) -> tuple[Any, float]:
    sim = _simulator(token, spec)
    t0 = time.perf_counter()
    payload = sim.trace_payload(sc)
    return payload, time.perf_counter() - t0


class TracePool:
    """``workers`` processes tracing scenarios for simulators of this process (a context
    manager; ``workers`` ≤ 1: nothing runs elsewhere, :meth:`prefetch` does nothing)."""

    def __init__(self, workers: int | None = None):
        self.workers = default_workers() if workers is None else max(1, int(workers))
        #: engine threads in each worker process: the usable cores shared out
        self.threads = max(1, _cores() // self.workers)
        self._pool: ProcessPoolExecutor | None = None
        self._tokens: dict[int, str] = {}
        self.tasks = 0

    def __enter__(self) -> TracePool:
        if self.workers > 1:
            self._pool = ProcessPoolExecutor(self.workers,
                                             mp_context=multiprocessing.get_context("spawn"))
        return self

    def __exit__(self, *exc: object) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None

    def _worker(self, sim: Simulator) -> tuple[str, Spec]:
        """The token and the (single-threaded where the cores are shared) spec by which the
        workers make ``sim`` again."""
        return (self._tokens.setdefault(id(sim), uuid.uuid4().hex),
                threaded(sim.spec(), self.threads))

    def prefetch(self, sim: Simulator, scenarios: Iterable[Scenario]) -> int:
        """Trace the scenarios whose traced part ``sim`` lacks (one per traced key) in the
        workers and store them in ``sim``; returns how many were traced."""
        if self._pool is None:
            return 0
        token, spec = self._worker(sim)
        todo: dict[str, Scenario] = {}
        for sc in scenarios:
            key = sim._traced_key(sc)
            if key not in todo and not sim.has_traced(sc):
                todo[key] = sc
        futures: list[tuple[Scenario, Future[tuple[Any, float]]]] = [
            (sc, self._pool.submit(_trace, token, spec, sc)) for sc in todo.values()]
        for sc, fut in futures:
            payload, seconds = fut.result()
            sim.store_traced(sc, payload, seconds)
        self.tasks += len(futures)
        return len(futures)

    def loops(self, sim: Simulator, project: Project, jobs: list[tuple[Scenario, Measured]],
              options: LoopOptions) -> list[LoopResult]:
        """:func:`~radtree.diagnose.loop.run_loop` from each ``(start, measured)`` of ``jobs``,
        one job per task, with everything ``sim`` has traced so far (what the workers trace
        is added to it); in this process when there is no pool."""
        if self._pool is None:
            ctx = EffectContext(project)
            return [run_loop(sim, ctx=ctx, start=start, measured=meas, options=options)
                    for start, meas in jobs]
        token, spec = self._worker(sim)
        traced = dict(sim.traced_cache())
        weights = getattr(sim, "weights", None)
        futures = [self._pool.submit(_loop, token, spec, weights, traced,
                                     _Job(project, start, meas, options))
                   for start, meas in jobs]
        out = []
        for fut in futures:
            loop, new, seconds = fut.result()
            cache = sim.traced_cache()
            for key, payload in new.items():
                if key not in cache:
                    cache[key] = payload
                    sim.traced_runs += 1
            sim.trace_seconds += seconds
            out.append(loop)
        self.tasks += len(futures)
        return out


@dataclass(frozen=True)
class _Job:
    """One diagnosis loop for a worker: from ``start`` against ``measured``."""

    project: Project
    start: Scenario
    measured: Measured
    options: LoopOptions


def _loop(token: str, spec: Spec, weights: Any, traced: dict[str, Any], job: _Job
          ) -> tuple[LoopResult, dict[str, Any], float]:
    sim = _simulator(token, spec)
    if weights is not None:
        sim.weights = weights  # type: ignore[attr-defined]
    cache = sim.traced_cache()
    for key, payload in traced.items():
        cache.setdefault(key, payload)
    have, t0 = set(cache), sim.trace_seconds
    loop = run_loop(sim, ctx=EffectContext(job.project), start=job.start, measured=job.measured,
                    options=job.options)
    return loop, {k: v for k, v in cache.items() if k not in have}, sim.trace_seconds - t0
