"""Simulate: every selected scenario × hour on one engine → ``results/illuminance.csv``.

Three steps, each a function of its own:

* **plan** (:func:`plan_simulation`): the engine, the scenarios and their hour states and
  scenes (a build-folder engine's folders built when stale), the parts already finished
  (resume), and the trace jobs left, grouped as the engine traces best — decided once in
  :class:`Layout`;
* **execute** (:func:`execute_plan`): the jobs on one :class:`~radtree.pipeline.executor.Executor`
  (a thread pool by default, Dask with ``RunOptions(scheduler=…)``), each hour written to its
  part file as it finishes;
* **publish** (:func:`radtree.pipeline.publish.publish`): the results table, direct-sun file,
  district GeoJSON, tree impact, timing and manifest, together under the publish lock.

Finished (scenario, hour) parts are kept in ``results/parts/`` keyed by the engine and the
scenario's parameter hash, so an interrupted run resumes where it stopped. Crown realisations
(``F@k``) are averaged back into their scenario (:mod:`radtree.pipeline.realisations`).
Messages go to the module loggers (:mod:`radtree.log`), the progress bar through
:func:`radtree.log.progress`.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, replace
from pathlib import Path

import pandas as pd

from radtree.config import Project, Scenario
from radtree.engines.base import Engine
from radtree.fileio import make_folder
from radtree.light.sky import SkyState
from radtree.log import progress
from radtree.pipeline.build import hour_grids
from radtree.pipeline.executor import Executor
from radtree.pipeline.jobs import (
    RESUME,
    Prepared,
    TraceJob,
    engine_trace,
    prepare_scenario,
    resolve_engine,
    trace_job,
)
from radtree.pipeline.limits import check_memory
from radtree.pipeline.options import RunOptions
from radtree.pipeline.parts import check_part
from radtree.pipeline.processes import usable_cores, with_threads
from radtree.pipeline.publish import Run, SimulationOutcome, publish
from radtree.pipeline.realisations import selected
from radtree.scene import Scene

__all__ = ["RESUME", "Layout", "RunOptions", "SimulationOutcome", "SimulationPlan",
           "TraceJob", "dry_run_commands", "engine_trace", "execute_plan", "plan_simulation",
           "prepare_scenario", "resolve_engine", "simulate_project", "task_chunks", "trace_job"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Layout:
    """How the engine's work is laid out, decided once per run from the engine and executor.

    ``folder``: the engine traces ``build/<scenario>/`` (Radiance: built first, one job per
    hour — a Makefile target each); else an in-process engine, whose jobs hold a scenario's
    hours (each grid traced at all its hours in one batch, :meth:`Engine.trace_many`; each
    grid draws from its own stream, so a grid's numbers are those of
    :func:`radtree.pipeline.trace.trace_hours` over the same hours and a resumed run's those
    of a fresh one). ``ship_plans``: jobs carry the engine's plan (not for an in-process
    engine's jobs pickled to Dask: a worker prepares the scenario itself). ``threads``: the
    engine threads of each in-process job (None: the project's ``engine.workers``)."""

    folder: bool
    ship_plans: bool
    threads: int | None

    @classmethod
    def of(cls, engine: Engine, executor: Executor, jobs_at_once: int) -> Layout:
        in_process = not engine.uses_build_folder
        threads = None
        if in_process and not executor.remote:
            # the cores shared out over the hours traced at once (an in-process engine's
            # numbers do not depend on them; 2 hours × 1 thread take ~20 % less CPU and wall
            # time than 2 × 2 on 2 cores)
            threads = max(1, usable_cores() // max(1, jobs_at_once))
        return cls(not in_process, not (in_process and executor.remote), threads)


@dataclass(frozen=True)
class SimulationPlan:
    """A run decided, nothing traced yet: ``run`` (what publish needs), the ``jobs`` left
    (most sensors first), the rows of the parts ``reused``, the ``executor``, the ``layout``
    and the preparation ``timing`` (s) per scenario."""

    run: Run
    jobs: list[TraceJob]
    reused: list[pd.DataFrame]
    executor: Executor
    layout: Layout
    timing: dict[str, dict[str, float]]


def simulate_project(project: Project, *, options: RunOptions | None = None
                     ) -> SimulationOutcome:
    """Trace every selected scenario × hour and write ``results/illuminance.csv`` (plan →
    execute → publish; see the module text). Finished parts are kept and reused on the next
    run unless ``options.fresh``."""
    plan = plan_simulation(project, options=options or RunOptions())
    frames, timing = execute_plan(plan)
    computed = sum(len(j.parts) for j in plan.jobs)
    return publish(plan.run, frames, timing, (computed, len(plan.reused)))


def _prepare(project: Project, options: RunOptions
             ) -> tuple[Engine, list[Scenario], dict[str, Prepared], Executor, Layout]:
    """The engine, the chosen scenarios prepared for it, the executor and the layout."""
    eng = resolve_engine(project, options.engine)
    chosen = selected(project, list(options.scenarios) if options.scenarios else None)
    workers = options.workers or project.engine.workers
    executor = options.executor(project.engine.workers)
    hours = list(options.hours) if options.hours else None
    layout = Layout.of(eng, executor, min(workers, len(chosen) * len(hours or
                                                                      project.site.hours)))
    here = project if layout.threads is None else with_threads(project, layout.threads)
    prepared = {sc.name: prepare_scenario(here, sc, eng, hours) for sc in chosen}
    check_memory(project, [p.built.triangles for p in prepared.values()], max(1, workers))
    return eng, chosen, prepared, executor, layout


def dry_run_commands(project: Project, *, options: RunOptions | None = None) -> list[str]:
    """The engine's commands for every selected scenario × hour (nothing traced; a
    build-folder engine's folders are built when stale)."""
    eng, chosen, prepared, _, layout = _prepare(project, options or RunOptions())
    return [line if layout.folder else f"{sc.name}: {line}"
            for sc in chosen for st in prepared[sc.name].states
            for line in eng.commands(prepared[sc.name].plan, st.label)]


def plan_simulation(project: Project, *, options: RunOptions) -> SimulationPlan:
    """The plan step: prepare the scenarios, find the finished parts, make the jobs left."""
    eng, chosen, prepared, executor, layout = _prepare(project, options)
    groups = _part_groups(project, eng, chosen, prepared, options.grids, layout)
    jobs, reused = _jobs_left(project, eng, chosen, prepared, groups, options.resume)
    # most sensors first (the dense map's hour, the crowns' realisations after), so the
    # workers do not end on one long task; the table's order does not depend on it
    jobs.sort(key=lambda j: -len(j.states) * sum(len(g.points) for g in j.scene.grids.values()))
    timing = {n: {"preparation_s": p.seconds, "geometry_s": p.built.geometry_seconds,
                  "tracing_s": 0.0} for n, p in prepared.items()}
    run = Run(project, eng, tuple(chosen), prepared, options.grids,
              frozenset(j.scenario.name for j in jobs), options.tree_impact)
    return SimulationPlan(run, jobs, reused, executor, layout, timing)


def _district_chunks(project: Project) -> bool:
    return project.district is not None and project.district.buildings is not None


def task_chunks(project: Project, grids: list[str]) -> list[list[str]]:
    """The grids of one hour split into tasks: one per façade chunk for an inventory project
    with buildings (grids ``facades_000`` …), else all grids in one task."""
    if _district_chunks(project):
        return [[g] for g in grids]
    return [grids]


_Member = tuple[SkyState, Path, list[str]]   # an hour, its part file, its grids


def _part_groups(project: Project, eng: Engine, chosen: list[Scenario],
                 prepared: dict[str, Prepared], grids: tuple[str, ...] | None,
                 layout: Layout) -> dict[tuple, list[_Member]]:
    """The parts to have, grouped into jobs: per scenario (and façade chunk), per hour too
    for a build-folder engine. The groups do not depend on what is already done."""
    parts_dir = project.results_dir / "parts"
    wanted = list(grids) if grids else None
    groups: dict[tuple, list[_Member]] = {}
    for sc in chosen:
        prep = prepared[sc.name]
        for st in prep.states:
            use = hour_grids(project, st.time, list(prep.built.scene.grids), wanted, sc)
            for chunk in task_chunks(project, use):
                tag = f"_{chunk[0]}" if len(chunk) == 1 and project.district is not None else ""
                part = parts_dir / f"{sc.name}_{st.label}{tag}_{eng.name}_{prep.phash}.csv"
                key = (sc.name, tuple(chunk) if _district_chunks(project) else (),
                       st.label if layout.folder else "")
                groups.setdefault(key, []).append((st, part, chunk))
    return groups


def _jobs_left(project: Project, eng: Engine, chosen: list[Scenario],
               prepared: dict[str, Prepared], groups: dict[tuple, list[_Member]],
               resume: bool) -> tuple[list[TraceJob], list[pd.DataFrame]]:
    """A job per group with a part missing (or unsound, or ``resume`` off); the rows of the
    groups whose parts are all there."""
    jobs: list[TraceJob] = []
    reused: list[pd.DataFrame] = []
    by_name = {sc.name: sc for sc in chosen}
    for (name, *_), members in groups.items():
        sc, prep = by_name[name], prepared[name]
        done = [_finished_part(part, sc, st, prep.phash, resume) for st, part, _ in members]
        if all(rows is not None for rows in done):
            reused.extend(d for d in done if d is not None)
            continue
        union = dict.fromkeys(g for _, _, chunk in members for g in chunk)
        sub = Scene([], {}, {g: prep.built.scene.grids[g] for g in union})
        jobs.append(TraceJob(eng, prep.plan, project, sc, [m[0] for m in members],
                             [m[2] for m in members], sub, prep.phash, [m[1] for m in members]))
    return jobs, reused


def _finished_part(part: Path, sc: Scenario, st: SkyState, phash: str,
                   resume: bool) -> pd.DataFrame | None:
    """The rows of a sound earlier part (None: missing, unsound, or not resuming)."""
    if not resume or not part.exists():
        return None
    rows, why = check_part(part, sc.name, st.time, phash)
    if why:
        log.info("  results/parts/%s %s: recomputing it", part.name, why)
    return rows


def execute_plan(plan: SimulationPlan) -> tuple[list[pd.DataFrame], dict[str, dict[str, float]]]:
    """The execute step: trace the plan's jobs on its executor (each hour's part written as
    it finishes); return every row (reused parts first) and the timing per scenario (s). A
    failed job raises (the parts finished so far stay: the next run resumes)."""
    frames = list(plan.reused)
    timing = {n: dict(t) for n, t in plan.timing.items()}
    if not plan.jobs:
        return frames, timing
    make_folder(plan.run.project.results_dir / "parts")
    jobs = plan.jobs if plan.layout.ship_plans else [replace(j, plan=None) for j in plan.jobs]
    bar = progress(None, desc=f"simulate ({plan.run.engine.name})",
                   total=sum(len(j.states) for j in jobs), unit="hour")
    try:
        for done in plan.executor.run(trace_job, jobs, label="trace"):
            frames.append(done.value())
            timing[done.job.scenario.name]["tracing_s"] += done.seconds
            bar.update(len(done.job.states))
    finally:
        bar.close()
    return frames, timing
