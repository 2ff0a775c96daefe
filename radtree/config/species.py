"""The species library: one TOML file per species in the top-level ``materials/species/``.

A :class:`Species` holds what radtree needs to build and season a street tree's crown: leaf
optics (photopic fractions 0–1), leaf size (m), leaf-angle distribution and mean leaf tilt
(degrees from horizontal), leaf area index (m² leaf per m² ground) and crown permeability in
leaf and bare, a default crown shape, and the leaf phenology as days of the year (1–365) for
the **northern** hemisphere; in the southern hemisphere the same calendar runs
``southern_shift_days`` (182) days later. Every value carries its source (a citation, or
``"documented default: <why>"``) in :attr:`Species.sources`.

The files read ``field.value = …`` and ``field.source = "…"`` for every field (TOML dotted
keys), plus ``key``, ``name`` and ``common_name``; the leaf's Radiance ``trans`` material is
the ``.rad`` file of the same stem beside it (``tests/test_species.py`` checks that it is what
:meth:`Species.leaf_material` renders).

This module is plain data (layer 2, so that the project reader and the inventory reader can
use it); the crown side lives in :mod:`radtree.trees.species`, which re-exports these names —
import them from there in layer 4 and above::

    from radtree.trees.species import load_species, known_species
    sp = load_species("Platanus x acerifolia")  # or "platanus_x_acerifolia", or "London plane"
    sp.leaf_area_fraction(355, -32.89)          # 1.0: full leaf at the southern summer solstice
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field, fields
from functools import lru_cache
from typing import Any

import numpy as np
import tomllib

from radtree.config.schema import Louvers
from radtree.errors import ConfigError
from radtree.optics import Trans
from radtree.resources import folder

#: de Wit's named leaf-angle distributions and their mean leaf tilt (degrees from horizontal),
#: as tabulated by Bonan, *Climate Change and Terrestrial Ecosystem Modeling* (2019), ch. 2
#: (supplemental program 2.2: planophile 26.76°, erectophile 63.24°, plagiophile 45°,
#: uniform 45°, spherical 57.30°). ``ellipsoidal`` (Campbell 1986) takes its mean from the file.
LEAF_ANGLE_DISTRIBUTIONS: dict[str, float | None] = {
    "planophile": 26.76, "erectophile": 63.24, "plagiophile": 45.0, "uniform": 45.0,
    "spherical": 57.30, "ellipsoidal": None,
}
#: Crown shapes: vertical semi-axis / horizontal radius of the crown spheroid. Documented
#: defaults (shape classes, not measurements): "spherical" 1, "oblate" (wider than tall, the
#: vaulted crowns of street alignments) 0.75, "prolate" (taller than
#: wide: limes, young ash) 1.3. radtree's [tree.crown] default 4.75/5 = 0.95 is near spherical.
CROWN_SHAPES: dict[str, float] = {"spherical": 1.0, "oblate": 0.75, "prolate": 1.3}
SOUTHERN_SHIFT_DAYS = 182
DAYS = 365
_FRACTIONS = ("leaf_reflectance", "leaf_transmittance_diffuse", "leaf_transmittance_global",
              "permeability_leaf_on", "permeability_leaf_off")
_DOYS = ("leaf_out_doy", "full_leaf_doy", "leaf_fall_start_doy", "leaf_fall_end_doy")
_SUBFOLDER = "species"


@dataclass(frozen=True)
class Species:
    """One tree species (see the module docstring for units and conventions).

    ``leaf_transmittance_global`` is the total (direct + diffuse) visible transmittance, ≥ the
    diffuse one; its direct part is what passes a leaf undeviated (edges, gaps within a leaf
    cluster). ``lai_leaf_off`` is the woody (branch) area index of the bare crown.
    ``permeability_*`` is the fraction of light crossing the crown (measured as
    under-crown / open illuminance). Phenology: leaf area 0 before ``leaf_out_doy``, rising
    linearly to full at ``full_leaf_doy``, full until ``leaf_fall_start_doy``, falling linearly
    to 0 (bare branches) at ``leaf_fall_end_doy`` — northern-hemisphere days of the year.
    """

    key: str
    name: str
    common_name: str
    leaf_reflectance: float
    leaf_transmittance_diffuse: float
    leaf_transmittance_global: float
    leaf_size_m: float
    leaf_angle_distribution: str
    mean_leaf_tilt_deg: float
    lai_leaf_on: float
    lai_leaf_off: float
    permeability_leaf_on: float
    permeability_leaf_off: float
    crown_shape: str
    leaf_out_doy: float
    full_leaf_doy: float
    leaf_fall_start_doy: float
    leaf_fall_end_doy: float
    southern_shift_days: float = SOUTHERN_SHIFT_DAYS
    #: between the tropics: "evergreen" (in leaf all year) or "" (not stated: the user gives
    #: the leaf season); optional in the library files
    tropical_phenology: str = ""
    sources: dict[str, str] = field(default_factory=dict, compare=False, hash=False)
    origin: str = field(default="", compare=False)   # the file it was read from

    def _fail(self, name: str, msg: str) -> ConfigError:
        return ConfigError(f"species {self.key!r}: {msg}", source=self.origin or None,
                           field=name)

    def __post_init__(self) -> None:
        if not re.match(r"^[a-z][a-z0-9_]*$", str(self.key)):
            raise self._fail("key", f"got {self.key!r}: use lower-case letters, digits and _")
        for f in fields(self):
            if f.name in ("key", "name", "common_name", "leaf_angle_distribution",
                          "crown_shape", "sources", "origin", "tropical_phenology"):
                continue
            v = getattr(self, f.name)
            if isinstance(v, bool) or not isinstance(v, int | float) or math.isnan(v):
                raise self._fail(f.name, f"got {v!r}, expected a number")
        for name in _FRACTIONS:
            if not 0.0 <= getattr(self, name) <= 1.0:
                raise self._fail(name, f"got {getattr(self, name)}, expected 0 … 1")
        if self.leaf_transmittance_diffuse > self.leaf_transmittance_global:
            raise self._fail("leaf_transmittance_diffuse", "diffuse transmittance "
                             f"{self.leaf_transmittance_diffuse} exceeds the global "
                             f"{self.leaf_transmittance_global}")
        if self.leaf_reflectance + self.leaf_transmittance_global > 1.0:
            raise self._fail("leaf_transmittance_global", "reflectance + global transmittance "
                             "exceeds 1")
        if not 0.0 < self.leaf_size_m <= 1.0:
            raise self._fail("leaf_size_m", f"got {self.leaf_size_m}, expected 0 < m ≤ 1")
        if self.leaf_angle_distribution not in LEAF_ANGLE_DISTRIBUTIONS:
            raise self._fail("leaf_angle_distribution", f"got {self.leaf_angle_distribution!r}"
                             f", expected one of {', '.join(LEAF_ANGLE_DISTRIBUTIONS)}")
        if not 0.0 <= self.mean_leaf_tilt_deg <= 90.0:
            raise self._fail("mean_leaf_tilt_deg", f"got {self.mean_leaf_tilt_deg}, "
                             "expected 0 … 90 degrees")
        if not 0.0 <= self.lai_leaf_off < self.lai_leaf_on <= 15.0:
            raise self._fail("lai_leaf_on", f"expected 0 ≤ lai_leaf_off ({self.lai_leaf_off})"
                             f" < lai_leaf_on ({self.lai_leaf_on}) ≤ 15")
        if self.permeability_leaf_on > self.permeability_leaf_off:
            raise self._fail("permeability_leaf_on", "the crown in leaf "
                             f"({self.permeability_leaf_on}) lets more through than bare "
                             f"({self.permeability_leaf_off})")
        if self.crown_shape not in CROWN_SHAPES:
            raise self._fail("crown_shape", f"got {self.crown_shape!r}, expected one of "
                             f"{', '.join(CROWN_SHAPES)}")
        days = [getattr(self, n) for n in _DOYS]
        if not (1 <= days[0] < days[1] <= days[2] < days[3] <= DAYS):
            raise self._fail("leaf_out_doy", "expected 1 ≤ leaf_out_doy < full_leaf_doy ≤ "
                             "leaf_fall_start_doy < leaf_fall_end_doy ≤ 365 (northern "
                             f"hemisphere days of the year), got {days}")
        if self.tropical_phenology not in ("", "evergreen"):
            raise self._fail("tropical_phenology", f"got {self.tropical_phenology!r}, "
                             "expected \"evergreen\" or leave it out")
        if not 0 <= self.southern_shift_days < DAYS:
            raise self._fail("southern_shift_days", f"got {self.southern_shift_days}, "
                             "expected 0 … 364")
        missing = [f.name for f in fields(self) if f.name not in (
            "key", "name", "common_name", "sources", "origin", "southern_shift_days",
            "tropical_phenology")
            and f.name not in self.sources]
        if missing:
            raise self._fail(missing[0], "no source given (a citation or 'documented "
                             "default: <why>') for " + ", ".join(missing))

    # ------------------------------------------------------------ optics
    @property
    def leaf_transmittance_direct(self) -> float:
        """The undeviated part of the leaf transmittance: global − diffuse."""
        return self.leaf_transmittance_global - self.leaf_transmittance_diffuse

    @property
    def material_name(self) -> str:
        return f"leaf_{self.key}"

    def leaf_material(self) -> Trans:
        """The leaf as a Radiance ``trans``: R, diffuse T, direct (specular) T."""
        return Trans(self.material_name, self.leaf_reflectance,
                     self.leaf_transmittance_diffuse, self.leaf_transmittance_direct)

    @property
    def crown_aspect(self) -> float:
        """Vertical semi-axis / horizontal radius of the default crown shape."""
        return CROWN_SHAPES[self.crown_shape]

    # ------------------------------------------------------------ phenology
    def leaf_area_fractions(self, day_of_year: Any, latitude_deg: float) -> np.ndarray:
        """:meth:`leaf_area_fraction` for an array of (fractional) days of the year."""
        doy = np.asarray(day_of_year, float)
        if latitude_deg < 0:
            doy = doy - self.southern_shift_days
        doy = np.mod(doy - 1.0, DAYS) + 1.0
        xp = [self.leaf_out_doy, self.full_leaf_doy, self.leaf_fall_start_doy,
              self.leaf_fall_end_doy]
        if xp[1] == xp[2]:
            xp[2] += 1e-9
        return np.interp(doy, xp, [0.0, 1.0, 1.0, 0.0], left=0.0, right=0.0)

    def leaf_area_fraction(self, day_of_year: float, latitude_deg: float) -> float:
        """Leaf area relative to full leaf (0 bare … 1 full) on ``day_of_year`` (1–365,
        fractional days allowed) at ``latitude_deg`` (north +; south < 0 shifts the calendar
        by ``southern_shift_days``): linear ramps leaf-out → full leaf and during leaf fall."""
        return float(self.leaf_area_fractions(day_of_year, latitude_deg))

    def lai(self, day_of_year: float, latitude_deg: float) -> float:
        """Leaf + wood area index on that day: bare ``lai_leaf_off`` plus the leaf share."""
        f = self.leaf_area_fraction(day_of_year, latitude_deg)
        return self.lai_leaf_off + f * (self.lai_leaf_on - self.lai_leaf_off)

    def describe(self, latitude_deg: float | None = None) -> str:
        """One line of the species' values; its leaf calendar (day of year) is the northern
        hemisphere's, and at a southern ``latitude_deg`` the line also gives the days
        shifted by ``southern_shift_days`` that the site uses."""
        return (f"{self.name} ({self.common_name}): leaf R {self.leaf_reflectance:g}, "
                f"T diffuse {self.leaf_transmittance_diffuse:g} / global "
                f"{self.leaf_transmittance_global:g}, tilt {self.mean_leaf_tilt_deg:g}° "
                f"({self.leaf_angle_distribution}), LAI {self.lai_leaf_on:g} in leaf / "
                f"{self.lai_leaf_off:g} bare, permeability {self.permeability_leaf_on:g} / "
                f"{self.permeability_leaf_off:g}; leaves out day {self.leaf_out_doy:g}, full "
                f"{self.full_leaf_doy:g}, fall {self.leaf_fall_start_doy:g}–"
                f"{self.leaf_fall_end_doy:g} (northern hemisphere)" + self._southern(latitude_deg))

    def _southern(self, latitude_deg: float | None) -> str:
        if latitude_deg is None or latitude_deg >= 0:
            return ""
        days = [(d + self.southern_shift_days - 1) % DAYS + 1 for d in (
            self.leaf_out_doy, self.full_leaf_doy, self.leaf_fall_start_doy,
            self.leaf_fall_end_doy)]
        return (f", at this southern site {self.southern_shift_days:g} days later: leaves out "
                f"day {days[0]:g}, full {days[1]:g}, fall {days[2]:g}–{days[3]:g}")


# ---------------------------------------------------------------- the library
def _normal(text: str) -> str:
    """A name folded for lookup: lower case, hybrid sign ×/x and punctuation dropped."""
    t = str(text).strip().lower().replace("×", " ")
    t = re.sub(r"\bx\b", " ", t)
    return re.sub(r"[^a-z0-9]+", "", t)


def parse_species(data: dict[str, Any], origin: str = "") -> Species:
    """A :class:`Species` from the TOML ``data`` of one library file."""
    kwargs: dict[str, Any] = {}
    sources: dict[str, str] = {}
    for f in fields(Species):
        if f.name in ("sources", "origin"):
            continue
        if f.name not in data:
            if f.name in ("southern_shift_days", "tropical_phenology"):
                continue
            raise ConfigError("missing", source=origin or None, field=f.name)
        raw = data[f.name]
        if isinstance(raw, dict):
            unknown = sorted(set(raw) - {"value", "source"})
            if unknown or "value" not in raw or not isinstance(raw.get("source"), str):
                raise ConfigError("expected value = …, source = \"…\"", source=origin or None,
                                  field=f.name)
            kwargs[f.name], sources[f.name] = raw["value"], raw["source"]
        else:
            kwargs[f.name] = raw
    unknown = sorted(set(data) - {f.name for f in fields(Species)})
    if unknown:
        raise ConfigError("unknown field (known: " + ", ".join(
            f.name for f in fields(Species) if f.name not in ("sources", "origin")) + ")",
            source=origin or None, field=unknown[0])
    return Species(sources=sources, origin=origin, **kwargs)


@lru_cache(maxsize=1)
def _library() -> dict[str, Species]:
    out: dict[str, Species] = {}
    node = folder("materials") / _SUBFOLDER
    for item in sorted(node.iterdir(), key=lambda p: p.name):
        if not item.name.endswith(".toml"):
            continue
        origin = f"materials/{_SUBFOLDER}/{item.name}"
        try:
            data = tomllib.loads(item.read_text(encoding="utf-8"))
        except tomllib.TOMLDecodeError as exc:
            raise ConfigError(f"not valid TOML: {exc}", source=origin) from None
        sp = parse_species(data, origin)
        if sp.key != item.name.removesuffix(".toml"):
            raise ConfigError(f"key {sp.key!r} differs from the file name", source=origin,
                              field="key")
        out[sp.key] = sp
    return out


def known_species() -> list[str]:
    """The keys of the shipped species, sorted (e.g. ``"platanus_x_acerifolia"``)."""
    return sorted(_library())


def species_library() -> dict[str, Species]:
    """Every shipped species by key."""
    return dict(_library())


def find_species(key_or_name: str) -> Species | None:
    """The species of key, scientific or common name (case-insensitive; see
    :func:`load_species`), None when the library has none such."""
    want = _normal(key_or_name)
    for sp in _library().values():
        if want in (_normal(sp.key), _normal(sp.name), _normal(sp.common_name)):
            return sp
    return None


def unknown_species_message(key_or_name: str) -> str:
    """"unknown species 'X' (known: key (Name); …)"."""
    lib = _library()
    listed = "; ".join(f"{k} ({lib[k].name})" for k in sorted(lib))
    return f"unknown species {key_or_name!r} (known: {listed})"


def load_species(key_or_name: str) -> Species:
    """The species of key (``"tilia_cordata"``), scientific name (``"Platanus × acerifolia"``,
    ``"platanus x acerifolia"``) or common name (``"London plane"``), case-insensitive.
    Unknown → :class:`ConfigError` listing the known species."""
    sp = find_species(key_or_name)
    if sp is None:
        raise ConfigError(unknown_species_message(key_or_name), field="species")
    return sp


# ---------------------------------------------------------------- crown defaults
def louvers_cover_fraction(permeability: float, direct_transmittance: float,
                           layers: int) -> float:
    """The cover fraction f of each of ``layers`` slat layers whose direct transmission
    ((1 − f) + f·T_direct)^layers equals ``permeability`` (clamped 0–1): the louvers model's
    own optics (:mod:`radtree.trees.louvers`) solved for f."""
    per_layer = permeability ** (1.0 / layers)
    if direct_transmittance >= 1.0:
        return 1.0
    return min(1.0, max(0.0, (1.0 - per_layer) / (1.0 - direct_transmittance)))


def tree_defaults(sp: Species, given: dict[str, dict[str, Any]] | None = None
                  ) -> dict[str, dict[str, float]]:
    """The ``[tree.*]`` fields a species fills where the project does not give them:
    table → field → value (leaf optics, slat inclination = mean leaf tilt, permeability).

    ``given``: the values the project gives (table → field → value); the louvers cover
    fraction is solved (:func:`louvers_cover_fraction`) for the slat optics and layer count in
    use — given or filled — so that the crown passes the species' leaf-on permeability (for
    the ``volume`` arrangement too, whose crossings then default to ``layers``; not when it
    gives ``crossings``: that density is the project's, e.g. calibrated)."""
    t = sp.leaf_transmittance_global
    louvers: dict[str, float] = {
        "reflectance": sp.leaf_reflectance, "transmittance": t,
        "specular_fraction": sp.leaf_transmittance_direct / t if t > 0 else 0.0,
        "inclination_deg": sp.mean_leaf_tilt_deg}
    used = {**louvers, **(given or {}).get("louvers", {})}
    try:
        explicit_density = (used.get("arrangement", Louvers.arrangement) == "volume"
                            and float(used.get("crossings", Louvers.crossings)) > 0)
    except (TypeError, ValueError):
        explicit_density = False
    if explicit_density:      # a volume crown of given crossings: its density is set
        return _other_tables(sp, louvers)
    try:
        layers = int(used.get("layers", Louvers.layers))
        direct = float(used["transmittance"]) * float(used["specular_fraction"])
    except (TypeError, ValueError):   # a bad given value: the reader reports it
        layers, direct = Louvers.layers, sp.leaf_transmittance_direct
    louvers["cover_fraction"] = round(louvers_cover_fraction(
        sp.permeability_leaf_on, direct, max(layers, 1)), 4)
    return _other_tables(sp, louvers)


def _other_tables(sp: Species, louvers: dict[str, float]) -> dict[str, dict[str, float]]:
    return {
        "louvers": louvers,
        "homogeneous": {"reflectance": sp.leaf_reflectance,
                        "permeability": sp.permeability_leaf_on},
        "perforated": {"reflectance": sp.leaf_reflectance,
                       "openness": sp.permeability_leaf_on},
    }
