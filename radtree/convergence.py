"""Ambient-bounce convergence: façade sensor means over increasing ``-ab`` (and ``-ad``).

Diffusely transmitting slat layers pass light to a sensor only through ambient bounces, so the
study's ``-ab 3`` may be far from converged. This runs each scenario's façade grid (one hour
by default, the first project hour) for a ladder of ``-ab`` values and reports the relative
change per step.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from radtree.config import Project, Scenario, effective_project
from radtree.engines.base import Engine
from radtree.fileio import atomic_path
from radtree.pipeline.assemble import BuiltScene, make_scene
from radtree.pipeline.build import ensure_built
from radtree.pipeline.executor import ThreadExecutor
from radtree.pipeline.jobs import resolve_engine
from radtree.pipeline.options import RunOptions
from radtree.pipeline.realisations import is_later_realisation, parent_name, selected
from radtree.pipeline.trace import trace_ab_ladder

log = logging.getLogger(__name__)

AB_LADDER = (1, 2, 3, 4, 6, 8)


@dataclass(frozen=True)
class _Step:
    """One row of the table: a scenario-hour at one ``-ab`` (``name``: the parent scenario)."""

    sc: Scenario
    name: str
    built: BuiltScene
    hour: str
    ab: int
    ad: int
    phash: str


@dataclass(frozen=True)
class _Trace:
    """One engine run: a scenario-hour at some ``-ab`` values (``folder``: its build folder)."""

    built: BuiltScene
    sc: Scenario
    hour: str
    abs_: tuple[int, ...]
    folder: Path | None


def convergence_table(project: Project, *, options: RunOptions | None = None,
                      ab_values: tuple[int, ...] = AB_LADDER,
                      previous: pd.DataFrame | None = None) -> pd.DataFrame:
    """One row per scenario × hour × -ab: façade mean lux and relative change from the step before.
    A scenario with several crown realisations is checked on its first one. ``options``:
    ``engine`` as ``simulate`` (None or ``auto`` → the project's ``engine.name``; the
    scenario's ``engine.*`` switches apply), ``scenarios``, ``hours`` (default the first
    project hour), ``workers``.

    ``previous`` (an earlier table, e.g. ``results/convergence.csv``): its rows with the same
    scenario, hour, ``-ab``, ``-ad``, engine and parameter hash are reused, not traced again.
    The remaining runs go ``workers`` at a time (default ``engine.workers``) for an engine that
    runs external programs (Radiance: one ``rtrace`` per ``-ab``), one at a time for an
    in-process engine; an engine with ``ladder_in_one_trace`` (NumPy) traces each scenario-hour
    once to the largest ``-ab`` and reads every step from the bounce orders of the same paths
    (so the steps' changes carry correlated noise, not the noise of independent runs)."""
    options = options or RunOptions()
    eng = resolve_engine(project, options.engine)
    done = _known(previous)
    steps, traces = _ladder(project, eng, options, ab_values, done)
    n = max(1, options.workers or project.engine.workers) if eng.uses_build_folder else 1
    traced: dict[tuple[str, str, int], float] = {}

    def run(t: _Trace) -> dict[tuple[str, str, int], float]:
        by_ab = trace_ab_ladder(project, t.sc, eng, t.hour, list(t.abs_), ["facade"], t.built,
                                t.folder)
        return {(t.sc.name, t.hour, ab): float(r["facade"].lux.mean()) for ab, r in by_ab.items()}

    for finished in ThreadExecutor(n).run(run, traces, label="ladder"):
        traced.update(finished.value())
    means = [done[key][1] if (key := (s.name, s.hour, s.ab, s.ad, eng.name, s.phash)) in done
             else traced[(s.sc.name, s.hour, s.ab)] for s in steps]
    return _rows(steps, means, eng)


def _ladder(project: Project, eng: Engine, options: RunOptions, ab_values: tuple[int, ...],
            done: dict[tuple, tuple[str, float]]) -> tuple[list[_Step], list[_Trace]]:
    """Every row of the table, and the engine runs for the rows not in ``done``."""
    steps: list[_Step] = []
    traces: list[_Trace] = []
    for sc in selected(project, list(options.scenarios) if options.scenarios else None):
        if is_later_realisation(sc.name):
            continue
        built = make_scene(project, sc, dense_grid=False)
        # a build-folder engine (Radiance) traces the ladder in the scenario's build folder:
        # one octree for every -ab (an option of rtrace, not of the scene), not one each
        folder = ensure_built(project, sc) if eng.uses_build_folder else None
        ad = effective_project(project, sc).engine.radiance.ad
        phash = project.params_hash(sc)
        for hour in options.hours or [project.site.hours[0]]:
            todo = []
            for ab in sorted(set(ab_values) | {built.ab}):   # always the -ab simulate uses
                steps.append(_Step(sc, parent_name(sc.name), built, hour, ab, ad, phash))
                if (parent_name(sc.name), hour, ab, ad, eng.name, phash) not in done:
                    todo.append(ab)
            # an engine that tallies bounce orders traces the ladder once, else one run per -ab
            groups = [todo] if eng.ladder_in_one_trace else [[ab] for ab in todo]
            traces += [_Trace(built, sc, hour, tuple(g), folder) for g in groups if g]
    return steps, traces


def _rows(steps: list[_Step], means: list[float], eng: Engine) -> pd.DataFrame:
    """The table; each row logged as it is made."""
    rows = []
    prev: dict[tuple[str, str], float] = {}
    for s, mean in zip(steps, means, strict=True):
        before = prev.get((s.name, s.hour))
        change = (mean - before) / before if before else float("nan")
        rows.append({"scenario": s.name, "model": s.sc.model, "time": s.hour, "ab": s.ab,
                     "ad": s.ad, "facade_mean_lux": round(mean, 1),
                     "change": round(change, 4) if before else None,
                     "model_recommended_ab": s.built.ab, "engine": eng.name,
                     "params_hash": s.phash})
        log.info("  %s %s -ab %d: %.0f lx%s", s.name, s.hour, s.ab, mean,
                 f" ({change:+.1%})" if before else "")
        prev[(s.name, s.hour)] = mean
    return pd.DataFrame(rows)


def read_convergence(project: Project) -> pd.DataFrame | None:
    """``results/convergence.csv`` as written by :func:`write_convergence`, or None."""
    path = project.results_dir / "convergence.csv"
    try:
        return pd.read_csv(path, dtype={"scenario": str, "time": str, "params_hash": str})
    except (OSError, ValueError):
        return None


def _known(previous: pd.DataFrame | None) -> dict[tuple, tuple[str, float]]:
    """(scenario, hour, ab, ad, engine, params_hash) → (time, façade mean) of an earlier
    table (rows without engine or parameter hash — older tables — are not reused)."""
    cols = {"scenario", "time", "ab", "ad", "engine", "params_hash", "facade_mean_lux"}
    if previous is None or not cols <= set(previous.columns):
        return {}
    return {(str(r.scenario), str(r.time), int(r.ab), int(r.ad), str(r.engine),
             str(r.params_hash)): (str(r.time), float(r.facade_mean_lux))
            for r in previous.dropna(subset=sorted(cols)).itertuples()}


def write_convergence(project: Project, table: pd.DataFrame) -> Path:
    """Write ``results/convergence.csv`` (read by the report) atomically; return its path."""
    out = project.results_dir / "convergence.csv"
    with atomic_path(out) as tmp:
        table.to_csv(tmp, index=False)
    return out
