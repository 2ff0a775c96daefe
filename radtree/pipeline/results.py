"""The one results table: path, rows from engine output, validated read, atomic write (its
schema: :mod:`radtree.results_schema`, re-exported here).

Statistics, reports and diagnosis read only this table.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from radtree.config import Project, Scenario
from radtree.engines.base import GridResult
from radtree.errors import RadtreeError
from radtree.fileio import atomic_path
from radtree.light.ground import ground_terms
from radtree.light.sky import SkyState
from radtree.measurements import normalise_time
from radtree.results_schema import DTYPES, OPTIONAL_COLUMNS, REQUIRED_COLUMNS, RESULT_COLUMNS
from radtree.scene import Scene

__all__ = ["OPTIONAL_COLUMNS", "REQUIRED_COLUMNS", "RESULT_COLUMNS", "facade_means", "hour_rows",
           "in_column_order", "merge_write", "read_results", "read_table", "results_path"]


def results_path(project: Project) -> Path:
    """``PROJECT/results/illuminance.csv``."""
    return project.results_dir / "illuminance.csv"


def hour_rows(project: Project, sc: Scenario, st: SkyState, scene: Scene,
              res: dict[str, GridResult], engine: str, phash: str) -> pd.DataFrame:
    """The tidy rows of one traced hour: engine lux plus the calculated ground terms."""
    frames = []
    for gname, gr in res.items():
        grid = scene.grids[gname]
        extra = ground_terms(project, sc, st, grid)
        frames.append(pd.DataFrame({
            "scenario": sc.name, "model": sc.model, "datetime": st.datetime.isoformat(),
            "time": st.time, "grid": gname, "sensor": np.arange(len(grid)), "row": grid.rows,
            "x": grid.points[:, 0], "y": grid.points[:, 1], "z": grid.points[:, 2],
            "lux": gr.lux + extra,
            "lux_stderr": gr.stderr if gr.stderr is not None else np.nan,
            "engine": engine, "params_hash": phash,
            "lux_traced": gr.lux, "lux_reflected_calc": extra,
            "reflection": sc.reflection,
            **{k: list(v) for k, v in grid.labels.items()},
        }))
    return pd.concat(frames, ignore_index=True)


def in_column_order(table: pd.DataFrame, scenario_order: list[str]) -> pd.DataFrame:
    """Rows sorted by scenario (project order), time, grid, sensor; columns in schema order."""
    order = {s: i for i, s in enumerate(scenario_order)}
    table = table.sort_values(["scenario", "time", "grid", "sensor"],
                              key=lambda c: c.map(order) if c.name == "scenario" else c)
    head = RESULT_COLUMNS + [c for c in OPTIONAL_COLUMNS if c in table.columns]
    cols = head + [c for c in table.columns if c not in head]
    return table[cols].reset_index(drop=True)


def read_table(path: Path, hint: str = "") -> pd.DataFrame:
    """A results table read from ``path`` and checked (columns, clock times); RadtreeError
    naming the file otherwise. ``hint``: what to run when the file is missing or empty."""
    if not path.is_file():
        raise RadtreeError(f"no results: {hint + ' ' if hint else ''}({path} not found)")
    try:
        df = pd.read_csv(path, dtype=DTYPES)  # type: ignore[arg-type]
    except (OSError, ValueError) as exc:
        raise RadtreeError(f"{path}: cannot read the results table ({exc})") from exc
    missing = [c for c in REQUIRED_COLUMNS if c not in df.columns]
    if missing:
        raise RadtreeError(f"{path}: results table lacks column(s) {', '.join(missing)}")
    if df.empty:
        raise RadtreeError(f"{path}: results table is empty" + (f"; {hint}" if hint else ""))
    try:
        df["time"] = [normalise_time(str(t)) for t in df["time"]]
    except RadtreeError as exc:
        raise RadtreeError(f"{path}: {exc}") from None
    if "lux_stderr" not in df.columns:
        df["lux_stderr"] = np.nan
    return df


def read_results(project: Project) -> pd.DataFrame:
    """The project's results table, validated; RadtreeError if ``simulate`` has not run."""
    return read_table(results_path(project), f"run `radtree simulate {project.root}` first")


def merge_write(out: Path, table: pd.DataFrame, names: list[str]) -> None:
    """Replace the named scenarios' rows in the table at ``out`` (keep the others), atomically."""
    if out.exists():
        old = pd.read_csv(out, dtype=DTYPES)  # type: ignore[arg-type]
        old = old[~old["scenario"].astype(str).isin(names)]
        table = pd.concat([old, table], ignore_index=True) if len(old) else table
    with atomic_path(out) as tmp:
        table.to_csv(tmp, index=False)


def facade_means(table: pd.DataFrame, grid: str = "facade") -> pd.DataFrame:
    """Hourly mean lux of a grid's sensors: one row per scenario, one column per hour."""
    rows = table[table["grid"] == grid]
    return rows.groupby(["scenario", "time"], sort=False)["lux"].mean().unstack("time")
