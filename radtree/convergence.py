"""Ambient-bounce convergence: façade sensor means over increasing ``-ab`` (and ``-ad``).

Diffusely transmitting slat layers pass light to a sensor only through ambient bounces, so the
study's ``-ab 3`` may be far from converged. This runs each scenario's façade grid (one hour
by default, the first project hour) for a ladder of ``-ab`` values and reports the relative
change per step.
"""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pandas as pd

from radtree.config import Project, effective_project
from radtree.engines.base import Engine
from radtree.fileio import atomic_path
from radtree.pipeline.assemble import make_scene
from radtree.pipeline.build import ensure_built
from radtree.pipeline.realisations import is_later_realisation, parent_name, selected
from radtree.pipeline.simulate import resolve_engine
from radtree.pipeline.trace import trace_ab_ladder

AB_LADDER = (1, 2, 3, 4, 6, 8)


def convergence_table(project: Project, scenarios: list[str] | None = None,
                      hours: list[str] | None = None, ab_values: tuple[int, ...] = AB_LADDER,
                      echo: Callable[[str], None] = print, engine: str | Engine = "auto",
                      previous: pd.DataFrame | None = None, workers: int | None = None
                      ) -> pd.DataFrame:
    """One row per scenario × hour × -ab: façade mean lux and relative change from the step before.
    A scenario with several crown realisations is checked on its first one. ``engine``: as
    ``simulate`` (``auto`` → the project's ``engine.name``); the scenario's ``engine.*`` switches
    apply.

    ``previous`` (an earlier table, e.g. ``results/convergence.csv``): its rows with the same
    scenario, hour, ``-ab``, ``-ad``, engine and parameter hash are reused, not traced again.
    The remaining runs go ``workers`` at a time (default ``engine.workers``) for an engine that
    runs external programs (Radiance: one ``rtrace`` per ``-ab``), one at a time for an
    in-process engine; an engine with ``ladder_in_one_trace`` (NumPy) traces each scenario-hour
    once to the largest ``-ab`` and reads every step from the bounce orders of the same paths
    (so the steps' changes carry correlated noise, not the noise of independent runs)."""
    eng = resolve_engine(project, engine)
    done = _known(previous)
    jobs: list[tuple] = []       # (scenario, name, built, hour, ab, ad, phash)
    tasks: list[tuple] = []      # (built, scenario, hour, ab values to trace, folder)
    for sc in selected(project, scenarios):
        if is_later_realisation(sc.name):
            continue
        built = make_scene(project, sc, dense_grid=False)
        # a build-folder engine (Radiance) traces the ladder in the scenario's build folder:
        # one octree for every -ab (an option of rtrace, not of the scene), not one each
        folder = ensure_built(project, sc, echo) if eng.uses_build_folder else None
        ad = effective_project(project, sc).engine.radiance.ad
        phash = project.params_hash(sc)
        for hour in hours or [project.site.hours[0]]:
            todo = []
            for ab in sorted(set(ab_values) | {built.ab}):   # always the -ab simulate uses
                jobs.append((sc, parent_name(sc.name), built, hour, ab, ad, phash))
                if (parent_name(sc.name), hour, ab, ad, eng.name, phash) not in done:
                    todo.append(ab)
            # an engine that tallies bounce orders traces the ladder once, else one run per -ab
            groups = [todo] if eng.ladder_in_one_trace else [[ab] for ab in todo]
            tasks += [(built, sc, hour, g, folder) for g in groups if g]

    def run(task: tuple) -> dict[tuple[str, str, int], float]:
        built, sc, hour, abs_, folder = task
        by_ab = trace_ab_ladder(project, sc, eng, hour, abs_, ["facade"], built, folder)
        return {(sc.name, hour, ab): float(r["facade"].lux.mean()) for ab, r in by_ab.items()}

    n = max(1, workers or project.engine.workers) if eng.uses_build_folder else 1
    traced: dict[tuple[str, str, int], float] = {}
    with ThreadPoolExecutor(max_workers=n) as pool:
        for got in pool.map(run, tasks):
            traced.update(got)
    means = [done[(name, hour, ab, ad, eng.name, phash)][1]
             if (name, hour, ab, ad, eng.name, phash) in done else traced[(sc.name, hour, ab)]
             for sc, name, _, hour, ab, ad, phash in jobs]
    rows = []
    prev: dict[tuple[str, str], float] = {}
    for (sc, name, built, hour, ab, ad, phash), mean in zip(jobs, means, strict=True):
        before = prev.get((name, hour))
        change = (mean - before) / before if before else float("nan")
        rows.append({"scenario": name, "model": sc.model, "time": hour, "ab": ab,
                     "ad": ad, "facade_mean_lux": round(mean, 1),
                     "change": round(change, 4) if before else None,
                     "model_recommended_ab": built.ab, "engine": eng.name,
                     "params_hash": phash})
        echo(f"  {name} {hour} -ab {ab}: {mean:.0f} lx"
             + (f" ({change:+.1%})" if before else ""))
        prev[(name, hour)] = mean
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
