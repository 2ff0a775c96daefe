"""The report's 3-D view section and, for a project built on a Honeybee model, its results in
honeybee-radiance's layout (``report/honeybee/``) with a per-grid table.

``view3d_data`` writes ``report/view3d.html`` (:mod:`radtree.report.view3d`); ``honeybee_data``
writes ``report/honeybee/<scenario>/<HHMM>/<grid>.res`` + ``grids_info.json`` and
``report/honeybee/model.hbjson`` (:func:`radtree.export.honeybee.write_results`), after
``radtree annual`` also ``report/honeybee/annual/<variant>/`` (``.ill`` files,
:func:`~radtree.export.honeybee.write_annual_results`), and returns
the mean / min / max lux per scenario, grid and hour (whole numbers).
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import pandas as pd

from radtree.config import Project

log = logging.getLogger(__name__)


def view3d_data(project: Project, table: pd.DataFrame, out: Path) -> dict[str, Any] | None:
    from radtree.report.view3d import write_view

    data = write_view(project, table, out)
    if data is None:
        log.info("  3-D view skipped: no simulated scenario has a build folder (`radtree build`)")
    else:   # out is the folder renamed into place
        log.info("  3-D view: %s triangles, %s sensors → %s", data["triangles"], data["sensors"],
                 project.report_dir / data["file"])
    return data


def grid_rows(table: pd.DataFrame) -> list[dict[str, str]]:
    g = table.groupby(["scenario", "grid", "time"], sort=False)["lux"]
    stats = g.agg(["count", "mean", "min", "max"]).reset_index()
    return [{"scenario": str(r.scenario), "grid": str(r.grid), "time": str(r.time),
             "n": str(int(r["count"])), "mean": f"{r['mean']:.0f}", "min": f"{r['min']:.0f}",
             "max": f"{r['max']:.0f}"} for _, r in stats.iterrows()]


def honeybee_data(project: Project, table: pd.DataFrame, out: Path) -> dict[str, Any] | None:
    if project.honeybee is None:
        return None
    from radtree.export.honeybee import write_annual_results, write_results
    from radtree.site.honeybee_model import honeybee_parts

    parts = honeybee_parts(project.honeybee)
    folders = write_results(table, parts.model, out / "honeybee")
    hourly = project.results_dir / "annual" / "hourly.npz"
    if hourly.exists():
        folders += write_annual_results(hourly, parts.model, out / "honeybee" / "annual")
    log.info("  Honeybee results: %d folders in honeybee-radiance's layout → %s", len(folders),
             project.report_dir / "honeybee")
    grids = [g.identifier for g in parts.model.properties.radiance.sensor_grids]
    return {"model": project.honeybee.model.name, "grids": grids,
            "folders": [str(f.relative_to(out)) for f in folders], "notes": parts.notes,
            "rows": grid_rows(table)}
