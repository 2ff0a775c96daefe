"""Ambient-bounce convergence: façade sensor means over increasing ``-ab`` (and ``-ad``).

Diffusely transmitting slat layers pass light to a sensor only through ambient bounces, so the
study's ``-ab 3`` may be far from converged. This runs each scenario's façade grid (one hour
by default, the first project hour) for a ladder of ``-ab`` values and reports the relative
change per step.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pandas as pd

from radtree.config import Project, effective_project
from radtree.engines.base import Engine
from radtree.fileio import atomic_path
from radtree.pipeline.assemble import make_scene
from radtree.pipeline.realisations import is_later_realisation, parent_name, selected
from radtree.pipeline.simulate import resolve_engine
from radtree.pipeline.trace import trace_hours

AB_LADDER = (1, 2, 3, 4, 6, 8)


def convergence_table(project: Project, scenarios: list[str] | None = None,
                      hours: list[str] | None = None, ab_values: tuple[int, ...] = AB_LADDER,
                      echo: Callable[[str], None] = print, engine: str | Engine = "auto"
                      ) -> pd.DataFrame:
    """One row per scenario × hour × -ab: façade mean lux and relative change from the step before.
    A scenario with several crown realisations is checked on its first one. ``engine``: as
    ``simulate`` (``auto`` → the project's ``engine.name``); the scenario's ``engine.*`` switches
    apply."""
    eng = resolve_engine(project, engine)
    rows = []
    for sc in selected(project, scenarios):
        if is_later_realisation(sc.name):
            continue
        name = parent_name(sc.name)
        built = make_scene(project, sc, dense_grid=False)
        ad = effective_project(project, sc).engine.ad
        for hour in hours or [project.site.hours[0]]:
            prev = None
            for ab in sorted(set(ab_values) | {built.ab}):   # always the -ab simulate uses
                traced = trace_hours(project, sc, eng, [hour], ["facade"], ab=ab, built=built)
                st, lux = traced.states[0], traced.results[0]["facade"].lux
                mean = float(lux.mean())
                change = (mean - prev) / prev if prev else float("nan")
                rows.append({"scenario": name, "model": sc.model, "time": st.time, "ab": ab,
                             "ad": ad, "facade_mean_lux": round(mean, 1),
                             "change": round(change, 4) if prev else None,
                             "model_recommended_ab": built.ab})
                echo(f"  {name} {st.time} -ab {ab}: {mean:.0f} lx"
                     + (f" ({change:+.1%})" if prev else ""))
                prev = mean
    return pd.DataFrame(rows)


def write_convergence(project: Project, table: pd.DataFrame) -> Path:
    """Write ``results/convergence.csv`` (read by the report) atomically; return its path."""
    out = project.results_dir / "convergence.csv"
    with atomic_path(out) as tmp:
        table.to_csv(tmp, index=False)
    return out
