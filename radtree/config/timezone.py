"""The site's time zone: an IANA name (daylight saving applied) or a fixed UTC offset.

``[site] time_zone`` is written either as an IANA time-zone name (``"Europe/Madrid"``,
``"America/Argentina/Buenos_Aires"``; the standard library's :mod:`zoneinfo`, with the ``tzdata``
package as its database where the system has none) or as a fixed offset from UTC
(``"UTC+1"``, ``"UTC-3"``, ``"UTC+05:30"``, ``"+09:30"``; no daylight saving). The older
``utc_offset_hours = -3`` is the fixed offset ``"UTC-3"``.

Project hours (``[site] hours``) are **local civil clock time** on ``[site] date``: with an
IANA zone, 09:00 on 21 June in Madrid is 09:00 CEST (UTC+2). Weather files keep *local
standard time* (EPW rows; the zone's offset without daylight saving):
:func:`standard_offset_hours` gives it for the date.
"""

from __future__ import annotations

import re
from datetime import date as _date
from datetime import datetime, timedelta, timezone, tzinfo
from functools import lru_cache

from radtree.errors import ConfigError

_OFFSET_RE = re.compile(r"^(?:UTC|GMT)?\s*([+-])(\d{1,2})(?::?(\d{2}))?$", re.IGNORECASE)
_HINT = ("an IANA time-zone name such as 'Europe/Madrid' (daylight saving applied) or a fixed "
         "offset such as 'UTC+1' or 'UTC-03:30'")


def fixed_name(hours: float) -> str:
    """The canonical text of a fixed offset: ``UTC+1``, ``UTC-3``, ``UTC+5:30``."""
    sign = "+" if hours >= 0 else "-"
    minutes = round(abs(hours) * 60)
    h, m = divmod(minutes, 60)
    return f"UTC{sign}{h}" + (f":{m:02d}" if m else "")


@lru_cache(maxsize=256)
def parse_time_zone(text: str) -> tzinfo:
    """The tzinfo of ``text`` (IANA name or fixed offset); ValueError with the expected forms."""
    if not isinstance(text, str) or not text.strip():
        raise ValueError(f"got {text!r}, expected {_HINT}")
    t = text.strip()
    if t.upper() in ("UTC", "GMT", "Z"):
        return timezone.utc
    m = _OFFSET_RE.match(t)
    if m:
        sign = -1 if m.group(1) == "-" else 1
        hours, minutes = int(m.group(2)), int(m.group(3) or 0)
        if hours > 14 or minutes >= 60 or hours * 60 + minutes > 14 * 60:
            raise ValueError(f"got {text!r}: offsets lie between UTC-14 and UTC+14")
        return timezone(sign * timedelta(hours=hours, minutes=minutes))
    from zoneinfo import ZoneInfo, ZoneInfoNotFoundError

    try:
        return ZoneInfo(t)
    except (ZoneInfoNotFoundError, ValueError, OSError):
        raise ValueError(f"got {text!r}: not a known IANA time zone nor a UTC offset; "
                         f"expected {_HINT}") from None


def is_fixed(text: str) -> bool:
    """True when ``text`` is a fixed offset (no daylight saving)."""
    return isinstance(parse_time_zone(text), timezone)


def offset_hours(tz: tzinfo, when: datetime) -> float:
    """UTC offset of civil time at ``when`` (naive local or aware), hours."""
    local = when.replace(tzinfo=tz)
    off = local.utcoffset()
    return 0.0 if off is None else off.total_seconds() / 3600.0


def dst_hours(tz: tzinfo, when: datetime) -> float:
    """Daylight-saving shift in force at local ``when``, hours (0 for fixed offsets)."""
    d = when.replace(tzinfo=tz).dst()
    return 0.0 if d is None else d.total_seconds() / 3600.0


def standard_offset_hours(text: str, on: str | None = None) -> float:
    """The zone's standard-time offset (without daylight saving) on date ``on`` (YYYY-MM-DD;
    default 1 January 2023), hours: the time base of EPW files."""
    tz = parse_time_zone(text)
    day = _date.fromisoformat(on) if on else _date(2023, 1, 1)
    noon = datetime(day.year, day.month, day.day, 12)
    return offset_hours(tz, noon) - dst_hours(tz, noon)


def site_time_zone(time_zone: str | None, utc_offset_hours: float | None, *,
                   source: str | None = None) -> tuple[str, float | None]:
    """``[site]``'s zone text from ``time_zone`` and/or the older ``utc_offset_hours``:
    (canonical text, the fixed offset or None). Both given and disagreeing, or neither
    given → ConfigError naming the fields and the fix."""
    if time_zone is None and utc_offset_hours is None:
        raise ConfigError("missing: give time_zone (" + _HINT + ")", source=source,
                          field="site.time_zone")
    if time_zone is None:
        return fixed_name(float(utc_offset_hours)), float(utc_offset_hours)  # type: ignore[arg-type]
    try:
        tz = parse_time_zone(time_zone)
    except ValueError as exc:
        raise ConfigError(str(exc), source=source, field="site.time_zone") from None
    if utc_offset_hours is not None:
        std = standard_offset_hours(time_zone)
        if abs(std - float(utc_offset_hours)) > 1e-6:
            raise ConfigError(
                f"time_zone {time_zone!r} (standard time UTC{std:+g} h) disagrees with "
                f"utc_offset_hours = {utc_offset_hours:g}: keep time_zone and delete "
                "utc_offset_hours", source=source, field="site.utc_offset_hours")
    fixed = tz.utcoffset(None).total_seconds() / 3600.0 if isinstance(tz, timezone) else None
    return time_zone.strip(), fixed
