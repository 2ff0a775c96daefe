"""When the deciduous crown is in leaf, and when the offices are occupied.

**Leaf schedule.** A binary switch: the crown is the leafed model (louvers) from the
``leaf_on`` date (inclusive) to the ``leaf_off`` date (exclusive), and bare branches
otherwise. Dates are ``MM-DD``; when ``leaf_on`` comes after ``leaf_off`` in the calendar
(southern hemisphere) the leafed season wraps over the new year.

The dates (:func:`leaf_season`), in order: given on the command line
(``radtree annual --leaf-on MM-DD --leaf-off MM-DD``); ``[tree] leaf_on`` / ``leaf_off`` of the
project; else the species' phenology (``[tree] species``) in the site's hemisphere — in leaf
from the middle of its leaf-out ramp to the middle of its leaf fall, the southern calendar
``southern_shift_days`` later. Between the tropics a deciduous calendar does not apply: the
species must state ``tropical_phenology = "evergreen"`` (in leaf all year), else the user gives
the dates. Leaf growth and leaf fall are gradual; the switch puts each transition on one date.
With ``[tree] species`` the annual run uses the species' hourly phenology instead
(:mod:`radtree.annual.phenology`: leaf area ramps, Beer's-law weights between the leafed and
the bare crown); ``--dates`` keeps this switch.

**Occupancy.** Hours whose middle lies in ``[start, end)`` local standard time, every day of
the year (default 8:00–18:00: the ten hours 8–9 … 17–18). Occupied hours before sunrise or
after sunset count with 0 lx, as in IES LM-83.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from datetime import date, timedelta
from typing import Any

import numpy as np

from radtree.errors import ConfigError

DATE_RE = re.compile(r"^(\d{2})-(\d{2})$")
#: latitude of the tropics (degrees): inside, no temperate leaf calendar is assumed
TROPIC_DEG = 23.44
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

    leaf_on: str
    leaf_off: str
    #: where the dates came from, for reports
    source: str = "given"

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
                f"days; {self.source}), bare branches otherwise")


def _mmdd(doy: float) -> str:
    d = date(_YEAR, 1, 1) + timedelta(days=int(round(doy - 1)) % 365)
    return f"{d.month:02d}-{d.day:02d}"


def leaf_season(project: Any, leaf_on: str | None = None, leaf_off: str | None = None
                ) -> LeafSchedule:
    """The leaf season of ``project`` (module text): the given dates, ``[tree] leaf_on`` /
    ``leaf_off``, else the species' phenology in the site's hemisphere; ConfigError when
    none applies (no species, or a species without a stated behaviour between the tropics)."""
    if (leaf_on is None) != (leaf_off is None):
        raise ConfigError("give both --leaf-on and --leaf-off (MM-DD), or neither")
    if leaf_on is not None:
        return LeafSchedule(leaf_on, leaf_off, "given on the command line")  # type: ignore[arg-type]
    tree = project.tree
    if tree.leaf_on is not None:
        return LeafSchedule(tree.leaf_on, tree.leaf_off, "[tree] leaf_on / leaf_off")
    species = tree.species or _inventory_species(project)
    if species is None:
        raise ConfigError("no leaf season: give [tree] species (its phenology sets the season "
                          "in the site's hemisphere) or [tree] leaf_on / leaf_off (or "
                          "--leaf-on / --leaf-off)", source=str(project.source), field="tree")
    from radtree.trees.species import load_species

    sp = load_species(species)
    lat = project.site.latitude
    if abs(lat) < TROPIC_DEG:
        if sp.tropical_phenology == "evergreen":
            return LeafSchedule("01-01", "12-31",
                                f"{sp.name}: evergreen between the tropics (species library)")
        raise ConfigError(f"latitude {lat:g} lies between the tropics, where the temperate leaf "
                          f"calendar of {sp.name} does not apply and the library states no "
                          "tropical behaviour: give [tree] leaf_on / leaf_off (MM-DD; e.g. the "
                          "dry season bare) or --leaf-on / --leaf-off",
                          source=str(project.source), field="tree.leaf_on")
    shift = sp.southern_shift_days if lat < 0 else 0.0
    on = (sp.leaf_out_doy + sp.full_leaf_doy) / 2.0 + shift
    off = (sp.leaf_fall_start_doy + sp.leaf_fall_end_doy) / 2.0 + shift
    hemi = "southern" if lat < 0 else "northern"
    return LeafSchedule(_mmdd(on), _mmdd(off),
                        f"the phenology of {sp.name} in the {hemi} hemisphere: mid leaf-out "
                        "to mid leaf-fall")


def _inventory_species(project: Any) -> str | None:
    """The most common library species of a district inventory (None without one)."""
    if project.district is None or project.district.trees is None:
        return None
    from collections import Counter

    from radtree.config.species import find_species
    from radtree.site.district import load_district

    known = Counter(sp.key for t in load_district(project).trees
                    if (sp := find_species(t.species)) is not None)
    return known.most_common(1)[0][0] if known else None


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
