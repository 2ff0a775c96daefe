"""The crown of each hour: leaf area ramping, leaf fall and bare branches from the species.

Without a species the annual run keeps its binary switch
(:class:`radtree.annual.schedule.LeafSchedule`: each day leafed or bare). With ``[tree]
species`` the crown of hour h holds the fraction f(h) of its full leaf area given by
:meth:`radtree.trees.species.Species.leaf_area_fraction` (linear ramps from leaf-out to full
leaf and through leaf fall, 0 when bare; the southern hemisphere's calendar 182 days on), at
the hour's fractional day of the year t = day + (hour − 12)/24 (local standard time, hour the
middle of the hour, so noon of day d is t = d).

Two crowns are traced — in full leaf and bare (branches) — and the hour's illuminance lies
between them. Beer's law in the leaf area gives where: the crown passes
P(f) = P_bare · exp(−k·f·L) with L = ``lai_leaf_on − lai_leaf_off`` (the leaf area index
added to the bare wood) and k = 0.5 (the projection of spherically distributed leaves,
vertical view), so the share of the leafed-minus-bare difference the hour takes is

    w(f) = (1 − exp(−k·f·L)) / (1 − exp(−k·L))        (w(0) = 0, w(1) = 1)

and E(h) = E_bare(h) + w(f(h)) · (E_leaf(h) − E_bare(h)). Leaves first added block more
than the last ones (w > f in between): half the leaf area of the reference case's crown
(L = 5.80 − 1.39 = 4.41) already blocks 75 % of what the full crown blocks over the bare one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from radtree.annual.schedule import LeafSchedule, day_of_year
from radtree.config import Project
from radtree.trees.species import Species, load_species

#: the leaf projection coefficient of Beer's law used for the weights (spherical, vertical)
K_BEER = 0.5


@dataclass(frozen=True)
class Phenology:
    """The hourly crown state of ``species`` at ``latitude_deg`` (north +)."""

    species: Species
    latitude_deg: float

    @classmethod
    def of(cls, species: str, latitude_deg: float) -> Phenology:
        return cls(load_species(species), latitude_deg)

    @property
    def leaf_area(self) -> float:
        """L: the leaf area index the leaves add to the bare crown (m²/m²)."""
        return self.species.lai_leaf_on - self.species.lai_leaf_off

    def leaf_fraction(self, month: np.ndarray, day: np.ndarray, hour: np.ndarray
                      ) -> np.ndarray:
        """f per hour (0 bare … 1 full leaf) for the hours' month, day and mid-hour (h)."""
        t = day_of_year(month, day) + (np.asarray(hour, float) - 12.0) / 24.0
        return self.species.leaf_area_fractions(t, self.latitude_deg)

    def weight(self, fraction: np.ndarray) -> np.ndarray:
        """w(f): the share of the leafed − bare illuminance difference (module text)."""
        kl = K_BEER * self.leaf_area
        return -np.expm1(-kl * np.asarray(fraction, float)) / -math.expm1(-kl)

    def describe(self) -> str:
        sp = self.species
        hemi = "southern" if self.latitude_deg < 0 else "northern"
        shift = sp.southern_shift_days if self.latitude_deg < 0 else 0
        days = [int((d - 1 + shift) % 365) + 1 for d in (
            sp.leaf_out_doy, sp.full_leaf_doy, sp.leaf_fall_start_doy, sp.leaf_fall_end_doy)]
        return (f"in leaf by the phenology of {sp.name} ({sp.common_name}, "
                f"materials/species/{sp.key}.toml) in the {hemi} hemisphere: leaves out from "
                f"day {days[0]}, full leaf day {days[1]}, leaf fall days {days[2]}–{days[3]} "
                f"(linear ramps of leaf area); each hour weighs the leafed and the bare crown by "
                f"Beer's law in leaf area (k {K_BEER}, leaf area index "
                f"{self.leaf_area:.2f} over the bare {sp.lai_leaf_off:g})")


def phenology_of(project: Project, enabled: bool = True) -> Phenology | None:
    """The species phenology of an annual run: with ``[tree] species`` unless not ``enabled``
    or the site lies between the tropics (then the dates of
    :func:`radtree.annual.schedule.leaf_season` apply)."""
    if project.tree.species is None or not enabled:
        return None
    from radtree.annual.schedule import TROPIC_DEG

    if abs(project.site.latitude) < TROPIC_DEG:   # no temperate ramps: the leaf season's dates
        return None
    return Phenology.of(project.tree.species, project.site.latitude)


def blend(leaf_on: np.ndarray, leaf_off: np.ndarray, weight: np.ndarray) -> np.ndarray:
    """E_bare + w · (E_leaf − E_bare) per hour: ``leaf_on``/``leaf_off`` (sensors, hours)."""
    w = np.asarray(weight, np.float64)[None, :]
    off = leaf_off.astype(np.float64)
    return (off + w * (leaf_on.astype(np.float64) - off)).astype(leaf_on.dtype)


def crown_year(total: dict[str, dict[str, np.ndarray]], direct: dict[str, dict[str, np.ndarray]],
               grids: list[str], wea: Any, leaf: LeafSchedule, phen: Phenology | None
               ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
    """Fill ``total["with"]`` and ``direct["with"]`` (grid → (sensors, hours)) from the leafed
    and bare crowns: by ``leaf``'s dates (each day one or the other), or with ``phen`` hour by
    hour (:func:`blend`). Returns (in leaf per hour — f ≥ 0.5 with ``phen`` —, f, w)."""
    if phen is None:
        in_leaf = leaf.in_leaf(wea.month, wea.day)
        for store in (total, direct):
            store["with"] = {g: np.where(in_leaf[None, :], store["leaf_on"][g],
                                         store["leaf_off"][g]) for g in grids}
        return in_leaf, None, None
    fraction = phen.leaf_fraction(wea.month, wea.day, wea.hour)
    weight = phen.weight(fraction)
    for store in (total, direct):
        store["with"] = {g: blend(store["leaf_on"][g], store["leaf_off"][g], weight)
                         for g in grids}
    return fraction >= 0.5, fraction, weight
