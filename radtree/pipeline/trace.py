"""A scenario traced in memory: the rows ``simulate`` would write, nothing written to disk.

Calibration, the permeability scan, the diagnosis and the ``-ab`` convergence check trace
through here, on any engine, with the same scene, the same ``-ab`` rule and the same calculated
ground terms as :func:`radtree.pipeline.simulate.simulate_project`.
"""

from __future__ import annotations

import math
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from radtree.config import Project, Scenario, effective_project
from radtree.engines.base import Engine, GridResult
from radtree.engines.registry import engine_named
from radtree.light.hours import hour_states
from radtree.light.sky import SkyState
from radtree.pipeline.assemble import BuiltScene, make_scene, scene_ab
from radtree.pipeline.results import hour_rows


@dataclass
class TracedHours:
    """Engine output per hour (``results[i]`` for ``states[i]``), before the ground terms."""

    built: BuiltScene
    states: list[SkyState]
    results: list[dict[str, GridResult]]
    ab: int


def _engine(engine: str | Engine | None) -> Engine:
    """An engine instance, by name, or the seeded engine (common random numbers) for None."""
    return engine if isinstance(engine, Engine) else engine_named(engine)


def trace_hours(project: Project, sc: Scenario, engine: str | Engine | None = None, *,
                hours: list[str] | None = None, grids: list[str] | None = None,
                rays: int | None = None, seed: int | None = None, ab: int | None = None,
                built: BuiltScene | None = None, folder: Path | None = None) -> TracedHours:
    """Trace the scenario's hours (default the project's) with ``engine`` (a name, an instance,
    or None for the seeded engine) on ``grids`` (default every grid of
    the scene without the dense map). ``rays``/``seed`` override ``engine.rays``/``engine.seed``
    (seeded engines); ``ab`` overrides the scene's ``-ab`` rule; ``built`` reuses a scene made
    by :func:`make_scene` (its ``-ab`` is taken afresh from the switched project); ``folder``:
    the scenario's build folder for an engine that traces one (its octrees are made once and
    kept there), else a temporary folder."""
    eng = _engine(engine)
    built = built or make_scene(project, sc, dense_grid=False)
    proj = effective_project(project, sc)
    use_ab = ab if ab is not None else scene_ab(
        proj, None if built.tree is None else built.tree.recommended_ab)
    params = proj.engine.changed(rays=int(rays or proj.engine.numpy.rays),
                                 seed=int(proj.engine.seed if seed is None else seed))
    states = hour_states(project, sc, hours)
    with tempfile.TemporaryDirectory(prefix="radtree-trace-") as tmp:
        plan = eng.prepare(built.scene, states, params, use_ab, folder or Path(tmp))
        results = eng.trace_many(plan, [st.label for st in states], grids)
    return TracedHours(built, states, results, use_ab)


def trace_ab_ladder(project: Project, sc: Scenario, engine: str | Engine | None, hour: str,
                    ab_values: list[int], grids: list[str] | None = None,
                    built: BuiltScene | None = None, folder: Path | None = None
                    ) -> dict[int, dict[str, GridResult]]:
    """Hour ``hour`` of the scenario at every ``-ab`` of ``ab_values`` (the engine's
    :meth:`~radtree.engines.base.Engine.trace_ab_ladder`): lux per ``-ab`` and grid. ``built``/``folder`` as :func:`trace_hours`."""
    eng = _engine(engine)
    built = built or make_scene(project, sc, dense_grid=False)
    params = effective_project(project, sc).engine
    state = hour_states(project, sc, [hour])[0]
    with tempfile.TemporaryDirectory(prefix="radtree-trace-") as tmp:
        return eng.trace_ab_ladder(built.scene, state, params, sorted(set(ab_values)),
                                   folder or Path(tmp), grids)


def trace_scenario(project: Project, sc: Scenario, engine: str | Engine | None = None,
                   rays: int | None = None, seed: int | None = None,
                   grids: list[str] | None = None, hours: list[str] | None = None
                   ) -> pd.DataFrame:
    """Every hour of one scenario in memory: the rows ``simulate`` would write (calculated
    ground terms included)."""
    eng = _engine(engine)
    traced = trace_hours(project, sc, eng, hours=hours, grids=grids, rays=rays, seed=seed)
    phash = project.params_hash(sc)
    return pd.concat([hour_rows(project, sc, st, traced.built.scene, res, eng.name, phash)
                      for st, res in zip(traced.states, traced.results)], ignore_index=True)


def facade_total(project: Project, sc: Scenario, engine: str | Engine | None = None,
                 rays: int | None = None, seed: int | None = None,
                 grid: str = "facade") -> tuple[float, float]:
    """Σ over the project's hours of the façade grid's traced mean (lux) and its Monte Carlo
    standard error (0 when the engine gives none) — the sums a global permeability divides."""
    traced = trace_hours(project, sc, engine, grids=[grid], rays=rays, seed=seed)
    total, var = 0.0, 0.0
    for res in traced.results:
        g = res[grid]
        total += float(g.lux.mean())
        if g.stderr is not None:
            var += float(np.sum(g.stderr ** 2)) / len(g.lux) ** 2
    return total, math.sqrt(var)
