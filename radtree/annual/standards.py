"""The standards consultants report against, from the annual run: ``results/annual/standards.csv``.

One row per scenario (with and without trees) × target (a grid: a façade chunk, an office
room) × metric, columns ``scenario, target, metric, value, unit, definition``; the
``definition`` column states what was computed, in words.

**EN 17037:2018 daylight provision** (climate-based method). A reference plane (the grid's
sensors, each standing for an equal area) meets a level when, for at least half of the
daylight hours, the target illuminance E_T is reached over 50 % of the plane *and* the minimum
target illuminance E_TM over 95 % of it. Levels (E_T / E_TM): minimum 300 / 100 lx, medium
500 / 300 lx, high 750 / 500 lx. Daylight hours: the 4 380 hours of the weather year with the
largest diffuse horizontal irradiance (half the year). Each hour is judged over the plane, then
the hours are counted — the order ClimateStudio follows ("for each hour of the year, the
percentage of the floor area achieving minimum and target illuminance thresholds is measured";
https://climatestudiodocs.com/docs/daylightEN17037.html, which states the 300 lx / 50 % and
100 lx / 95 % minimum level, the 50 % of daylight hours and the 4 380 hours). Medium level
500 / 300 lx: Bartenbach, "More (day-)light — thoughts on the new daylight standard EN 17037"
(bartenbach.com news 133). The high level's 750 / 500 lx is EN 17037 Table A.1 as quoted in
the task; no public summary read here states it (check it against the standard).

**EN 17037:2018 exposure to sunlight.** The duration of possible direct sun at a reference
point on a chosen date between 1 February and 21 March (default 21 March), counted only while
the sun's altitude exceeds 11°; levels minimum 1.5 h, medium 3 h, high 4 h ("Mindestempfehlung
… 1,5 Stunden. Bei mehr als 4 Stunden liegt eine hohe Besonnungsdauer vor … Besonnungszeiten
werden erst ab einem Sonnenhöhenwinkel > 11° angerechnet": iMA Richter & Röckle,
https://www.ima-umwelt.de/verschattung, summarising DIN EN 17037:2018+A1:2021; the medium
level's 3 h as the task states it). The standard's reference point lies on the inner surface
of the window, mid-width, ≥ 1.2 m above the floor and 0.3 m above the sill; here every sensor
of the target stands for a reference point (a façade sensor sits on a window position) and the
value is their mean, with the % of them reaching each level beside it. "Possible" sun: a clear
sky every minute of the date; each time step counts by the share of the sun beam that reaches
the point (1 free, 0 blocked; through a crown the leaves' specular transmittance), from the
sun in front of the sensor (cos > 0). The crown on that date is the leafed one when the
leaf schedule has it in leaf, else the bare one.

**LEED v4.1 EQ credit Daylight, option 1** — sDA300/50% and ASE1000,250 "as defined in IES
LM-83-12" (LEED v4.1 credit language, leeduser.buildinggreen.com/credit/Hospitality-CI-v4.1/EQc7),
over the occupied hours 8:00–18:00 (3 650 hours a year; Autodesk Revit's LEED v4 EQc7 opt1
help: "300 lux for a percentage of 3650 annual hours", "over 1000 lux for more than 250 of
3650 annual hours"): :mod:`radtree.annual.metrics` computes both (sDA: % of sensors with
DA300 ≥ 50 %; ASE: % of sensors with more than 250 occupied hours of direct sun > 1000 lx).
No blinds are operated.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from datetime import datetime, timedelta, timezone
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

import radtree.annual.metrics as metrics
from radtree.annual.schedule import parse_month_day
from radtree.errors import ConfigError

if TYPE_CHECKING:
    from pathlib import Path

    from radtree.annual.skymatrix import Wea
    from radtree.config import EngineParams, Project
    from radtree.engines.base import Engine
    from radtree.light.sky import SkyState
    from radtree.scene import Scene

COLUMNS = ["scenario", "target", "metric", "value", "unit", "definition"]
DAYLIGHT_HOURS = 4380         # half of the 8 760 hours (ClimateStudio's daylight hours)
TIME_FRACTION = 50.0          # % of the daylight hours
TARGET_AREA = 50.0            # % of the reference plane reaching E_T
MINIMUM_AREA = 95.0           # % of the reference plane reaching E_TM


@dataclass(frozen=True)
class ProvisionLevel:
    """An EN 17037 daylight-provision level: target E_T and minimum target E_TM (lux)."""

    name: str
    target_lux: float
    minimum_lux: float


PROVISION_LEVELS = (ProvisionLevel("minimum", 300.0, 100.0),
                    ProvisionLevel("medium", 500.0, 300.0),
                    ProvisionLevel("high", 750.0, 500.0))
#: EN 17037 exposure to sunlight: hours of possible sun per level
SUNLIGHT_LEVELS = (("minimum", 1.5), ("medium", 3.0), ("high", 4.0))
SUNLIGHT_MIN_ALTITUDE_DEG = 11.0
SUNLIGHT_DATE = "03-21"
SUNLIGHT_STEP_MIN = 2.0


def daylight_hours(dhi: np.ndarray, count: int = DAYLIGHT_HOURS) -> np.ndarray:
    """(hours,) True for the ``count`` hours of largest diffuse horizontal irradiance (ties:
    the earlier hour first)."""
    d = np.asarray(dhi, float)
    order = np.argsort(-d, kind="stable")
    out = np.zeros(len(d), bool)
    out[order[:min(count, len(d))]] = True
    return out


def plane_hours(lux: np.ndarray, hours: np.ndarray, threshold: float, area: float) -> float:
    """% of the ``hours`` (mask) at which at least ``area`` % of the sensors (rows of ``lux``,
    (sensors, hours)) reach ``threshold`` lux (E ≥ threshold)."""
    e = np.atleast_2d(np.asarray(lux, float))[:, np.asarray(hours, bool)]
    if e.shape[1] == 0:
        return float("nan")
    share = 100.0 * (e >= threshold).mean(axis=0)
    return float(100.0 * np.mean(share >= area))


def provision(lux: np.ndarray, hours: np.ndarray) -> list[tuple[str, float, str, str]]:
    """EN 17037 daylight provision of one reference plane: (metric, value, unit, definition)."""
    rows = []
    met = 0
    for k, lv in enumerate(PROVISION_LEVELS, start=1):
        t = plane_hours(lux, hours, lv.target_lux, TARGET_AREA)
        m = plane_hours(lux, hours, lv.minimum_lux, MINIMUM_AREA)
        rows.append((f"en17037_{lv.name}_target_hours", t, "% of daylight hours",
                     f"EN 17037 daylight provision, {lv.name} level: share of the "
                     f"{DAYLIGHT_HOURS} daylight hours (largest diffuse horizontal irradiance) "
                     f"at which ≥ {TARGET_AREA:g} % of the plane has ≥ {lv.target_lux:g} lx"))
        rows.append((f"en17037_{lv.name}_minimum_hours", m, "% of daylight hours",
                     f"EN 17037 daylight provision, {lv.name} level: share of the daylight "
                     f"hours at which ≥ {MINIMUM_AREA:g} % of the plane has ≥ "
                     f"{lv.minimum_lux:g} lx"))
        if met == k - 1 and t >= TIME_FRACTION and m >= TIME_FRACTION:
            met = k
    names = ", ".join(f"{k} {lv.name} ({lv.target_lux:g}/{lv.minimum_lux:g} lx)"
                      for k, lv in enumerate(PROVISION_LEVELS, start=1))
    rows.append(("en17037_provision_level", float(met), "level",
                 f"EN 17037 daylight provision: highest level met (0 none, {names}): E_T over "
                 f"{TARGET_AREA:g} % and E_TM over {MINIMUM_AREA:g} % of the plane, each for "
                 f"≥ {TIME_FRACTION:g} % of the daylight hours"))
    return rows


def sunlight(hours: np.ndarray, date: str) -> list[tuple[str, float, str, str]]:
    """EN 17037 exposure to sunlight from the sun hours of each reference point."""
    h = np.asarray(hours, float)
    rows = [("en17037_sunlight_hours", float(h.mean()) if h.size else float("nan"), "h",
             f"EN 17037 exposure to sunlight: hours of possible direct sun on {date} (sun "
             f"altitude > {SUNLIGHT_MIN_ALTITUDE_DEG:g}°, in front of the point, each step "
             f"weighted by the share of the beam reaching it), mean over the target's "
             f"reference points (its sensors)")]
    for name, need in SUNLIGHT_LEVELS:
        rows.append((f"en17037_sunlight_{name}", float(100.0 * np.mean(h >= need))
                     if h.size else float("nan"), "% of points",
                     f"EN 17037 exposure to sunlight, {name} level: % of the target's "
                     f"reference points with ≥ {need:g} h of sun on {date}"))
    return rows


def leed(lux: np.ndarray, direct: np.ndarray, occupied: np.ndarray
         ) -> list[tuple[str, float, str, str]]:
    """LEED v4.1 sDA300/50% and ASE1000,250 of one grid."""
    da = metrics.daylight_autonomy(lux, occupied)
    ase = metrics.sunlight_hours(direct, occupied)
    n = int(np.asarray(occupied, bool).sum())
    return [
        ("leed_sda_300_50", metrics.spatial_daylight_autonomy(da), "% of area",
         f"LEED v4.1 sDA300/50% (IES LM-83-12): % of sensors with ≥ 300 lx for ≥ 50 % of the "
         f"{n} occupied hours; no blinds operated"),
        ("leed_ase_1000_250", metrics.annual_sunlight_exposure(ase), "% of area",
         f"LEED v4.1 ASE1000,250 (IES LM-83-12): % of sensors with direct sun > 1000 lx in "
         f"more than 250 of the {n} occupied hours (LEED asks ≤ 10 %)"),
    ]


def check_sunlight_date(value: str) -> str:
    """``MM-DD`` between 1 February and 21 March (EN 17037), else ConfigError."""
    month, day = parse_month_day(value, "sunlight date")
    if not (2, 1) <= (month, day) <= (3, 21):
        raise ConfigError(f"sunlight date: got {value!r}, expected a date between 02-01 and "
                          "03-21 (EN 17037 exposure to sunlight)", field="--sunlight-date")
    return f"{month:02d}-{day:02d}"


def sun_steps(latitude: float, longitude: float, utc_offset_hours: float, year: int,
              date: str, step_min: float = SUNLIGHT_STEP_MIN,
              min_altitude_deg: float = SUNLIGHT_MIN_ALTITUDE_DEG
              ) -> tuple[list[datetime], np.ndarray, np.ndarray]:
    """The mid-points of ``step_min`` steps over the local day ``date`` (``MM-DD`` of
    ``year``) at which the sun is above ``min_altitude_deg``: their times, apparent altitudes
    and compass azimuths (degrees; NREL SPA via pvlib)."""
    import pvlib

    month, day = parse_month_day(date, "sunlight date")
    tz = timezone(timedelta(hours=utc_offset_hours))
    n = int(round(24 * 60 / step_min))
    start = datetime(year, month, day, tzinfo=tz)
    times = pd.DatetimeIndex([start + timedelta(minutes=(i + 0.5) * step_min)
                              for i in range(n)])
    pos = pvlib.solarposition.get_solarposition(times, latitude, longitude)
    alt = pos["apparent_elevation"].to_numpy()
    az = pos["azimuth"].to_numpy()
    up = alt > min_altitude_deg
    return [t.to_pydatetime() for t in times[up]], alt[up], az[up]


def sun_hours(trace: Callable[[list[SkyState]], list[dict[str, np.ndarray]]], grids: dict[str, tuple],
              times: list[datetime], altitude: np.ndarray, azimuth: np.ndarray,
              step_min: float = SUNLIGHT_STEP_MIN, chunk: int = 16) -> dict[str, np.ndarray]:
    """Hours of sun per sensor: Σ over the steps of (step length) × the share of a unit beam
    from the sun reaching the sensor. ``trace(states)``: direct illuminance per grid and state
    for a list of sun-only hour states of 1 lux direct normal (an engine at ``-ab 0``);
    ``grids``: name → (points, normals)."""
    from radtree.light.sky import SkyState
    from radtree.light.sun import SunPosition

    out = {g: np.zeros(len(p)) for g, (p, _) in grids.items()}
    states = [SkyState(time=t.strftime("%H:%M:%S"), datetime=t, sun=SunPosition(a, z),
                       direct_normal_lux=1.0, sky_model="none", ground_glow=False)
              for t, a, z in zip(times, altitude, azimuth, strict=True)]
    for i in range(0, len(states), chunk):
        part = states[i:i + chunk]
        for st, res in zip(part, trace(part), strict=True):
            sun = st.sun.vector
            for g, (_, normals) in grids.items():
                cos = normals @ sun
                share = np.where(cos > 1e-9, res[g] / np.where(cos > 1e-9, cos, 1.0), 0.0)
                out[g] += np.clip(share, 0.0, 1.0) * step_min / 60.0
    return out


def direct_tracer(engine: Engine, scene: Scene, params: EngineParams, grids: list[str]
                  ) -> Callable[[list[SkyState]], list[dict[str, np.ndarray]]]:
    """``trace(states)`` for :func:`sun_hours`: the direct illuminance per grid of each state,
    traced by ``engine`` at ``-ab 0`` (the sun alone, exact transmittance through crowns)."""
    def trace(states: list[SkyState]) -> list[dict[str, np.ndarray]]:
        plan = engine.prepare(scene, states, params, 0)
        got = engine.trace_many(plan, [s.label for s in states], grids)
        return [{g: r[g].lux for g in grids} for r in got]

    return trace


def standards_table(scenarios: dict[str, str], grids: list[str],
                    total: dict[str, dict[str, np.ndarray]],
                    direct: dict[str, dict[str, np.ndarray]], dhi: np.ndarray,
                    occupied: np.ndarray, sunlight_hours: dict[str, dict[str, np.ndarray]]
                    | None = None, sunlight_date: str = SUNLIGHT_DATE) -> pd.DataFrame:
    """``standards.csv`` rows: per tree key of ``scenarios`` (``with``/``without`` → the
    scenario's name) and grid, EN 17037 provision (and sunlight when ``sunlight_hours`` has
    it) and LEED sDA/ASE from the hourly ``total`` and ``direct`` lux (sensors, hours)."""
    day = daylight_hours(dhi)
    rows = []
    for tree, scenario in scenarios.items():
        for g in grids:
            lux, dire = total[tree][g], direct[tree][g]
            found = provision(lux, day) + leed(lux, dire, occupied)
            if sunlight_hours is not None and g in sunlight_hours.get(tree, {}):
                found += sunlight(sunlight_hours[tree][g], sunlight_date)
            rows += [{"scenario": scenario, "target": g, "metric": m, "value": v, "unit": u,
                      "definition": d} for m, v, u, d in found]
    return pd.DataFrame(rows, columns=COLUMNS)


def write_standards(project: Project, table: pd.DataFrame) -> Path:
    """Write ``results/annual/standards.csv`` (atomically); returns its path."""
    from radtree.fileio import atomic_path

    path = project.results_dir / "annual" / "standards.csv"
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        table.to_csv(tmp, index=False, float_format="%.6g")
    return path


def annual_sunlight(project: Project, scenes: dict[str, Scene], grids: list[str], date: str,
                    in_leaf: np.ndarray, wea: Wea) -> dict[str, dict[str, np.ndarray]]:
    """Hours of possible sun per sensor on ``date`` (EN 17037 exposure to sunlight), with the
    crown of that day (leafed when ``in_leaf`` at its noon hour, else bare) and without trees,
    traced at ``-ab 0`` by the seeded engine (:func:`sun_hours`)."""
    from radtree.engines.registry import seeded_engine

    site = project.site
    month, day = (int(x) for x in date.split("-"))
    noon = np.flatnonzero((wea.month == month) & (wea.day == day) & (wea.hour >= 12))
    leafed = bool(in_leaf[noon[0]]) if len(noon) else True
    times, alt, az = sun_steps(site.latitude, site.longitude, site.utc_offset_hours,
                               int(str(site.date)[:4]), date)
    eng = seeded_engine()
    params = project.engine.changed(rays=1)
    out: dict[str, dict[str, np.ndarray]] = {}
    for tree, variant in (("with", "leaf_on" if leafed else "leaf_off"),
                          ("without", "without")):
        scene = scenes[variant]
        out[tree] = sun_hours(direct_tracer(eng, scene, params, grids),
                              {g: (scene.grids[g].points, scene.grids[g].normals)
                               for g in grids}, times, alt, az)
    return out


