"""Ambient-bounce convergence: façade sensor means over increasing ``-ab`` (and ``-ad``).

Diffusely transmitting slat layers pass light to a sensor only through ambient bounces, so the
study's ``-ab 3`` may be far from converged. This runs each scenario's façade grid (one hour
by default, the first project hour) for a ladder of ``-ab`` values and reports the relative
change per step.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import pandas as pd

from radtree.config import Project
from radtree.engines.radiance.engine import trace_hour
from radtree.light.hours import hour_states
from radtree.scenarios import is_later_realisation, make_scene, parent_name, selected

AB_LADDER = (1, 2, 3, 4, 6, 8)


def convergence_table(project: Project, scenarios: list[str] | None = None,
                      hours: list[str] | None = None, ab_values: tuple[int, ...] = AB_LADDER,
                      echo: Callable[[str], None] = print) -> pd.DataFrame:
    """One row per scenario × hour × -ab: façade mean lux and relative change from the step before.
    A scenario with several crown realisations is checked on its first one."""
    rows = []
    for sc in selected(project, scenarios):
        if is_later_realisation(sc.name):
            continue
        name = parent_name(sc.name)
        built = make_scene(project, sc, dense_grid=False)
        states = hour_states(project, sc, hours or [project.site.hours[0]])
        for st in states:
            prev = None
            for ab in sorted(set(ab_values) | {built.ab}):   # always the -ab simulate uses
                params = replace(project.engine, ab=ab)
                lux = trace_hour(built.scene, st, params, grids=["facade"], ab=ab)["facade"].lux
                mean = float(lux.mean())
                change = (mean - prev) / prev if prev else float("nan")
                rows.append({"scenario": name, "model": sc.model, "time": st.time, "ab": ab,
                             "ad": project.engine.ad, "facade_mean_lux": round(mean, 1),
                             "change": round(change, 4) if prev else None,
                             "model_recommended_ab": built.ab})
                echo(f"  {name} {st.time} -ab {ab}: {mean:.0f} lx"
                     + (f" ({change:+.1%})" if prev else ""))
                prev = mean
    return pd.DataFrame(rows)
