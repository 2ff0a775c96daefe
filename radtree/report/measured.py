"""The project's measurements against the simulated results, for the report
(:func:`radtree.report.data.collect`): the façade mean per measured hour and the statistics
of every scenario (:func:`radtree.stats.compare`), and the per-row daily means (lux)."""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np
import pandas as pd

from radtree.config import Project
from radtree.errors import RadtreeError
from radtree.measurements import MeasuredShape, grid_mean, load_measured, load_measured_rows
from radtree.stats import (
    FACADE_GRID,
    Comparison,
    compare,
    row_hourly_between_models,
    row_hourly_means,
    row_means,
)

log = logging.getLogger(__name__)


@dataclass
class MeasuredComparison:
    """The measurements against the simulated results (all None without measurements)."""

    tidy: pd.DataFrame | None = None
    shape: MeasuredShape | None = None
    hourly: pd.DataFrame | None = None
    comparison: Comparison | None = None
    stats: pd.DataFrame | None = None
    times: list[str] | None = None


def compare_measured(project: Project, results: pd.DataFrame, reflection: dict[str, str],
                     order: list[str], notes: list[str]) -> MeasuredComparison:
    """The project's measurements read, their façade mean per hour, and the statistics of
    every scenario of ``order`` against them (:func:`radtree.stats.compare`, ``reflection``:
    each scenario's ground reflection label) in that order."""
    if project.measured is None:
        notes.append("the project names no measurements ([project] measured): simulated values "
                     "only, no statistics")
        return MeasuredComparison()
    rank = {n: i for i, n in enumerate(order)}
    tidy, shape = load_measured(project.measured)
    facade = results[results["grid"].astype(str) == FACADE_GRID].dropna(subset=["row"])
    per_row = facade.groupby(facade["row"].astype(str).str.lower())["sensor"].nunique()
    measured = grid_mean(tidy, per_row.to_dict() if "row" in tidy.columns else None)
    log.info("  comparing %d scenario(s) with %d measured hour(s)", len(order), len(measured))
    comparison = compare(results, tidy, reflection=reflection)
    notes.extend(comparison.notes)
    stats = comparison.stats.assign(_s=comparison.stats["scenario"].map(rank))
    stats = stats.sort_values("_s").drop(columns="_s").reset_index(drop=True)
    return MeasuredComparison(tidy, shape, measured, comparison, stats, list(measured["time"]))


def measured_rows_frame(project: Project, measured: pd.DataFrame | None,
                         notes: list[str]) -> pd.DataFrame | None:
    """The measured daily mean per sensor row: ``[project] measured_rows``, else derived from
    the hourly measured file when it has rows (with a note), else None."""
    if project.measured_rows is not None:
        return load_measured_rows(project.measured_rows)
    if measured is not None and "row" in measured.columns:
        rows = measured.assign(row=measured["row"].astype(str).str.lower())
        notes.append("per-row measured daily means derived from the hourly measured file "
                     "(mean over its hours)")
        return (rows.groupby("row", sort=False)["measured_lux"].mean()
                .rename("measured_mean_lux").reset_index())
    return None


def row_tables(project: Project, results: pd.DataFrame, measured: pd.DataFrame | None,
                measured_times: list[str] | None, order: list[str],
                notes: list[str]) -> tuple[pd.DataFrame | None, bool, pd.DataFrame | None]:
    """Per scenario and sensor row: simulated daily means against the measured ones (when
    there are), whether they were measured, and the rows' hourly values between models."""
    facade = results[results["grid"].astype(str) == FACADE_GRID]
    if facade.empty or facade["row"].dropna().empty:
        notes.append("the façade grid has no row labels: no per-row comparison")
        return None, False, None
    measured_rows = measured_rows_frame(project, measured, notes)
    rows = None
    if measured_rows is not None:
        try:
            rows = row_means(results, measured_rows, times=measured_times)
        except RadtreeError as exc:
            notes.append(f"per-row comparison with the measured daily means not possible: {exc}")
    with_measured = rows is not None
    if rows is None:
        per = row_hourly_means(results)
        rows = (per.groupby(["scenario", "row"], sort=True)
                .agg(model=("model", "first"), simulated_mean_lux=("lux", "mean"))
                .reset_index())
        se = per.groupby(["scenario", "row"], sort=True)["lux_stderr"].apply(
            lambda v: float(np.sqrt(np.sum(np.asarray(v, float) ** 2)) / len(v)))
        rows["simulated_stderr"] = se.to_numpy()
        rows["measured_mean_lux"] = math.nan
        rows["ratio"] = math.nan
        rows["difference_lux"] = math.nan
    rank = {n: i for i, n in enumerate(order)}
    row_rank = {"higher": 0, "intermediate": 1, "lower": 2}
    rows = rows.assign(_s=rows["scenario"].map(rank), _r=rows["row"].map(row_rank).fillna(9))
    rows = rows.sort_values(["_s", "_r", "row"]).drop(columns=["_s", "_r"])
    between = None
    if len(order) > 1:
        try:
            between = row_hourly_between_models(results, reference=order[0])
            between = between.assign(_s=between["scenario"].map(rank),
                                     _r=between["row"].map(row_rank).fillna(9))
            between = between.sort_values(["_s", "_r"]).drop(columns=["_s", "_r"])
        except RadtreeError as exc:
            notes.append(f"per-row hourly comparison between models not possible: {exc}")
    return rows.reset_index(drop=True), with_measured, between
