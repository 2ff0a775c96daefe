"""EPW weather files: the one reader, the illuminance of the project's hours, the annual EPW.

Every EPW radtree reads goes through :func:`read_epw` (``pvlib.iotools.read_epw``, columns
named as pvlib names them: ``direct_normal_illum``, ``diffuse_horizontal_illum`` in lux, …).

EPW rows are hourly, labelled by the hour *ending* (hour 11 = 10:00–11:00). A clock time
HH:MM is read from the row whose interval contains it (HH:30 → row HH+1); HH:00 is read from
the row ending at HH (00:00 from row 1).
"""

from __future__ import annotations

import io
import logging
import math
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from radtree.errors import ConfigError
from radtree.light.clearsky import GENERATED_TAG, write_generated_epw

log = logging.getLogger(__name__)

MISSING_ILLUMINANCE = 999900  # EPW missing-value code of the illuminance fields is 999999
_HEADER_LINES = 8


@dataclass(frozen=True)
class Epw:
    """An EPW file as read by pvlib.

    ``latitude`` north positive, ``longitude`` east positive (degrees), ``utc_offset_hours``
    the file's time zone, ``elevation_m`` metres; ``data`` pvlib's hourly frame (one row per
    EPW data row, in file order); ``generated`` when a ``COMMENTS`` header line carries
    :data:`~radtree.light.clearsky.GENERATED_TAG` (a radtree clear-sky year, not measured).
    """

    path: Path
    latitude: float
    longitude: float
    utc_offset_hours: float
    elevation_m: float
    data: pd.DataFrame
    generated: bool

    def __post_init__(self) -> None:
        if not (-90.0 <= self.latitude <= 90.0 and -180.0 <= self.longitude <= 180.0):
            raise ConfigError(f"{self.path}: LOCATION latitude {self.latitude}, longitude "
                              f"{self.longitude} out of range")

    @property
    def location(self) -> tuple[float, float, float, float]:
        """(latitude, longitude east+, UTC offset h, elevation m) of the LOCATION line."""
        return self.latitude, self.longitude, self.utc_offset_hours, self.elevation_m

    def illuminance(self) -> dict[tuple[int, int, int], tuple[float, float]]:
        """(month, day, hour-ending) → (direct normal lux, diffuse horizontal lux).

        Every row must hold both values; a missing direct normal illuminance (999999) is an
        error naming the file line.
        """
        cols = ["month", "day", "hour", "direct_normal_illum", "diffuse_horizontal_illum"]
        num = self.data[cols].apply(pd.to_numeric, errors="coerce")
        bad = num.isna().any(axis=1).to_numpy()
        if bad.any():
            line = int(bad.argmax()) + _HEADER_LINES + 1
            raise ConfigError(f"{self.path}: line {line}: malformed EPW data row")
        missing = (num["direct_normal_illum"] >= MISSING_ILLUMINANCE).to_numpy()
        if missing.any():
            line = int(missing.argmax()) + _HEADER_LINES + 1
            raise ConfigError(f"{self.path}: line {line}: direct normal illuminance is "
                              "missing (999999)")
        return {(int(m), int(d), int(h)): (float(dni), float(dhi))
                for m, d, h, dni, dhi in num.itertuples(index=False, name=None)}


def read_epw(path: Path) -> Epw:
    """Read an EPW file with ``pvlib.iotools.read_epw``; errors name the file."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError as exc:
        raise ConfigError(f"cannot read EPW file {path}: {exc}") from exc
    lines = text.split("\n", _HEADER_LINES + 1)
    first = lines[0].rstrip("\r")
    if len(lines) <= _HEADER_LINES or first.split(",")[0] != "LOCATION" \
            or len(first.split(",")) < 10:
        raise ConfigError(f"{path} is not an EPW file (no LOCATION header line)")
    import pvlib

    try:
        data, meta = pvlib.iotools.read_epw(io.StringIO(text))
    except (ValueError, TypeError) as exc:  # malformed LOCATION line or date/hour fields
        first_line = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise ConfigError(f"{path}: malformed EPW file (LOCATION line or the year, month, "
                          f"day, hour fields of a data row): {first_line}") from exc
    generated = any(line.startswith("COMMENTS") and GENERATED_TAG in line
                    for line in lines[:_HEADER_LINES])
    return Epw(path=path, latitude=meta["latitude"], longitude=meta["longitude"],
               utc_offset_hours=meta["TZ"], elevation_m=meta["altitude"], data=data,
               generated=generated)


def epw_location(path: Path) -> tuple[float, float, float, float]:
    """(latitude, longitude, UTC offset h, elevation m) from an EPW's LOCATION line alone."""
    try:
        with open(path, encoding="utf-8", errors="replace") as fh:
            first = fh.readline().rstrip("\r\n").split(",")
    except OSError as exc:
        raise ConfigError(f"cannot read EPW file {path}: {exc}") from exc
    if first[0] != "LOCATION" or len(first) < 10:
        raise ConfigError(f"{path} is not an EPW file (no LOCATION header line)")
    try:
        return float(first[6]), float(first[7]), float(first[8]), float(first[9])
    except ValueError:
        raise ConfigError(f"{path}: malformed LOCATION line (latitude, longitude, time zone, "
                          f"elevation): {','.join(first[6:10])}") from None


def check_epw_site(project, path: Path | None = None) -> None:
    """The EPW is the site's: latitude and longitude within 0.5°, the same standard time
    zone; else ConfigError naming both values and the fix."""
    path = Path(path or project.light.epw)
    if not path.exists():
        raise ConfigError(f"EPW file not found: {path}", source=str(project.source),
                          field="light.epw")
    lat, lon, tz, elev = epw_location(path)
    site = project.site
    fix = ("use an EPW of the site (or [light] weather = \"clear-sky\", which needs no file), "
           "or correct [site]")
    if abs(lat - site.latitude) > 0.5 or abs(lon - site.longitude) > 0.5:
        raise ConfigError(f"the EPW {path.name} is for latitude {lat:g}, longitude {lon:g}, but "
                          f"[site] is at latitude {site.latitude:g}, longitude "
                          f"{site.longitude:g} (more than 0.5° apart): {fix}",
                          source=str(project.source), field="light.epw")
    if abs(tz - site.utc_offset_hours) > 1e-6:
        raise ConfigError(f"the EPW {path.name} is in standard time UTC{tz:+g} h, but [site] "
                          f"time_zone {site.time_zone!r} has standard time "
                          f"UTC{site.utc_offset_hours:+g} h: {fix}",
                          source=str(project.source), field="light.epw")


@dataclass(frozen=True)
class HourWeather:
    """The weather of one project hour: direct normal and diffuse horizontal illuminance
    (lux; diffuse None when the source has none) and where they came from."""

    direct_normal_lux: float
    diffuse_horizontal_lux: float | None
    source: str


def _standard_clock(when) -> tuple[int, int, int, int]:
    """(month, day, hour, minute) of aware ``when`` in its zone's standard time (no DST)."""
    from datetime import timedelta

    dst = when.dst() or timedelta(0)
    std = when.replace(tzinfo=None) - dst
    return std.month, std.day, std.hour, std.minute


def epw_hour_illuminance(project, hours: list[str], path: Path | None = None,
                         ) -> dict[str, tuple[float, float]]:
    """(direct normal, diffuse horizontal) lux per civil clock time from the EPW file.

    EPW rows are local standard time: a civil hour under daylight saving is read from the row
    of its standard-time clock (09:00 CEST → 08:00 standard → the row ending at 08)."""
    from radtree.light.sun import local_datetime

    path = Path(path or project.light.epw)
    data = read_epw(path).illuminance()
    out = {}
    for h in hours:
        month, day, hh, mm = _standard_clock(local_datetime(project.site.date, h,
                                                            project.site.tzinfo))
        ending = hh + 1 if mm > 0 else max(hh, 1)
        key = (month, day, ending)
        if key not in data:
            raise ConfigError(f"EPW file {path} has no row for {month:02d}-{day:02d} hour "
                              f"{ending}")
        out[h] = data[key]
    return out


def hour_weather(project, hours: list[str]) -> dict[str, HourWeather]:
    """The weather of each civil clock time of ``hours`` on ``[site] date``, from the
    project's source (``[light] weather``): clear sky at the instant, an EPW row (checked
    against ``[site]``), or the DNI table."""
    light = project.light
    if light.weather == "table":
        from radtree.light.tables import direct_normal_table

        table = direct_normal_table(light.direct_normal_table)
        name = Path(light.direct_normal_table).name
        missing = [h for h in hours if h not in table]
        if missing:
            raise ConfigError(f"hour(s) {', '.join(missing)} have no direct normal "
                              f"illuminance in {light.direct_normal_table}",
                              source=str(project.source), field="light.direct_normal")
        return {h: HourWeather(table[h], None, f"DNI table {name}") for h in hours}
    if light.weather == "epw":
        check_epw_site(project)
        both = epw_hour_illuminance(project, hours)
        name = Path(light.epw).name
        return {h: HourWeather(v[0], v[1], f"EPW {name}") for h, v in both.items()}
    from radtree.light.clearsky import clear_sky_illuminance
    from radtree.light.sun import local_datetime

    site = project.site
    when = pd.DatetimeIndex([pd.Timestamp(local_datetime(site.date, h, site.tzinfo))
                             .tz_convert("UTC") for h in hours])
    cs = clear_sky_illuminance(when, site.latitude, site.longitude, site.elevation_m)
    return {h: HourWeather(float(d), float(f), CLEAR_SKY_SOURCE)
            for h, d, f in zip(hours, cs["dni_lux"], cs["dhi_lux"])}


# ---------------------------------------------------------------- the EPW of an annual run
@dataclass(frozen=True)
class WeatherSource:
    """The EPW an annual run uses, and whether it was generated by radtree."""

    path: Path
    generated: bool
    description: str


def _close(a: float, b: float, tol: float = 0.05) -> bool:
    return math.isclose(a, b, abs_tol=tol)


def find_weather(project, epw: Path | None = None) -> WeatherSource:
    """The EPW of an annual run.

    In order: ``epw`` (command line), ``[light] epw`` of the project, a generated EPW shipped
    in ``PROJECT/data/`` (``*generated*.epw`` whose location matches the site), else a clear-sky
    EPW generated now into ``PROJECT/results/annual/weather/`` (an INFO message says so).
    """
    site = project.site
    for cand, why in ((epw, "given on the command line"), (project.light.epw, "[light] epw")):
        if cand is not None:
            p = Path(cand)
            if not p.exists():
                raise ConfigError(f"EPW file not found: {p}", field="light.epw")
            check_epw_site(project, p)
            w = read_epw(p)
            return WeatherSource(p, w.generated, f"{p.name} ({why}"
                                 + (", GENERATED clear sky)" if w.generated else ")"))
    data = project.root / "data"
    for p in sorted(data.glob("*generated*.epw")) if data.is_dir() else []:
        w = read_epw(p)
        if _close(w.latitude, site.latitude) and _close(w.longitude, site.longitude):
            return WeatherSource(p, w.generated,
                                 f"{p.name} (shipped with the project; GENERATED clear sky)")
    out = project.results_dir / "annual" / "weather" / "generated_clear_sky.epw"
    if out.exists():
        w = read_epw(out)
        if (_close(w.latitude, site.latitude) and _close(w.longitude, site.longitude)
                and _close(w.utc_offset_hours, site.utc_offset_hours)
                and _close(w.elevation_m, site.elevation_m, 1.0)):
            return WeatherSource(out, True, f"{out.name} (GENERATED clear sky, cached)")
    log.info(f"  no EPW given: generating a clear-sky year for the site → {out}")
    write_generated_epw(out, site.name, site.latitude, site.longitude, site.elevation_m,
                        site.utc_offset_hours)
    return WeatherSource(out, True, f"{out.name} (GENERATED clear sky for the site)")



#: how the clear sky is made, for records and reports (:mod:`radtree.light.clearsky`)
CLEAR_SKY_SOURCE = ("clear sky (pvlib Ineichen-Perez, Linke turbidity climatology; Perez 1990 "
                    "luminous efficacy)")


def weather_sources(light) -> tuple[str, str]:
    """Where an hour's direct normal and diffuse horizontal illuminance come from, in words,
    for ``[light]`` (``weather``: clear sky, an EPW, or a DNI table and the constant
    ``diffuse_horizontal_lux``)."""
    if light.weather == "table":
        return (f"DNI table {Path(light.direct_normal_table).name}",
                f"[light] diffuse_horizontal_lux = {light.diffuse_horizontal_lux:g} lx (constant)")
    if light.weather == "epw":
        name = f"EPW {Path(light.epw).name}"
        return name, name
    return CLEAR_SKY_SOURCE, CLEAR_SKY_SOURCE
