"""``simulate``'s units of work: a scenario prepared for an engine, and the trace jobs made of it.

A :class:`TraceJob` is a scenario's hours on some grids (a façade chunk of an inventory),
each hour written to its own part file; :func:`trace_job` runs one — in a thread of this
process, or pickled to a Dask worker (:mod:`radtree.pipeline.executor`), where a job shipped
without its engine plan (``plan`` None) prepares the scenario itself, once per worker.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pandas as pd

from radtree.config import Project, Scenario, effective_project
from radtree.engines.base import Engine
from radtree.engines.registry import get_engine
from radtree.errors import EngineError, RadtreeError
from radtree.light.hours import hour_states
from radtree.light.sky import SkyState
from radtree.pipeline.assemble import BuiltScene
from radtree.pipeline.build import built_scene, ensure_built, log_notes
from radtree.pipeline.parts import write_part
from radtree.pipeline.results import hour_rows
from radtree.scene import Scene

log = logging.getLogger(__name__)

RESUME = "finished hours are kept in results/parts/; run the same command again to resume"


@dataclass
class Prepared:
    """A scenario ready to trace: its scene, hour states, parameter hash, the engine's plan
    and the ``seconds`` the hour states (sun, sky, weather) took."""

    built: BuiltScene
    states: list[SkyState]
    phash: str
    plan: Any
    seconds: float


@dataclass
class TraceJob:
    """One unit of work: a scenario's hours on some grids (a façade chunk), each hour written
    to its part (``parts[i]`` for ``states[i]``). ``plan`` None: the worker prepares the
    scenario itself (in-memory engines on Dask)."""

    engine: Engine
    plan: Any
    project: Project
    scenario: Scenario
    states: list[SkyState]
    grids: list[list[str]]  # per state
    scene: Scene            # the grids only
    phash: str
    parts: list[Path]


def resolve_engine(project: Project, engine: str | Engine | None = "auto") -> Engine:
    """The engine to run: an instance as given, or by name (``auto`` or None → the project's
    ``engine.name``, itself ``auto`` → Radiance when found, else NumPy)."""
    if isinstance(engine, Engine):
        return engine
    if engine not in (None, "auto"):
        return get_engine(engine)
    return get_engine(project.engine.name, source=str(project.source))


def prepare_scenario(project: Project, sc: Scenario, engine: Engine,
                     hours: list[str] | None = None) -> Prepared:
    """A scenario's scene, hour states, parameter hash and the engine's plan (a build-folder
    engine's folder (re)built first when stale)."""
    t0 = time.perf_counter()
    states = hour_states(project, sc, hours)
    seconds = time.perf_counter() - t0
    built = built_scene(project, sc)
    if not engine.uses_build_folder:   # a build folder's notes are logged when it is built
        log_notes(sc.name, built.notes)
    scene = built.scene
    if scene.instances and not engine.instancing:
        extra = scene.instanced_triangles()
        log.info("  %s: the %s engine has no instancing — %d crowns expanded to %d triangles "
                 "(~%.0f MiB of vertices, vs %d stored for Radiance)", sc.name, engine.name,
                 len(scene.instances), extra, extra * 9 * 8 / 2**20, scene.n_triangles)
    folder = ensure_built(project, sc) if engine.uses_build_folder else None
    plan = engine.prepare(built.scene, states, effective_project(project, sc).engine, built.ab,
                          folder)
    return Prepared(built, states, project.params_hash(sc), plan, seconds)


_WORKER_PLANS: dict[tuple[str, str], Any] = {}


def trace_job(job: TraceJob) -> pd.DataFrame:
    """Trace one job and write its part files atomically (runs in a thread or a Dask worker)."""
    plan = job.plan
    if plan is None:   # a worker process of an in-memory engine: prepare once per scenario
        key = (job.scenario.name, job.phash)
        if key not in _WORKER_PLANS:
            _WORKER_PLANS.clear()
            _WORKER_PLANS[key] = prepare_scenario(job.project, job.scenario, job.engine).plan
        plan = _WORKER_PLANS[key]
    if len(job.states) == 1:
        results = engine_trace(job.engine, plan, job.scenario, job.states, job.grids[0])
    else:   # each grid at the hours it is traced at, in one batch
        results = [{} for _ in job.states]
        for g in dict.fromkeys(g for gs in job.grids for g in gs):
            at = [i for i, gs in enumerate(job.grids) if g in gs]
            got = engine_trace(job.engine, plan, job.scenario, [job.states[i] for i in at], [g])
            for i, res in zip(at, got, strict=True):
                results[i].update(res)
    frames = []
    for st, res, part in zip(job.states, results, job.parts, strict=True):
        df = hour_rows(job.project, job.scenario, st, job.scene, res, job.engine.name,
                       job.phash)
        write_part(part, df)
        frames.append(df)
    return pd.concat(frames, ignore_index=True)


def engine_trace(eng: Engine, plan: Any, sc: Scenario, states: list[SkyState],
                 grids: list[str]) -> list[dict[str, Any]]:
    """``eng.trace_many`` of some hours; any failure of the engine (a Radiance program failing
    or killed, the in-process engine raising) → one :class:`EngineError` naming scenario and
    hour(s). Interrupts pass through."""
    try:
        return eng.trace_many(plan, [st.label for st in states], grids)
    except Exception as exc:  # noqa: BLE001 - every engine failure gets its scenario and hour
        what = str(exc) if isinstance(exc, RadtreeError) else f"{type(exc).__name__}: {exc}"
        hours = ("hour " if len(states) == 1 else "hours ") + ", ".join(st.time for st in states)
        raise EngineError(f"scenario {sc.name}, {hours}: the {eng.name} engine failed: "
                          f"{what}\n  {RESUME}") from exc
