"""Sun position, computed once in radtree and handed to everything else.

Uses pvlib's implementation of the NREL Solar Position Algorithm (SPA). Angles in degrees:
altitude above the horizon (apparent, i.e. with atmospheric refraction), azimuth clockwise
from north (compass). Vectors in the scene frame: x east, y north, z up.
"""

from __future__ import annotations

import functools
import importlib.util
import math
from dataclasses import dataclass
from datetime import datetime, timedelta, timezone, tzinfo
from functools import lru_cache
from pathlib import Path
from types import ModuleType

import numpy as np

SUN_HALF_ANGLE_DEG = 0.2665  # the sun's disc subtends 0.533°
SUN_ANGLE_DEG = 2.0 * SUN_HALF_ANGLE_DEG  # the disc's full angle, 0.533° (a Radiance source's)
SUN_SOLID_ANGLE_SR = 2.0 * math.pi * (1.0 - math.cos(math.radians(SUN_HALF_ANGLE_DEG)))


@dataclass(frozen=True)
class SunPosition:
    """Where the sun is at one instant.

    ``altitude_deg`` is the apparent altitude (refraction included), ``azimuth_deg`` the compass
    azimuth (clockwise from north).
    """

    altitude_deg: float
    azimuth_deg: float

    @property
    def vector(self) -> np.ndarray:
        """Unit vector towards the sun, x east, y north, z up."""
        return direction_vector(self.altitude_deg, self.azimuth_deg)

    @property
    def radiance_azimuth_deg(self) -> float:
        """Azimuth in Radiance's ``gendaylit -ang`` convention: degrees west of south."""
        return compass_to_radiance_azimuth(self.azimuth_deg)

    @property
    def above_horizon(self) -> bool:
        return self.altitude_deg > 0.0


def direction_vector(altitude_deg: float, azimuth_deg: float) -> np.ndarray:
    """Unit vector for an altitude and a compass azimuth (x east, y north, z up)."""
    alt = math.radians(altitude_deg)
    az = math.radians(azimuth_deg)
    return np.array([math.sin(az) * math.cos(alt), math.cos(az) * math.cos(alt), math.sin(alt)])


def compass_to_radiance_azimuth(azimuth_deg: float) -> float:
    """Compass azimuth (clockwise from north) → Radiance azimuth (degrees west of south)."""
    a = azimuth_deg - 180.0
    return (a + 180.0) % 360.0 - 180.0


def local_datetime(date: str, time: str, zone: float | tzinfo) -> datetime:
    """A timezone-aware local civil clock datetime from ``YYYY-MM-DD`` and ``HH:MM``.

    ``zone``: a fixed UTC offset in hours, or a tzinfo (an IANA zone: daylight saving
    applied, e.g. 09:00 on 21 June in ``Europe/Madrid`` is UTC+2)."""
    tz = zone if isinstance(zone, tzinfo) else timezone(timedelta(hours=zone))
    return datetime.fromisoformat(f"{date}T{time}").replace(tzinfo=tz)


@functools.lru_cache(maxsize=4096)   # every scenario and crown realisation asks for the same hours
def sun_position(
    when: datetime, latitude: float, longitude: float, elevation_m: float = 0.0
) -> SunPosition:
    """Sun position (NREL SPA via pvlib) for a timezone-aware datetime.

    ``longitude`` in degrees east (west negative), ``latitude`` north positive. Remembered
    per instant and place (a diagnosis asks for the same hours hundreds of times).
    """
    if when.tzinfo is None:
        raise ValueError("sun_position needs a timezone-aware datetime")
    return _spa(when, float(latitude), float(longitude), float(elevation_m))


#: pvlib.solarposition.spa_python's defaults: pressure (hPa), temperature (°C), ΔT (s),
#: atmospheric refraction at sunrise/sunset (degrees), threads
SPA_DEFAULTS = (101325.0 / 100.0, 12.0, 67.0, 0.5667, 4)


@lru_cache(maxsize=4096)
def _spa(when: datetime, latitude: float, longitude: float, elevation_m: float) -> SunPosition:
    """``pvlib.solarposition.spa_python`` at one instant with its defaults, called on pvlib's
    SPA module directly (the same numbers: ``tests/test_solar.py``)."""
    pressure, temperature, delta_t, refraction, threads = SPA_DEFAULTS
    _app_zenith, _zenith, app_elevation, _elevation, azimuth, _eot = _spa_module().solar_position(
        np.array([when.timestamp()]), latitude, longitude, elevation_m, pressure, temperature,
        delta_t, refraction, threads)
    return SunPosition(altitude_deg=float(app_elevation[0]), azimuth_deg=float(azimuth[0]))


@functools.cache
def _spa_module() -> ModuleType:
    """pvlib's NREL SPA (``pvlib/spa.py``: NumPy only) loaded on its own. ``import pvlib``
    imports the whole package (≈ 1.2 s, SciPy included) in every process that needs one
    sun position; the SPA module alone loads in milliseconds."""
    found = importlib.util.find_spec("pvlib")
    path = (Path(found.submodule_search_locations[0]) / "spa.py"
            if found is not None and found.submodule_search_locations else None)
    if path is None or not path.is_file():   # an unusual install: the package's own import
        from pvlib import spa

        return spa
    spec = importlib.util.spec_from_file_location("radtree._pvlib_spa", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def angular_separation_deg(a: np.ndarray, b: np.ndarray) -> float:
    """Angle between two direction vectors, degrees."""
    a = np.asarray(a, float) / np.linalg.norm(a)
    b = np.asarray(b, float) / np.linalg.norm(b)
    return math.degrees(math.acos(float(np.clip(np.dot(a, b), -1.0, 1.0))))


def daylight_hours(latitude: float, longitude: float, elevation_m: float, zone: float | tzinfo,
                   date: str, min_altitude_deg: float = 0.0, step_min: int = 60) -> list[str]:
    """The local civil clock times ``HH:MM`` of ``date`` (every ``step_min`` minutes from
    00:00) with the sun's centre (apparent, refraction included) above ``min_altitude_deg``."""
    out = []
    for m in range(0, 24 * 60, step_min):
        t = f"{m // 60:02d}:{m % 60:02d}"
        sun = sun_position(local_datetime(date, t, zone), latitude, longitude, elevation_m)
        if sun.altitude_deg > min_altitude_deg:
            out.append(t)
    return out
