"""The *generated* clear-sky year: an EPW radtree writes when no measured weather is given.

No measured Mendoza weather file can be downloaded here, so radtree can write one from a
documented clear-sky model. It is labelled as generated in the EPW header (``COMMENTS 1`` and
``COMMENTS 2`` start with ``GENERATED``) and in every annual report. Point a project at a real
file with ``[light] epw = "..."`` (or ``radtree annual --epw``) to replace it.

The model, hour by hour (8760 hours of a non-leap year, local standard time, no daylight
saving; EPW row ``h`` covers the clock hour h−1…h and is evaluated at its midpoint h−0.5):

* sun position: NREL SPA (pvlib), apparent zenith;
* irradiance: Ineichen–Perez clear sky (Ineichen & Perez 2002, pvlib ``ineichen``) with the
  monthly Linke turbidity climatology shipped with pvlib (Remund et al. 2003, interpolated
  to the day) at the site's elevation → global, direct normal and diffuse horizontal W/m²;
* illuminance fields: Perez et al. (1990) luminous-efficacy models for the direct and
  diffuse parts (:func:`radtree.light.perez.perez_efficacy`; sky clearness ε, brightness Δ
  from the irradiances, precipitable water 2 cm — the value ``gendaylit``/``gendaymtx`` assume by default, so the illuminances written
  here agree with what Radiance derives from the irradiances); global = diffuse + direct·cos Z;
* extraterrestrial horizontal and normal irradiance (pvlib, Spencer), total sky cover 0
  (clear), pressure from the elevation (standard atmosphere);
* every other field (temperatures, humidity, wind, …) carries the EPW *missing* code: the
  file is for daylight only.

A clear-sky year is an upper bound on sunshine: Mendoza is sunny, but not cloudless, so
daylight autonomy and sunlight exposure from this file are optimistic. Use a measured or
typical-year EPW for design decisions. Which EPW a run uses:
:func:`radtree.light.weather.find_weather`.
"""

from __future__ import annotations

from datetime import timedelta, timezone
from pathlib import Path

import numpy as np
import pandas as pd

from radtree.errors import ConfigError
from radtree.fileio import write_text
from radtree.light.perez import PRECIPITABLE_WATER_CM, perez_efficacy

GENERATED_TAG = "GENERATED"
YEAR = 2023  # any non-leap year: 8760 rows; 1 January 2023 is a Sunday

# EPW missing-value codes for the fields the generator does not model (0-based field index).
_MISSING = {6: "99.9", 7: "99.9", 8: "999", 12: "9999", 19: "9999", 20: "999", 21: "999",
            24: "9999", 25: "99999", 26: "9", 27: "999999999", 28: "999", 29: "0.999",
            30: "999", 31: "99", 32: "999", 33: "999", 34: "99"}


def clear_sky_illuminance(times: pd.DatetimeIndex, latitude: float, longitude: float,
                          elevation_m: float) -> pd.DataFrame:
    """Clear-sky irradiance and illuminance at the time-zone-aware instants ``times``.

    Columns: zenith (apparent, degrees), ghi, dni, dhi (W/m²), ghi_lux, dni_lux, dhi_lux (lux),
    etrn (extraterrestrial normal irradiance, W/m²); zero with the sun below the horizon. The
    model is the module text's: Ineichen–Perez with pvlib's Linke turbidity climatology, Perez
    (1990) luminous efficacy for the direct and the diffuse part.
    """
    import pvlib

    sp = pvlib.solarposition.get_solarposition(times, latitude, longitude, altitude=elevation_m)
    am_rel = pvlib.atmosphere.get_relative_airmass(sp["apparent_zenith"])
    am_abs = pvlib.atmosphere.get_absolute_airmass(am_rel,
                                                   pvlib.atmosphere.alt2pres(elevation_m))
    linke = pvlib.clearsky.lookup_linke_turbidity(times, latitude, longitude)
    etrn = pvlib.irradiance.get_extra_radiation(times)
    cs = pvlib.clearsky.ineichen(sp["apparent_zenith"], am_abs, linke, altitude=elevation_m,
                                 dni_extra=etrn)
    zen = sp["apparent_zenith"].to_numpy()
    up = zen < 90.0
    ghi = np.where(up, np.nan_to_num(cs["ghi"].to_numpy()), 0.0)
    dni = np.where(up, np.nan_to_num(cs["dni"].to_numpy()), 0.0)
    dhi = np.where(up, np.nan_to_num(cs["dhi"].to_numpy()), 0.0)
    eff_dir, eff_dif = perez_efficacy(dni, dhi, zen, times.day_of_year.to_numpy())
    dni_lux = dni * eff_dir
    dhi_lux = dhi * eff_dif
    ghi_lux = dhi_lux + dni_lux * np.cos(np.radians(np.clip(zen, 0, 90)))
    return pd.DataFrame({"zenith": zen, "ghi": ghi, "dni": dni, "dhi": dhi,
                         "ghi_lux": ghi_lux, "dni_lux": dni_lux, "dhi_lux": dhi_lux,
                         "etrn": np.where(up, etrn.to_numpy(), 0.0)}, index=times)


def clear_sky_year(latitude: float, longitude: float, elevation_m: float,
                   utc_offset_hours: float, year: int = YEAR) -> pd.DataFrame:
    """8760 hourly rows of the generated clear-sky year (columns: month, day, hour (EPW hour
    ending), zenith, ghi, dni, dhi (W/m²), ghi_lux, dni_lux, dhi_lux, etr, etrn)."""
    tz = timezone(timedelta(hours=utc_offset_hours))
    start = pd.Timestamp(year=year, month=1, day=1, hour=0, minute=30, tz=tz)
    mid = pd.date_range(start, periods=8760, freq="h")
    if len(mid) != 8760 or mid[-1].year != year:
        raise ConfigError(f"year {year} is not a 365-day year")
    cs = clear_sky_illuminance(mid, latitude, longitude, elevation_m)
    zen = cs["zenith"].to_numpy()
    etr = cs["etrn"].to_numpy() * np.cos(np.radians(np.clip(zen, 0, 90)))
    out = cs.reset_index(drop=True)
    out.insert(0, "hour", mid.hour + 1)
    out.insert(0, "day", mid.day)
    out.insert(0, "month", mid.month)
    out["etr"] = etr
    return out


def epw_text(city: str, latitude: float, longitude: float, elevation_m: float,
             utc_offset_hours: float, year: int = YEAR) -> str:
    """The generated clear-sky EPW as text (header labelled GENERATED)."""
    import pvlib

    df = clear_sky_year(latitude, longitude, elevation_m, utc_offset_hours, year)
    pressure = int(round(float(pvlib.atmosphere.alt2pres(elevation_m))))
    name = city.replace(",", " ")
    header = [
        f"LOCATION,{name},-,-,radtree generated clear sky,000000,{latitude:.3f},"
        f"{longitude:.3f},{utc_offset_hours:.1f},{elevation_m:.1f}",
        "DESIGN CONDITIONS,0",
        "TYPICAL/EXTREME PERIODS,0",
        "GROUND TEMPERATURES,0",
        "HOLIDAYS/DAYLIGHT SAVINGS,No,0,0,0",
        f"COMMENTS 1,{GENERATED_TAG} by radtree (radtree.light.clearsky) - NOT MEASURED DATA. "
        "Clear sky every day: Ineichen-Perez clear-sky irradiance (pvlib) with the monthly "
        "Linke turbidity climatology of pvlib (Remund et al. 2003) at the site elevation; "
        "sun position NREL SPA; illuminances from the Perez et al. (1990) luminous efficacy "
        f"models with {PRECIPITABLE_WATER_CM:g} cm precipitable water.",
        f"COMMENTS 2,{GENERATED_TAG}: daylight fields only - temperature humidity wind "
        "and precipitation carry EPW missing codes. Each row is evaluated at the middle of "
        "its hour (local standard time). Replace with a measured or typical-year EPW via "
        "[light] epw in radtree.toml.",
        "DATA PERIODS,1,1,Data,Sunday,1/1,12/31",
    ]
    rows = []
    for r in df.itertuples(index=False):
        f = ["0"] * 35
        f[0], f[1], f[2], f[3], f[4] = str(year), str(r.month), str(r.day), str(r.hour), "0"
        f[5] = "?9?9?9?9E0?9?9?9?9?9?9?9?9?9?9?9?9?9?9*9*9?9?9?9"
        f[9] = str(pressure)
        f[10] = f"{r.etr:.0f}"
        f[11] = f"{r.etrn:.0f}"
        f[13], f[14], f[15] = f"{r.ghi:.0f}", f"{r.dni:.0f}", f"{r.dhi:.0f}"
        f[16], f[17], f[18] = f"{r.ghi_lux:.0f}", f"{r.dni_lux:.0f}", f"{r.dhi_lux:.0f}"
        f[22] = f[23] = "0"
        for i, v in _MISSING.items():
            f[i] = v
        rows.append(",".join(f))
    return "\n".join(header + rows) + "\n"


def write_generated_epw(path: Path, city: str, latitude: float, longitude: float,
                        elevation_m: float, utc_offset_hours: float, year: int = YEAR) -> Path:
    """Write the generated clear-sky EPW to ``path`` (atomically)."""
    return write_text(path, epw_text(city, latitude, longitude, elevation_m, utc_offset_hours,
                                     year))
