"""The year an annual run is computed over: weather checked against the site, sky matrix, suns."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from radtree.annual.skymatrix import (
    Suns,
    Wea,
    epw_to_wea,
    reinhart_directions,
    sky_matrix,
    sun_patch_weights,
    sun_positions,
)
from radtree.config import Project
from radtree.errors import ConfigError
from radtree.light.weather import WeatherSource, find_weather

YearInputs = tuple[WeatherSource, Wea, np.ndarray, Suns, np.ndarray, np.ndarray,
                   np.ndarray, np.ndarray]


def annual_weather(project: Project, *, epw: Path | None, mf: int, sun_mf: int,
                   rho: float) -> YearInputs:
    """The year's weather (``epw`` or the project's), refused unless within 0.5° of the site's
    latitude and longitude; its sky matrix (Reinhart MF ``mf``, ground reflectance ``rho``, 0–1); the
    hourly suns and the MF ``sun_mf`` patches they fall in.

    Returns ``(weather, wea, sky, suns, verts, weights, need, patch_dirs)``: ``verts`` and
    ``weights`` place each sun among its patch vertices, ``need`` lists the patches any sun uses
    (patch 0, the ground, left out) and ``patch_dirs`` are the patch directions (x east, y north,
    z up)."""
    weather = find_weather(project, epw)
    wea = epw_to_wea(weather.path, project.results_dir / "annual" / "weather" / "year.wea")
    site = project.site
    if abs(wea.latitude - site.latitude) > 0.5 or abs(-wea.longitude_west - site.longitude) > 0.5:
        raise ConfigError(f"weather {weather.path} is for {wea.latitude}, {-wea.longitude_west} "
                          f"but the site is at {site.latitude}, {site.longitude}")
    sky = sky_matrix(wea, mf, rho)
    suns = sun_positions(wea, project.results_dir / "annual" / "weather")
    verts, weights = sun_patch_weights(suns.direction, sun_mf)
    need = np.unique(verts)
    need = need[need > 0]
    return weather, wea, sky, suns, verts, weights, need, reinhart_directions(sun_mf)


def annual_ground_reflectance(project: Project) -> float:
    """The street's reflectance for a whole year: the constant, or the mean of the
    sun-angle table (coefficients need one fixed material)."""
    table = project.street.ground_reflectance_table
    if table is None:
        return float(project.street.ground_reflectance)
    from radtree.light.tables import ground_reflectance_table

    df = ground_reflectance_table(table)
    return float(df["reflectance"].mean())
