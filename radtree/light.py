"""The light of each hour of a project: sun position, DNI/DHI, ground reflectance → SkyState.

Inputs: a DNI table (``time,direct_normal_lux`` in lux, '#' comments allowed) or an EPW file;
the ground reflectance is a constant or a table ``angle_deg,reflectance`` against the sun
altitude (interpolated, clamped at the ends).
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd

from radtree.config import Project, Scenario, effective_project, parse_time
from radtree.errors import ConfigError
from radtree.sky import SkyState
from radtree.solar import local_datetime, sun_position


def read_table(path: Path, columns: tuple[str, ...], what: str) -> pd.DataFrame:
    """Read a small CSV with '#' comments and check its columns."""
    try:
        df = pd.read_csv(path, comment="#", skipinitialspace=True)
    except FileNotFoundError as exc:
        raise ConfigError(f"{what} not found: {path}") from exc
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
        raise ConfigError(f"{what} {path} is not a readable CSV: {exc}") from exc
    missing = [c for c in columns if c not in df.columns]
    if missing:
        raise ConfigError(f"{what} {path}: missing column(s) {', '.join(missing)} "
                          f"(found: {', '.join(map(str, df.columns))})")
    for c in columns[1:]:
        vals = pd.to_numeric(df[c], errors="coerce")
        bad = vals.isna() | (vals < 0)
        if bad.any():
            i = int(np.flatnonzero(bad.to_numpy())[0])
            raise ConfigError(f"{what} {path}: data row {i + 1}: {c} = {df[c].iloc[i]!r} "
                              "is not a non-negative number")
        df[c] = vals
    return df


def direct_normal_table(path: Path) -> dict[str, float]:
    df = read_table(path, ("time", "direct_normal_lux"), "direct normal illuminance table")
    out: dict[str, float] = {}
    for i, (t, v) in enumerate(zip(df["time"], df["direct_normal_lux"])):
        t = parse_time(str(t).strip(), f"{path.name}, data row {i + 1}, time")
        if v > 150000:
            raise ConfigError(f"{path}: {t}: direct normal illuminance {v} lx is implausible "
                              "(> 150 000 lx); is the unit klux or W/m²?")
        out[t] = float(v)
    return out


def ground_reflectance_at(project: Project, altitude_deg: float) -> float:
    """The street's reflectance for a sun altitude (table: interpolate, clamp; else constant)."""
    table = project.street.ground_reflectance_table
    if table is None:
        return project.street.ground_reflectance
    df = read_table(table, ("angle_deg", "reflectance"), "ground reflectance table")
    df = df.sort_values("angle_deg")
    if (df["reflectance"] > 1).any():
        raise ConfigError(f"ground reflectance table {table}: reflectance above 1")
    return float(np.interp(altitude_deg, df["angle_deg"], df["reflectance"]))


def hour_states(project: Project, scenario: Scenario | None = None,
                hours: list[str] | None = None) -> list[SkyState]:
    """One SkyState per project hour (or the given subset), as the scenario lights it.

    The sky is the scenario's ``sky`` (else the project's ``light.sky``); with ``reflection =
    calculated`` the traced ground is black and there is no ground glow (the reflected part is
    added analytically afterwards, see :mod:`radtree.reflect`).
    """
    if scenario is not None:
        project = effective_project(project, scenario)
    site = project.site
    wanted = list(hours) if hours is not None else list(site.hours)
    unknown = [h for h in wanted if h not in site.hours]
    if unknown:
        raise ConfigError(f"unknown hour(s) {', '.join(unknown)}; the project has "
                          f"{', '.join(site.hours)}", source=str(project.source), field="site.hours")
    dhi: dict[str, float] = {}
    if project.light.direct_normal_table is not None:
        dni = direct_normal_table(project.light.direct_normal_table)
    else:
        from radtree.weather import epw_diffuse, epw_hour_values

        dni = epw_hour_values(project, wanted)
        dhi = epw_diffuse(project, wanted)
    sky = (scenario.sky if scenario is not None and scenario.sky else project.light.sky)
    calculated = scenario is not None and scenario.reflection == "calculated"
    states = []
    for h in wanted:
        if h not in dni:
            raise ConfigError(f"hour {h} has no direct normal illuminance in "
                              f"{project.light.direct_normal_table}")
        when = local_datetime(site.date, h, site.utc_offset_hours)
        sun = sun_position(when, site.latitude, site.longitude, site.elevation_m)
        if not sun.above_horizon:
            raise ConfigError(f"at {h} on {site.date} the sun is below the horizon "
                              f"(altitude {sun.altitude_deg:.2f}°): not a daylight hour",
                              source=str(project.source), field="site.hours")
        rho = ground_reflectance_at(project, sun.altitude_deg)
        st = SkyState(
            time=h, datetime=when, sun=sun, direct_normal_lux=dni[h],
            diffuse_horizontal_lux=(dhi.get(h, project.light.diffuse_horizontal_lux)
                                    if sky == "perez" else 0.0),
            sky_model=sky, ground_reflectance=rho, ground_glow=True,
        )
        if calculated:
            st = replace(st, ground_reflectance=0.0, ground_glow=False)
        states.append(st)
    return states
