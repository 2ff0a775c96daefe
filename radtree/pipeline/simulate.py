"""Simulate: every selected scenario × hour on one engine → ``results/illuminance.csv``.

Finished (scenario, hour) parts are kept in ``results/parts/`` keyed by the engine and the
scenario's parameter hash, so an interrupted run resumes where it stopped. Crown realisations
(``F@k``) are averaged back into their scenario (:mod:`radtree.pipeline.realisations`).
"""

from __future__ import annotations

import json
import threading
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor, as_completed
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import pandas as pd

from radtree.config import Project, Scenario, effective_project
from radtree.engines.base import Engine
from radtree.engines.registry import get_engine
from radtree.errors import EngineError, RadtreeError
from radtree.fileio import atomic_path, make_folder, write_text
from radtree.light.hours import hour_states
from radtree.light.sky import SkyState
from radtree.lock import PUBLISH_NAME, folder_lock
from radtree.pipeline.assemble import BuiltScene
from radtree.pipeline.build import (
    built_scene,
    echo_notes,
    ensure_built,
    hour_grids,
    progress_bar,
)
from radtree.pipeline.limits import check_memory
from radtree.pipeline.manifest import manifest, weather_record
from radtree.pipeline.parts import check_part, write_part
from radtree.pipeline.processes import usable_cores, with_threads
from radtree.pipeline.realisations import merge_realisations, parent_name, selected
from radtree.pipeline.results import hour_rows, in_column_order, merge_write, results_path
from radtree.scene import Scene

RESUME = "finished hours are kept in results/parts/; run the same command again to resume"


@dataclass
class SimulationOutcome:
    """What ``simulate`` wrote: the results ``table`` (read back from ``path``), per-scenario
    ``timing`` (s), hours ``computed`` and ``reused`` from earlier parts, the ``engine`` name."""

    table: pd.DataFrame
    path: Path
    timing: pd.DataFrame
    computed: int
    reused: int
    engine: str


@dataclass
class _Prepared:
    built: BuiltScene
    states: list[SkyState]
    phash: str
    plan: Any
    seconds: float   # hour states (sun, sky, weather)


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


_WORKER_PLANS: dict[tuple[str, str], Any] = {}


def trace_job(job: TraceJob) -> pd.DataFrame:
    """Trace one job and write its part file atomically (runs in a thread or a Dask worker)."""
    plan = job.plan
    if plan is None:   # a worker process of an in-memory engine: prepare once per scenario
        key = (job.scenario.name, job.phash)
        if key not in _WORKER_PLANS:
            _WORKER_PLANS.clear()
            _WORKER_PLANS[key] = prepare_scenario(job.project, job.scenario, job.engine,
                                                  None, lambda _m: None).plan
        plan = _WORKER_PLANS[key]
    frames = []
    if len(job.states) == 1:
        results = engine_trace(job.engine, plan, job.scenario, job.states, job.grids[0])
    else:   # each grid at the hours it is traced at, in one batch
        results = [{} for _ in job.states]
        for g in dict.fromkeys(g for gs in job.grids for g in gs):
            at = [i for i, gs in enumerate(job.grids) if g in gs]
            got = engine_trace(job.engine, plan, job.scenario, [job.states[i] for i in at], [g])
            for i, res in zip(at, got, strict=True):
                results[i].update(res)
    for st, res, part in zip(job.states, results, job.parts, strict=True):
        df = hour_rows(job.project, job.scenario, st, job.scene, res, job.engine.name,
                       job.phash)
        write_part(part, df)
        frames.append(df)
    return pd.concat(frames, ignore_index=True)


def _district_chunks(project: Project) -> bool:
    return project.district is not None and project.district.buildings is not None


def task_chunks(project: Project, grids: list[str]) -> list[list[str]]:
    """The grids of one hour split into tasks: one per façade chunk for an inventory project
    with buildings (grids ``facades_000`` …), else all grids in one task."""
    if _district_chunks(project):
        return [[g] for g in grids]
    return [grids]


def resolve_engine(project: Project, engine: str | Engine = "auto") -> Engine:
    """The engine to run: an instance as given, or by name (``auto`` → the project's
    ``engine.name``, itself ``auto`` → Radiance when found, else NumPy)."""
    if isinstance(engine, Engine):
        return engine
    if engine != "auto":
        return get_engine(engine)
    return get_engine(project.engine.name, source=str(project.source))


def prepare_scenario(project: Project, sc: Scenario, engine: Engine,
                     hours: list[str] | None = None, echo: Callable[[str], None] = print
                     ) -> _Prepared:
    """A scenario's scene, hour states, parameter hash and the engine's plan."""
    t0 = time.perf_counter()
    states = hour_states(project, sc, hours)
    seconds = time.perf_counter() - t0
    built = built_scene(project, sc)
    if not engine.uses_build_folder:   # a build folder's notes are printed when it is built
        echo_notes(sc.name, built.notes, echo)
    scene = built.scene
    if scene.instances and not engine.instancing:
        extra = scene.instanced_triangles()
        echo(f"  {sc.name}: the {engine.name} engine has no instancing — {len(scene.instances)} "
             f"crowns expanded to {extra} triangles (~{extra * 9 * 8 / 2**20:.0f} MiB of "
             f"vertices, vs {scene.n_triangles} stored for Radiance)")
    folder = ensure_built(project, sc, echo) if engine.uses_build_folder else None
    plan = engine.prepare(built.scene, states, effective_project(project, sc).engine, built.ab,
                          folder)
    return _Prepared(built, states, project.params_hash(sc), plan, seconds)


def simulate_project(project: Project, engine: str | Engine = "auto",
                     scenarios: list[str] | None = None, hours: list[str] | None = None,
                     workers: int | None = None, dry_run: bool = False,
                     echo: Callable[[str], None] = print, progress: bool = True,
                     resume: bool = True, grids: list[str] | None = None,
                     executor: Callable[[Callable, list], Any] | None = None
                     ) -> SimulationOutcome | None:
    """Trace every selected scenario × hour and write ``results/illuminance.csv``.

    ``executor(fn, jobs)``: yields ``fn(job)`` for every :class:`TraceJob` as they complete
    (e.g. on Dask, :func:`radtree.sweep.scheduler.map_jobs`); default a thread pool of
    ``workers``. Either way finished parts are kept and reused on the next run."""
    eng = resolve_engine(project, engine)
    chosen = selected(project, scenarios)
    workers = workers or project.engine.workers
    parts_dir = project.results_dir / "parts"
    timing: dict[str, dict[str, float]] = {}
    prepared: dict[str, _Prepared] = {}
    tasks: list[tuple[Scenario, SkyState]] = []
    traced_here = project
    if not eng.uses_build_folder and executor is None:
        # an in-process engine's threads per hour: the cores shared out over the hours traced
        # at once (its numbers do not depend on them; 2 hours × 1 thread take ~20 % less CPU
        # and wall time than 2 × 2 on 2 cores)
        at_once = max(1, min(workers, len(chosen) * len(hours or project.site.hours)))
        traced_here = with_threads(project, max(1, usable_cores() // at_once))
    for sc in chosen:
        prep = prepare_scenario(traced_here, sc, eng, hours, echo)
        prepared[sc.name] = prep
        timing[sc.name] = {"preparation_s": prep.seconds,
                           "geometry_s": prep.built.geometry_seconds, "tracing_s": 0.0}
        tasks.extend((sc, st) for st in prep.states)
    check_memory(project, [p.built.triangles for p in prepared.values()], max(1, workers))
    if dry_run:
        for sc, st in tasks:
            for line in eng.commands(prepared[sc.name].plan, st.label):
                echo(f"{sc.name}: {line}" if not eng.uses_build_folder else line)
        return None

    make_folder(parts_dir)
    lock = threading.Lock()
    frames: list[pd.DataFrame] = []
    # an in-process engine traces a scenario's hours in one job, each grid at all the hours
    # it is traced at in the same batches (:meth:`Engine.trace_many`; each grid draws from its
    # own stream): a grid's numbers are those of pipeline.trace.trace_hours over the same
    # hours, and a resumed run's those of a fresh one (the groups do not depend on what is
    # already done)
    groups: dict[tuple, list[tuple[SkyState, Path, list[str]]]] = {}
    for sc, st in tasks:
        prep = prepared[sc.name]
        use = hour_grids(project, st.time, list(prep.built.scene.grids), grids, sc)
        for chunk in task_chunks(project, use):
            tag = f"_{chunk[0]}" if len(chunk) == 1 and project.district is not None else ""
            part = parts_dir / f"{sc.name}_{st.label}{tag}_{eng.name}_{prep.phash}.csv"
            key = (sc.name, tuple(chunk) if _district_chunks(project) else (),
                   "" if not eng.uses_build_folder else st.label)
            groups.setdefault(key, []).append((st, part, chunk))
    todo: list[TraceJob] = []
    reused = 0
    by_name = {sc.name: sc for sc in chosen}
    for (name, *_), members in groups.items():
        sc, prep = by_name[name], prepared[name]
        done = []
        for st, part, _ in members:
            rows, why = check_part(part, sc.name, st.time, prep.phash) if resume and \
                part.exists() else (None, "")
            if why:
                echo(f"  results/parts/{part.name} {why}: recomputing it")
            done.append(rows)
        if all(rows is not None for rows in done):
            frames.extend(done)
            reused += len(done)
            continue
        union = dict.fromkeys(g for _, _, chunk in members for g in chunk)
        sub = Scene([], {}, {g: prep.built.scene.grids[g] for g in union})
        todo.append(TraceJob(eng, prep.plan, project, sc, [m[0] for m in members],
                             [m[2] for m in members], sub, prep.phash, [m[1] for m in members]))

    def work(job: TraceJob) -> pd.DataFrame:
        t = time.perf_counter()
        df = trace_job(job)
        with lock:
            timing[job.scenario.name]["tracing_s"] += time.perf_counter() - t
        return df

    # most sensors first (the dense map's hour, the crowns' realisations after), so the
    # workers do not end on one long task; the table's order does not depend on it
    todo.sort(key=lambda j: -len(j.states) * sum(len(g.points) for g in j.scene.grids.values()))
    if todo:
        bar = progress_bar(None, f"simulate ({eng.name})", progress,
                           total=sum(len(j.states) for j in todo), unit="hour")
        try:
            if executor is not None:
                light = [replace(j, plan=None) if not eng.uses_build_folder else j for j in todo]
                for df in executor(trace_job, light):
                    frames.append(df)
                    if bar is not None:
                        bar.update(df["time"].nunique())
            else:
                with ThreadPoolExecutor(max_workers=max(1, workers)) as pool:
                    futures = {pool.submit(work, item): item for item in todo}
                    try:
                        for fut in as_completed(futures):
                            frames.append(fut.result())
                            if bar is not None:
                                bar.update(len(futures[fut].states))
                    except BaseException:
                        for f in futures:
                            f.cancel()
                        raise
        finally:
            if bar is not None:
                bar.close()
    table = pd.concat(frames, ignore_index=True)
    parents = list(dict.fromkeys(parent_name(sc.name) for sc in chosen))
    table, per_realisation = merge_realisations(
        table, {p: project.params_hash(project.scenario(p)) for p in parents})
    if per_realisation is not None:
        merge_write(project.results_dir / "realisations.csv", per_realisation, parents)
    table = in_column_order(table, [s.name for s in project.scenarios])
    impact = _tree_impact(project, eng, chosen, prepared, echo, grids,
                          {j.scenario.name for j in todo})
    out = results_path(project)
    tdf = _timing_table(timing, eng.name)
    with folder_lock(project.results_dir, "radtree simulate", wait=True, name=PUBLISH_NAME,
                     echo=echo):
        merge_write(out, table, parents)   # table, timing and manifest: one reader sees all
        _write_direct_sun(project, chosen, prepared)
        if project.district is not None and project.district.buildings is not None:
            from radtree.pipeline.district import write_facades_geojson

            write_facades_geojson(project, pd.read_csv(out, dtype={"facade": str,
                                                                   "building": str}))
        if impact is not None:
            from radtree.pipeline.tree_impact import write_tree_impact

            echo(f"  tree impact: {write_tree_impact(project, impact)}")
        _merge_timing(project.results_dir / "timing.csv", tdf)
        write_text(project.results_dir / "manifest.json", json.dumps(
            manifest(project, extra={"engine": eng.name, "scenarios": [s.name for s in chosen],
                                     "weather": _weather(project, prepared)}),
            indent=2, default=str))
    return SimulationOutcome(pd.read_csv(out), out, tdf, sum(len(j.parts) for j in todo),
                             reused, eng.name)


def _weather(project: Project, prepared: dict[str, _Prepared]) -> dict[str, Any]:
    """The manifest's weather record: this run's scenarios' hour states, and the earlier
    runs' record of the scenarios the results table still holds."""
    old: dict[str, Any] = {}
    path = project.results_dir / "manifest.json"
    if path.is_file():
        try:
            old = json.loads(path.read_text(encoding="utf-8")).get("weather") or {}
        except (OSError, ValueError):
            old = {}
    states: dict[str, list[SkyState]] = {}
    for name, prep in prepared.items():
        states.setdefault(parent_name(name), prep.states)
    return {**old, **weather_record(project, states)}


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


def _timing_table(timing: dict[str, dict[str, float]], engine: str) -> pd.DataFrame:
    """Seconds per scenario (realisations summed into their scenario)."""
    summed: dict[str, dict[str, float]] = {}
    for name, v in timing.items():
        acc = summed.setdefault(parent_name(name), dict.fromkeys(v, 0.0))
        for k, x in v.items():
            acc[k] += x
    return pd.DataFrame([{"scenario": k, "engine": engine, **v} for k, v in summed.items()])


def _merge_timing(out: Path, tdf: pd.DataFrame) -> None:
    if out.exists():
        old = pd.read_csv(out)
        old = old[~old["scenario"].astype(str).isin(tdf["scenario"].astype(str))]
        tdf = pd.concat([old, tdf], ignore_index=True)
    with atomic_path(out) as tmp:
        tdf.to_csv(tmp, index=False)


def _tree_impact(project: Project, eng: Engine, chosen: list[Scenario],
                 prepared: dict[str, _Prepared], echo: Callable[[str], None],
                 grids: list[str] | None, traced: set[str]) -> pd.DataFrame | None:
    """The tree-impact table (:mod:`radtree.pipeline.tree_impact`) of the chosen scenarios,
    unless every one of them was reused from earlier parts and the table is there."""
    from radtree.pipeline.tree_impact import tree_impact, tree_impact_path

    if not traced and tree_impact_path(project).exists():
        return None
    return tree_impact(project, eng, chosen,
                       {n: (p.built, p.states) for n, p in prepared.items()}, echo, grids)


def _write_direct_sun(project: Project, chosen: list[Scenario],
                      prepared: dict[str, _Prepared]) -> None:
    """``results/direct_sun.csv``: whether the sun beam reaches each sensor at each hour, per
    crown realisation, for the perforated scenarios (:mod:`radtree.pipeline.sunreach`)."""
    from radtree.pipeline.sunreach import direct_sun_rows

    rows = [direct_sun_rows(sc.name, prepared[sc.name].built.scene, prepared[sc.name].states)
            for sc in chosen if sc.model == "perforated"
            and "facade" in prepared[sc.name].built.scene.grids]
    if rows:
        table = pd.concat(rows, ignore_index=True)
        merge_write(project.results_dir / "direct_sun.csv", table,
                    list(dict.fromkeys(table["scenario"].astype(str))))
