"""When the deciduous crown is in leaf, and when the offices are occupied.

**Leaf schedule.** A binary switch: the crown is the leafed model (louvers) from the
``leaf_on`` date (inclusive) to the ``leaf_off`` date (exclusive), and bare branches
otherwise. Dates are ``MM-DD``; when ``leaf_on`` comes after ``leaf_off`` in the calendar
(southern hemisphere) the leafed season wraps over the new year.

Defaults for white mulberry (*Morus alba*) street trees in Mendoza (Cuyo region, ≈ 33° S,
irrigated urban forest) — an **assumption** from the species' phenology in the southern
hemisphere, not a measurement: buds break in September and the canopy is fully developed by
**mid-October** (``10-15``); leaves yellow in April–May and are shed with the first frosts,
the crowns being bare from about **1 June** (``06-01``). Leaf growth and leaf fall are
gradual; the switch puts the whole transition on one date, so dates are parameters
(``radtree annual --leaf-on MM-DD --leaf-off MM-DD``). Measured seasonal permeabilities of
Mendoza's street trees (e.g. Cantón, Cortegoso & de Rosa 1994, *Energy and Buildings* 20)
are the place to calibrate both the dates and the bare crown. With ``[tree] species`` the
annual run uses the species' hourly phenology instead (:mod:`radtree.annual.phenology`: leaf
area ramps, Beer's-law weights between the leafed and the bare crown); ``--dates`` keeps this
switch.

**Occupancy.** Hours whose middle lies in ``[start, end)`` local standard time, every day of
the year (default 8:00–18:00: the ten hours 8–9 … 17–18). Occupied hours before sunrise or
after sunset count with 0 lx, as in IES LM-83.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from datetime import date

import numpy as np

from radtree.errors import ConfigError

DATE_RE = re.compile(r"^(\d{2})-(\d{2})$")
DEFAULT_LEAF_ON = "10-15"
DEFAULT_LEAF_OFF = "06-01"
DEFAULT_OCCUPANCY = (8.0, 18.0)
_YEAR = 2023  # a non-leap year: day numbers 1…365


def parse_month_day(value: str, what: str = "date") -> tuple[int, int]:
    """``MM-DD`` → (month, day), validated against a non-leap year."""
    m = DATE_RE.match(str(value).strip())
    if not m:
        raise ConfigError(f"{what}: got {value!r}, expected MM-DD such as '10-15'")
    month, day = int(m.group(1)), int(m.group(2))
    try:
        date(_YEAR, month, day)
    except ValueError as exc:
        raise ConfigError(f"{what}: {value!r} is not a day of a (non-leap) year") from exc
    return month, day


def day_of_year(month: np.ndarray | int, day: np.ndarray | int) -> np.ndarray:
    starts = np.cumsum([0, 31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30])
    return starts[np.asarray(month) - 1] + np.asarray(day)


@dataclass(frozen=True)
class LeafSchedule:
    """Leaf-on from ``leaf_on`` (inclusive) to ``leaf_off`` (exclusive), ``MM-DD``."""

    leaf_on: str = DEFAULT_LEAF_ON
    leaf_off: str = DEFAULT_LEAF_OFF

    def __post_init__(self) -> None:
        on = parse_month_day(self.leaf_on, "leaf-on date")
        off = parse_month_day(self.leaf_off, "leaf-off date")
        if on == off:
            raise ConfigError(f"leaf-on and leaf-off dates are the same ({self.leaf_on})")

    def in_leaf(self, month: np.ndarray | int, day: np.ndarray | int) -> np.ndarray:
        """True where the crown is in leaf on that (month, day)."""
        doy = day_of_year(month, day)
        on = int(day_of_year(*parse_month_day(self.leaf_on)))
        off = int(day_of_year(*parse_month_day(self.leaf_off)))
        if on < off:
            return (doy >= on) & (doy < off)
        return (doy >= on) | (doy < off)

    def leaf_days(self) -> int:
        d = np.arange(1, 366)
        months = np.searchsorted(np.cumsum([31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31]),
                                 d, side="left") + 1
        starts = np.cumsum([0, 31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30])
        return int(self.in_leaf(months, d - starts[months - 1]).sum())

    def describe(self) -> str:
        return (f"in leaf from {self.leaf_on} to {self.leaf_off} (MM-DD, {self.leaf_days()} "
                "days), bare branches otherwise")


def parse_occupancy(value: str | tuple[float, float]) -> tuple[float, float]:
    """``"8-18"`` (or ``"8:30-17"``) → (8.0, 18.0) hours of local standard time."""
    if isinstance(value, tuple):
        start, end = float(value[0]), float(value[1])
    else:
        parts = str(value).split("-")
        if len(parts) != 2:
            raise ConfigError(f"occupancy: got {value!r}, expected START-END such as '8-18'")

        def hours(text: str) -> float:
            t = text.strip()
            try:
                if ":" in t:
                    hh, mm = t.split(":")
                    return int(hh) + int(mm) / 60.0
                return float(t)
            except ValueError as exc:
                raise ConfigError(f"occupancy: {text!r} is not an hour") from exc

        start, end = hours(parts[0]), hours(parts[1])
    if not 0.0 <= start < end <= 24.0:
        raise ConfigError(f"occupancy: got {start:g}–{end:g} h, expected 0 ≤ start < end ≤ 24")
    return start, end


def occupied(hour_mid: np.ndarray, occupancy: tuple[float, float]) -> np.ndarray:
    """True for hours whose middle (decimal local standard time) lies in [start, end)."""
    h = np.asarray(hour_mid, float)
    return (h >= occupancy[0]) & (h < occupancy[1])
