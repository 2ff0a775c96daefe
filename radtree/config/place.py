"""The place of a project: the site (location, time zone, date, hours), the street canyon and
the light (weather source, sky) — typed dataclasses validated on creation.

Lengths in metres, angles in degrees (azimuth clockwise from north), illuminance in lux, times
as local civil clock ``HH:MM`` (:mod:`radtree.config.timezone`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from datetime import tzinfo
from pathlib import Path
from typing import Any, ClassVar

from radtree.config.spec import Checked, line_azimuth, meta

SKY_CHOICES = ("none", "perez")
#: where the hours' direct normal and diffuse illuminance come from (:class:`Light`)
WEATHER_CHOICES = ("clear-sky", "epw", "table")


def positive(default: float) -> Any:
    """A field of a number > 0 with ``default``."""
    return field(default=default, metadata=meta(0.0, lo_open=True))


def fraction(default: float) -> Any:
    """A field of a number in [0, 1] with ``default``."""
    return field(default=default, metadata=meta(0.0, 1.0))


_positive, _fraction = positive, fraction


@dataclass(frozen=True)
class Site(Checked):
    """Place and times: latitude north +, longitude east + (west negative), elevation m.

    ``time_zone``: an IANA name (``"Europe/Madrid"``: daylight saving applied) or a fixed
    offset (``"UTC+1"``); ``hours`` are local civil clock times on ``date``
    (:mod:`radtree.config.timezone`). ``utc_offset_hours`` is the zone's *standard-time*
    offset on ``date`` (the time base of EPW files), derived from ``time_zone``; a file may
    give it instead of ``time_zone`` (a fixed offset).
    """

    TABLE: ClassVar[str] = "site"
    name: str
    latitude: float = field(metadata=meta(-90, 90))
    longitude: float = field(metadata=meta(-180, 180))
    elevation_m: float = field(metadata=meta(-500, 9000))
    utc_offset_hours: float = field(metadata=meta(-14, 14, switch=False))
    date: str = field(metadata=meta(kind="date"))
    hours: tuple[str, ...] = field(metadata=meta(kind="times", switch=False))
    time_zone: str = field(default="", metadata=meta(switch=False))

    def check(self) -> None:
        from radtree.config.timezone import fixed_name, parse_time_zone

        if not self.time_zone:
            object.__setattr__(self, "time_zone", fixed_name(self.utc_offset_hours))
        try:
            parse_time_zone(self.time_zone)
        except ValueError as exc:
            raise self.fail("time_zone", str(exc)) from None

    @property
    def tzinfo(self) -> tzinfo:
        """The zone of the site's clock times (daylight saving applied for IANA names)."""
        from radtree.config.timezone import parse_time_zone

        return parse_time_zone(self.time_zone)


@dataclass(frozen=True)
class Street(Checked):
    """An east–west (by default) street canyon.

    ``facade_azimuth_deg`` is the compass direction the studied façade looks towards (its
    outward normal): 0 = north. The façade lies at the canyon's side y' = 0 of a local frame
    rotated by that azimuth; the opposite façade is ``width_m`` away. ``ground_reflectance`` is
    a constant, or in the file the path of a per-hour table (then ``ground_reflectance_table``).
    """

    TABLE: ClassVar[str] = "street"
    width_m: float = _positive(20.0)
    length_m: float = _positive(80.0)
    facade_azimuth_deg: float = field(default=0.0, metadata=meta(-360, 360))
    facade_reflectance: float = _fraction(0.9)
    building_height_m: float = _positive(15.0)
    opposite_building_height_m: float = _positive(15.0)
    opposite_reflectance: float = _fraction(0.35)
    ground_reflectance: float = field(default=0.15, metadata=meta(0.0, 1.0, path_ok=True))
    ground_reflectance_table: Path | None = field(default=None, metadata=meta(kind="-"))
    #: where the studied façade stands, [[x1, y1], [x2, y2]] in the site frame (m, x east,
    #: y north; the façade looks to the right of x1 → x2, radtree.site.placement); None: the
    #: façade plane passes through the site origin (hand-written projects) or, with an
    #: inventory, it is placed by radtree.site.placement
    facade_line: tuple[tuple[float, float], tuple[float, float]] | None = field(
        default=None, metadata=meta(kind="line", switch=False))

    def check(self) -> None:
        if self.facade_line is None:
            return
        az = line_azimuth(self.facade_line)
        given = self.facade_azimuth_deg
        if given != 0.0 and abs((given - az + 180.0) % 360.0 - 180.0) > 1.0:
            raise self.fail("facade_azimuth_deg", f"got {given:g}°, but facade_line "
                            f"{[list(p) for p in self.facade_line]} looks {az:.1f}° (to the "
                            "right of its first point → second): leave facade_azimuth_deg "
                            "out, or list the line's points the other way round")
        object.__setattr__(self, "facade_azimuth_deg", az)   # the line's: one orientation


@dataclass(frozen=True)
class Light(Checked):
    """Sun and sky inputs: where each hour's direct normal and diffuse illuminance come from.

    ``weather``: ``clear-sky`` (no file: pvlib's Ineichen–Perez clear sky with pvlib's Linke
    turbidity climatology at the site, Perez et al. 1990 luminous efficacy →
    :mod:`radtree.light.clearsky`), ``epw`` (a weather file, ``epw``; checked against
    ``[site]``) or ``table`` (a DNI table ``time,direct_normal_lux`` in lux, ``direct_normal``).
    Left out: ``epw`` when an EPW is given, ``table`` when a DNI table is, else ``clear-sky``.
    ``sky``: ``none`` = sun only, or ``perez`` = Perez sky of the hour's diffuse horizontal
    illuminance (from the weather; a DNI table gives none, then ``diffuse_horizontal_lux``).
    """

    TABLE: ClassVar[str] = "light"
    direct_normal_table: Path | None = field(default=None, metadata=meta(
        toml="direct_normal", switch=False))
    epw: Path | None = field(default=None, metadata=meta(switch=False))
    sky: str = field(default="none", metadata=meta(choices=SKY_CHOICES))
    diffuse_horizontal_lux: float = field(default=12000.0, metadata=meta(0.0, 150000.0))
    weather: str = field(default="", metadata=meta(choices=("", ) + WEATHER_CHOICES,
                                                   switch=False))

    def check(self) -> None:
        given = {"epw": self.epw is not None, "table": self.direct_normal_table is not None}
        if given["epw"] and given["table"]:
            raise self.fail("epw", "both an EPW and a DNI table (direct_normal) are given: "
                            "keep one")
        inferred = "epw" if given["epw"] else "table" if given["table"] else "clear-sky"
        if not self.weather:
            object.__setattr__(self, "weather", inferred)
        elif self.weather == "clear-sky" and inferred != "clear-sky":
            raise self.fail("weather", f"weather = 'clear-sky' needs no file, but "
                            f"{'epw' if given['epw'] else 'direct_normal'} is given: delete "
                            "one of the two")
        elif self.weather in ("epw", "table") and not given[self.weather]:
            key = "epw" if self.weather == "epw" else "direct_normal"
            raise self.fail("weather", f"weather = {self.weather!r} needs {key} = \"…\" "
                            "(or use weather = 'clear-sky')")
