"""Any site on Earth: a free-standing façade under the site's clear sky, against pvlib.

For each site (both hemispheres, the tropics, above 60° latitude, both sides of the date line,
zones with daylight saving), date and façade orientation (N, E, S, W), radtree's own chain —
``radtree new --lat --lon --tz --date`` → the project's hours in local civil time → the clear-sky
weather of :mod:`radtree.light.clearsky` → the hour's sun (SPA) and Perez sky
(:mod:`radtree.light.perez`, gendaylit's all-weather luminance model) → the NumPy engine —
gives the illuminance on a vertical sensor 1.5 m above an unshaded ground of the project's
reflectance, with no wall, tree or opposite building (so the ground in front is lit everywhere,
as transposition models assume).

The independent reference is pvlib: the same clear-sky irradiances (W/m²) transposed to the
vertical plane with pvlib's Perez (1990) model (``pvlib.irradiance.get_total_irradiance``,
``model="perez"``, sun position from ``pvlib.solarposition``), ground-reflected light isotropic
from an infinite ground of the same reflectance, each component turned into lux with the same
luminous efficacy (direct: DNI lux / DNI W; sky diffuse: DHI lux / DHI W; ground: GHI lux /
GHI W). The two sky models differ (a luminance distribution vs a three-part irradiance model),
so agreement is expected to a few per cent, not exactly; the tolerance is 10 %
(issue 37). The daylight hours radtree traces (sun centre above the horizon, refraction
included) are compared with pvlib's sunrise and sunset (SPA, upper limb with refraction).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import pandas as pd

from radtree.config import EngineParams, load_project
from radtree.engines.numpy import trace_hour
from radtree.light.hours import hour_states
from radtree.light.sun import daylight_hours
from radtree.scene import Scene, SensorGrid
from radtree.site.starter import Location, new_project


@dataclass(frozen=True)
class Place:
    name: str
    latitude: float
    longitude: float
    time_zone: str
    elevation_m: float


#: twelve sites: both hemispheres, the tropics, above 60°, both sides of the date line,
#: daylight saving north and south, half-hour offsets
SITES = (
    Place("Madrid", 40.42, -3.70, "Europe/Madrid", 667.0),
    Place("New York", 40.71, -74.01, "America/New_York", 10.0),
    Place("Sydney", -33.87, 151.21, "Australia/Sydney", 20.0),
    Place("Santiago de Chile", -33.45, -70.67, "America/Santiago", 570.0),
    Place("Singapore", 1.35, 103.82, "Asia/Singapore", 15.0),
    Place("Nairobi", -1.29, 36.82, "Africa/Nairobi", 1795.0),
    Place("Reykjavik", 64.15, -21.94, "Atlantic/Reykjavik", 30.0),
    Place("Anchorage", 61.22, -149.90, "America/Anchorage", 30.0),
    Place("Suva", -18.14, 178.44, "Pacific/Fiji", 5.0),
    Place("Apia", -13.83, -171.76, "Pacific/Apia", 2.0),
    Place("Mumbai", 19.08, 72.88, "Asia/Kolkata", 14.0),
    Place("Cape Town", -33.92, 18.42, "Africa/Johannesburg", 25.0),
)
DATES = ("2024-03-20", "2024-06-21", "2024-12-21")
FACADES = {"N": 0.0, "E": 90.0, "S": 180.0, "W": 270.0}
SENSOR_HEIGHT_M = 1.5
TOLERANCE = 0.10


def _facade_grid() -> SensorGrid:
    az = np.radians(list(FACADES.values()))
    normals = np.column_stack([np.sin(az), np.cos(az), np.zeros(len(az))])
    points = np.tile([0.0, 0.0, SENSOR_HEIGHT_M], (len(az), 1))
    return SensorGrid("facades", points, normals)


def pvlib_vertical_lux(times: pd.DatetimeIndex, place: Place, albedo: float
                       ) -> tuple[np.ndarray, np.ndarray]:
    """(hours, 4) façade illuminance N, E, S, W by pvlib's Perez transposition (module text):
    the total and its direct (sun) part."""
    import pvlib

    from radtree.light.clearsky import clear_sky_illuminance

    cs = clear_sky_illuminance(times, place.latitude, place.longitude, place.elevation_m)
    sp = pvlib.solarposition.get_solarposition(times, place.latitude, place.longitude,
                                               altitude=place.elevation_m)
    am = pvlib.atmosphere.get_relative_airmass(sp["apparent_zenith"])
    extra = pvlib.irradiance.get_extra_radiation(times)

    def ratio(lux: str, watt: str) -> np.ndarray:
        w = cs[watt].to_numpy()
        return np.divide(cs[lux].to_numpy(), w, out=np.zeros_like(w), where=w > 0)

    k_dir, k_sky, k_gnd = ratio("dni_lux", "dni"), ratio("dhi_lux", "dhi"), ratio("ghi_lux", "ghi")
    out, direct = [], []
    for az in FACADES.values():
        poa = pvlib.irradiance.get_total_irradiance(
            90.0, az, sp["apparent_zenith"], sp["azimuth"], cs["dni"], cs["ghi"], cs["dhi"],
            dni_extra=extra, airmass=am, albedo=albedo, model="perez")
        out.append(poa["poa_direct"].fillna(0).to_numpy() * k_dir
                   + poa["poa_sky_diffuse"].fillna(0).to_numpy() * k_sky
                   + poa["poa_ground_diffuse"].fillna(0).to_numpy() * k_gnd)
        direct.append(poa["poa_direct"].fillna(0).to_numpy() * k_dir)
    return np.column_stack(out), np.column_stack(direct)


def pvlib_daylight(place: Place, date: str) -> tuple[pd.Timestamp | None, pd.Timestamp | None]:
    """pvlib's sunrise and sunset (SPA) on the local ``date``; None in polar day or night."""
    import pvlib

    local = pd.Timestamp(date, tz=place.time_zone)
    rise = sset = None
    for shift in (0, -1, 1):   # near the date line pvlib answers for the neighbouring day
        day = pd.DatetimeIndex([local + pd.Timedelta(days=shift)])
        rs = pvlib.solarposition.sun_rise_set_transit_spa(day, place.latitude, place.longitude)
        transit = rs["transit"].iloc[0]
        rise, sset = rs["sunrise"].iloc[0], rs["sunset"].iloc[0]
        if not pd.isna(transit) and transit.tz_convert(place.time_zone).date() == local.date():
            break
    return (None if pd.isna(rise) else rise, None if pd.isna(sset) else sset)


@dataclass(frozen=True)
class Comparison:
    """One site × date: radtree and pvlib per hour and façade (lux), and the daylight check."""

    place: Place
    date: str
    hours: list[str]
    radtree: np.ndarray
    radtree_stderr: np.ndarray
    pvlib: np.ndarray
    radtree_direct: np.ndarray
    pvlib_direct: np.ndarray
    sun_altitude_deg: np.ndarray
    hours_match: bool
    daylight_note: str

    @property
    def rel_error(self) -> np.ndarray:
        return np.abs(self.radtree - self.pvlib) / np.maximum(self.pvlib, 1e-9)

    def worst(self) -> tuple[float, str, str]:
        """(largest relative difference, hour, façade)."""
        if not self.hours:
            return 0.0, "-", "-"
        i, j = np.unravel_index(int(np.argmax(self.rel_error)), self.rel_error.shape)
        return float(self.rel_error[i, j]), self.hours[i], list(FACADES)[j]


def _hours_match(place: Place, date: str, hours: list[str]) -> tuple[bool, str]:
    """radtree's daylight hours are the whole hours strictly between pvlib's sunrise and
    sunset, except those at which pvlib's apparent solar elevation lies between −0.8333° and
    0° (sunrise/sunset mark the upper limb with standard refraction, radtree's hours the
    centre above the horizon)."""
    import pvlib

    rise, sset = pvlib_daylight(place, date)
    if rise is None or sset is None:
        return True, "polar day or night: pvlib gives no sunrise/sunset"
    stamps = pd.DatetimeIndex([pd.Timestamp(f"{date}T{h:02d}:00", tz=place.time_zone)
                               for h in range(24)])
    elev = pvlib.solarposition.get_solarposition(stamps, place.latitude, place.longitude,
                                                 altitude=place.elevation_m)[
        "apparent_elevation"].to_numpy()
    expected = [f"{w:%H:%M}" for w, e in zip(stamps, elev)
                if rise < w < sset and not -0.8333 <= e <= 0.0]
    got = [h for h, e in zip([f"{w:%H:%M}" for w in stamps], elev)
           if h in hours and not -0.8333 <= e <= 0.0]
    return got == expected, f"sunrise {rise:%H:%M}, sunset {sset:%H:%M}"


def compare_site(place: Place, date: str, folder: Path, rays: int = 4096) -> Comparison:
    """radtree's free-standing façade vs pvlib at every daylight hour of ``date``."""
    new_project(folder, template="street", where=Location(
        place.latitude, place.longitude, place.time_zone, place.elevation_m, date))
    project = load_project(folder)
    hours = daylight_hours(place.latitude, place.longitude, place.elevation_m,
                           project.site.tzinfo, date)
    match, note = _hours_match(place, date, hours)
    if not hours:
        empty = np.zeros((0, len(FACADES)))
        return Comparison(place, date, [], empty, empty, empty, empty, empty, np.zeros(0),
                          match, note)
    project = replace(project, site=replace(project.site, hours=tuple(hours)),
                      light=replace(project.light, sky="perez"))
    scene = Scene([], {}, {"facades": _facade_grid()})
    params = EngineParams(rays=rays, max_bounces=1)
    states = hour_states(project)
    lux, se, direct = [], [], []
    for st in states:
        r = trace_hour(scene, st, params)["facades"]
        lux.append(r.lux)
        se.append(r.stderr if r.stderr is not None else np.zeros_like(r.lux))
        sun_only = replace(st, sky_model="none", diffuse_horizontal_lux=0.0, ground_glow=False)
        direct.append(trace_hour(scene, sun_only, params)["facades"].lux)
    times = pd.DatetimeIndex([st.datetime for st in states]).tz_convert("UTC")
    ref, ref_direct = pvlib_vertical_lux(times, place, project.street.ground_reflectance)
    alt = np.array([st.sun.altitude_deg for st in states])
    return Comparison(place, date, hours, np.array(lux), np.array(se), ref, np.array(direct),
                      ref_direct, alt, match, note)


def worst_table(results: list[Comparison]) -> list[str]:
    """One line per site: the worst relative difference over its dates, hours and façades."""
    lines = [f"{'site':<18} {'lat':>7} {'lon':>8} {'zone':<20} {'hours':>5} {'worst':>7}  where"]
    by_site: dict[str, list[Comparison]] = {}
    for c in results:
        by_site.setdefault(c.place.name, []).append(c)
    for name, cs in by_site.items():
        worst = max((c.worst() + (c.date,) for c in cs), key=lambda w: w[0])
        p = cs[0].place
        n = sum(len(c.hours) for c in cs)
        lines.append(f"{name:<18} {p.latitude:>7.2f} {p.longitude:>8.2f} {p.time_zone:<20} "
                     f"{n:>5} {100 * worst[0]:>6.2f}%  {worst[3]} {worst[1]} {worst[2]}-facing")
    return lines
