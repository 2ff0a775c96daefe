"""The measured side of a diagnosis: a measured file matched to the hours a project simulates.

:func:`load_measurements` reads any shape :func:`radtree.measurements.load_measured` knows
(grid mean per hour, per row, per sensor; lux or klux) and the per-row daily means, keeps the
measured hours that are among the project's ``site.hours`` and says which were left out.
Values in lux; times ``HH:MM`` local clock time.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from radtree.config import Project
from radtree.diagnose.identify import DEFAULT_NOISE
from radtree.errors import RadtreeError


@dataclass
class Measured:
    """The measured side of a diagnosis, restricted to hours the project simulates.

    ``hourly``: grid mean per hour of ``times`` (lx). ``rows_daily``: ``row, sensors,
    measured_mean_lux`` or None; ``rows_hourly``: ``time, row, measured_lux`` or None.
    ``left_out``: measured hours without a simulation counterpart (not in ``site.hours``);
    ``unmeasured``: project hours without a measurement.
    """

    times: tuple[str, ...]
    hourly: np.ndarray
    source: str
    units: str
    shape: str
    rows_daily: pd.DataFrame | None = None
    rows_hourly: pd.DataFrame | None = None
    left_out: list[str] = field(default_factory=list)
    unmeasured: list[str] = field(default_factory=list)
    #: sun altitude and azimuth (degrees) per value when ``times`` are not clock times (a
    #: campaign's observations, :mod:`.campaign_sim`); None: from the project's hours
    sun: tuple[np.ndarray, np.ndarray] | None = None
    #: relative noise (1 σ) and floor (lux) of the values: the identifiability's weights
    noise: float = DEFAULT_NOISE
    noise_lux: float = 0.0

    @property
    def mean(self) -> float:
        return float(np.mean(self.hourly))

    def notes(self) -> list[str]:
        out = []
        if self.left_out:
            out.append("measured hour(s) without a simulation counterpart (not in the "
                       f"project's site.hours), left out of the diagnosis: "
                       f"{', '.join(self.left_out)}")
        if self.unmeasured:
            out.append(f"project hour(s) without a measurement, not simulated: "
                       f"{', '.join(self.unmeasured)}")
        if self.rows_daily is not None and (self.left_out or self.unmeasured):
            out.append("the per-row daily means were measured over the whole day; they are "
                       f"compared with simulated means over the {len(self.times)} matched hours")
        return out


def load_measurements(project: Project, path: str | os.PathLike | None = None,
                      units: str | None = None, sensors_per_row: dict[str, int] | None = None,
                      rows_path: str | os.PathLike | None = None) -> Measured:
    """Read the measured file (any shape of :func:`radtree.measurements.load_measured`) and the
    per-row daily means (``project.measured_rows``) and match them to the project's hours."""
    from radtree.measurements import grid_mean, load_measured, load_measured_rows

    if path is None:
        if project.measured is None:
            raise RadtreeError(f"no measurements: pass --measured FILE.csv or set [project] "
                               f"measured in {project.source}")
        path = project.measured
    frame, shape = load_measured(path, units)
    if shape.kind == "row" and sensors_per_row is None:
        raise RadtreeError("a per-row measured file needs the simulated sensors per row")
    gm = grid_mean(frame, sensors_per_row if shape.kind == "row" else None)
    hours = list(project.site.hours)
    have = dict(zip(gm["time"], gm["measured_lux"].astype(float)))
    times = tuple(h for h in hours if h in have)
    left_out = [t for t in gm["time"] if t not in hours]
    unmeasured = [h for h in hours if h not in have]
    if len(times) < 3:
        raise RadtreeError(
            f"{path}: only {len(times)} measured hour(s) match the project's site.hours "
            f"({', '.join(hours)}); the diagnosis needs at least 3 (measured: "
            f"{', '.join(gm['time'])})")
    rows_hourly = None
    if shape.kind == "row":
        rows_hourly = frame[["time", "row", "measured_lux"]].copy()
    elif shape.kind == "sensor" and "row" in frame.columns:
        rows_hourly = (frame.groupby(["time", "row"], sort=True)["measured_lux"].mean()
                       .reset_index())
    if rows_hourly is not None:
        rows_hourly = rows_hourly[rows_hourly["time"].isin(times)].reset_index(drop=True)
    rows_daily = None
    rp = rows_path if rows_path is not None else project.measured_rows
    if rp is not None:
        rows_daily = load_measured_rows(rp)
    return Measured(times, np.array([have[t] for t in times]), str(path), shape.units,
                    shape.kind, rows_daily, rows_hourly, left_out, unmeasured)
