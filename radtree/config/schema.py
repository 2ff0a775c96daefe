"""The project's typed dataclasses, validated on creation (:class:`radtree.config.spec.Checked`).

Lengths in metres, angles in degrees (azimuth clockwise from north), illuminance in lux, times
as local clock ``HH:MM``. Bounds, choices and TOML names are field metadata (:func:`meta`).
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

from radtree.config.bsdf import REPRESENTATIONS, CrownBsdf
from radtree.config.clumping import clumping_fields
from radtree.config.crown_models import CROWN_MODELS
from radtree.config.engine import EngineParams
from radtree.config.honeybee import HoneybeeSite
from radtree.config.limits import Limits
from radtree.config.params_hash import params_hashes, plain
from radtree.config.photo import INCLINATION_DISTRIBUTIONS, photo_fields
from radtree.config.place import (
    SKY_CHOICES,
    Light,
    Site,
    Street,
    fraction,
    positive,
)
from radtree.config.spec import TIME_RE, Checked, meta
from radtree.errors import ConfigError

TREE_FORMS = ("dome", "free")
LOUVER_ARRANGEMENTS = ("layers", "volume")
_PHOTO = photo_fields()
_CLUMPING = clumping_fields()
REFLECTION_MODES = ("traced", "calculated")
WALL_POLICIES = ("clip", "refuse")    # a crown reaching a wall (radtree.trees.wall_policy)
POINTS_BEAMS = ("scan_angle", "vertical")   # airborne [tree] points (radtree.trees.points_crown)
#: Presets of the louvers slat optics (the switch ``"louvers.reading"``): the study's reading
#: (every layer fully covered, T 0.5 in the slat) and near-opaque leaves with open gaps.
LOUVER_READINGS: dict[str, dict[str, float]] = {
    "study": {"cover_fraction": 1.0, "transmittance": 0.5, "reflectance": 0.11},
    "gap": {"cover_fraction": 0.5, "transmittance": 0.05, "reflectance": 0.11,
            "specular_fraction": 0.0}}


_positive, _fraction = positive, fraction


# ---------------------------------------------------------------- dataclasses
@dataclass(frozen=True)
class Dome(Checked):
    """Dome form: a hemisphere of ``radius_m`` centred on the sensor grid, flat side on the wall."""

    TABLE: ClassVar[str] = "tree.dome"
    radius_m: float = _positive(4.0)
    segments: int = 48


@dataclass(frozen=True)
class Crown(Checked):
    """Free-standing crowns: spheroids on trunks in a row along the façade.

    Trunk ``trunk_distance_m`` from the façade, trees every ``spacing_m`` (``count`` trees,
    centred on the sensors), crown of horizontal radius ``radius_m`` and vertical semi-axis
    ``vertical_radius_m``, crown base ``base_height_m`` above the street; the crown is clipped
    ``clearance_m`` from the façade plane.
    """

    TABLE: ClassVar[str] = "tree.crown"
    trunk_distance_m: float = _positive(3.0)
    spacing_m: float = _positive(8.0)
    count: int = field(default=3, metadata=meta(1, 50))
    radius_m: float = _positive(5.0)
    vertical_radius_m: float = _positive(4.75)
    base_height_m: float = _positive(3.0)
    clearance_m: float = field(default=0.0, metadata=meta(0.0))
    trunk_diameter_m: float = _positive(0.45)
    segments: int = 32


@dataclass(frozen=True)
class Homogeneous(Checked):
    """One translucent sheet. ``transmittance`` None → chosen so the crown passes ``permeability``
    (T in the dome form, crossed once; √permeability for a free crown, crossed twice)."""

    TABLE: ClassVar[str] = "tree.homogeneous"
    transmittance: float | None = field(default=None, metadata=meta(0.0, 1.0))
    reflectance: float = _fraction(0.11)
    permeability: float = _fraction(0.055)

    def check(self) -> None:
        if self.transmittance is not None and self.transmittance + self.reflectance > 1:
            raise self.fail("transmittance", "reflectance + transmittance exceeds 1")


@dataclass(frozen=True)
class Perforated(Checked):
    """Opaque sheet (leaf reflectance) with holes where the photo shows sky.

    ``photo`` a fisheye image (with ``lens`` and ``mask`` = cx,cy,r px), else a seeded random
    gap pattern of ``openness`` (``seed``). ``realisations``: how many random gap patterns
    (``seed``, ``seed`` + 1, …) ``simulate`` traces and averages, as for the louvers; without a
    photo only (a photo is one fixed pattern). The shared ``[tree] photo`` wins over ``photo``.
    """

    TABLE: ClassVar[str] = "tree.perforated"
    photo: Path | None = None
    lens: str = "equidistant"
    mask: tuple[float, float, float] | None = field(default=None, metadata=meta(kind="mask"))
    openness: float = _fraction(0.06)
    reflectance: float = _fraction(0.11)
    resolution: int = 64
    seed: int = 1
    realisations: int = field(default=1, metadata=meta(1, 64))


@dataclass(frozen=True)
class Louvers(Checked):
    """Inclined translucent leaf slats in ``layers`` filtration stages.

    Each slat is a ``slat_size_m`` square inclined ``inclination_deg`` (leaf inclination), slat
    centres on a triangular grid along branches inclined ``branch_inclination_deg``; each layer
    covers ``cover_fraction`` of the horizontal plane. Slat optics: reflectance, total
    transmittance, and the fraction of that transmittance that is specular (undeviated).

    ``arrangement`` (free-standing crowns only): ``"layers"`` — nested lens-shaped layers, every
    vertical line crosses ``layers`` slats; ``"volume"`` — slat centres uniform at random in the
    crown, azimuths random, density such that a vertical line through the crown centre crosses
    ``crossings`` slats on average (0: use ``layers``), times ``cover_fraction``.
    ``realisations``: how many random crowns (``seed``, ``seed`` + 1, …; each traced with
    its own ``engine.seed`` + k − 1) ``simulate`` traces and averages; the results'
    ``lux_stderr`` is then the standard error over them.
    """

    TABLE: ClassVar[str] = "tree.louvers"
    layers: int = field(default=4, metadata=meta(1, 20))
    slat_size_m: float = field(default=0.3, metadata=meta(0.02, 3.0))
    inclination_deg: float = field(default=30.0, metadata=meta(0.0, 90.0))
    branch_inclination_deg: float = 40.0
    cover_fraction: float = _fraction(1.0)
    reflectance: float = _fraction(0.11)
    transmittance: float = _fraction(0.5)
    specular_fraction: float = _fraction(0.9)
    seed: int = 1
    arrangement: str = field(default="layers", metadata=meta(choices=LOUVER_ARRANGEMENTS))
    crossings: float = field(default=0.0, metadata=meta(0.0, 60.0))
    realisations: int = field(default=1, metadata=meta(1, 64))
    # volume slats: one inclination, or drawn from Campbell's ellipsoidal distribution of
    # parameter ellipsoid_x (radtree.config.photo; fitted to an upward photo)
    inclination_distribution: str = field(default="fixed", metadata=meta(
        choices=INCLINATION_DISTRIBUTIONS))
    ellipsoid_x: float = field(default=1.0, metadata=meta(0.05, 20.0))
    # volume slats grouped in clusters of clumping index Ω (radtree.config.clumping)
    clumping: float = _CLUMPING["clumping"]
    cluster_radius_m: float = _CLUMPING["cluster_radius_m"]
    clumping_fit: bool = _CLUMPING["clumping_fit"]

    def check(self) -> None:
        if self.reflectance + self.transmittance > 1:
            raise self.fail("transmittance", f"reflectance {self.reflectance} + transmittance "
                            f"{self.transmittance} exceeds 1")


@dataclass(frozen=True)
class Tree(Checked):
    """The crown: its ``form`` (``dome`` | ``free``), one table per crown model and the crown's
    photograph (``photo``, ``lens``, ``mask``, ``photo_direction``, …: :mod:`radtree.config.photo`)."""

    TABLE: ClassVar[str] = "tree"
    form: str = field(default="dome", metadata=meta(choices=TREE_FORMS))
    dome: Dome = field(default_factory=Dome)
    crown: Crown = field(default_factory=Crown)
    homogeneous: Homogeneous = field(default_factory=Homogeneous)
    perforated: Perforated = field(default_factory=Perforated)
    louvers: Louvers = field(default_factory=Louvers)
    #: a species of the library (materials/species/, key or name): fills the leaf optics, slat
    #: inclination and permeability that the [tree.*] tables leave out (radtree.config.species)
    species: str | None = field(default=None, metadata=meta(switch=False))
    # the crown's photograph, shared by the crown models (radtree.config.photo)
    photo: Path | None = _PHOTO["photo"]
    lens: str = _PHOTO["lens"]
    mask: tuple[float, float, float] | None = _PHOTO["mask"]
    photo_direction: str = _PHOTO["photo_direction"]
    photo_x_m: float = _PHOTO["photo_x_m"]
    photo_distance_m: float = _PHOTO["photo_distance_m"]
    photo_height_m: float = _PHOTO["photo_height_m"]
    photo_zenith_deg: float = _PHOTO["photo_zenith_deg"]
    accept_poor_fit: bool = _PHOTO["accept_poor_fit"]
    representation: str = field(default="explicit", metadata=meta(choices=REPRESENTATIONS))
    bsdf: CrownBsdf = field(default_factory=CrownBsdf)
    #: the leaf season (``MM-DD``) of annual runs and exports, both or neither: when left out
    #: it comes from the species' phenology and the site's hemisphere (radtree.annual.schedule)
    leaf_on: str | None = field(default=None, metadata=meta(switch=False))
    leaf_off: str | None = field(default=None, metadata=meta(switch=False))
    #: a crown reaching a wall: ``clip`` it at the wall (a note gives the crown volume removed,
    #: % per tree) or ``refuse`` (ConfigError with the trunk move or crown radius that fits);
    #: the same in row, inventory and Honeybee projects (radtree.trees.wall_policy)
    wall_policy: str = field(default="clip", metadata=meta(choices=WALL_POLICIES))
    #: one tree's points (LAS/LAZ with its ground): free louvers crowns filled voxel by voxel
    #: with its plant area density (radtree.trees.points_crown) — with representation =
    #: "turbid", turbid voxel crowns of that density (radtree.trees.turbid_voxels); voxel size
    #: in m (None: 5 point spacings)
    points: Path | None = field(default=None)
    points_voxel_m: float | None = field(default=None, metadata=meta(0.05, 20.0))
    #: a crown as a voxel grid of plant area density, for representation = "turbid" (CSV with
    #: columns x_m, y_m, z_m — voxel centres in m from the trunk base, x along the façade, y
    #: away from it, z up — and pad_m2_m3, m²/m³; voxels left out are empty: the format of
    #: radtree.trees.voxel_file); placed on every trunk of the free row
    voxels: Path | None = field(default=None)
    #: the voxel side of ``voxels`` in m (None: the smallest spacing of the centres)
    voxels_size_m: float | None = field(default=None, metadata=meta(0.01, 20.0))
    #: the terrestrial scan positions of ``points`` (TOML of [[scan]] tables,
    #: radtree.lidar.tls): the inversion then follows every beam from its scanner, the shots
    #: without return included; voxel size ``points_voxel_m`` or 1 m (None: airborne,
    #: vertical beams)
    points_scans: Path | None = field(default=None)
    #: airborne ``points`` (no ``points_scans``): follow each beam from its LAS scan angle and
    #: flight line (``scan_angle``; vertical columns when the file's angles do not give the
    #: beams, radtree.lidar.scan_angle) or take every beam as vertical (``vertical``)
    points_beams: str = field(default="scan_angle", metadata=meta(choices=POINTS_BEAMS))

    def check(self) -> None:
        if self.voxels is not None and self.points is not None:
            raise self.fail("voxels", "give tree.voxels or tree.points, not both")
        if self.voxels is not None and self.representation != "turbid":
            raise self.fail("voxels", f"a voxel crown is a turbid medium: set representation = "
                            f"\"turbid\" (got {self.representation!r}), or use tree.points "
                            "for slats")
        if (self.leaf_on is None) != (self.leaf_off is None):
            raise self.fail("leaf_on" if self.leaf_on is None else "leaf_off",
                            "give both leaf_on and leaf_off (MM-DD), or neither")
        for name in ("leaf_on", "leaf_off"):
            v = getattr(self, name)
            if v is not None and not re.match(r"^(0[1-9]|1[0-2])-(0[1-9]|[12]\d|3[01])$", v):
                raise self.fail(name, f"got {v!r}, expected MM-DD such as '04-15'")


@dataclass(frozen=True)
class Sensors(Checked):
    """The façade sensor circle: ``count`` points at equal angle steps on a ``radius_m`` circle
    centred ``height_m`` above the street and ``offset_m`` off the wall, normal out of the wall.
    Rows by height: top third ``higher``, middle ``intermediate``, bottom ``lower``. The dense
    façade map grid (``dense_*``) is traced at ``dense_hours`` only (empty = every hour).

    ``heights_m`` (a list, e.g. ``[1.5, 4.5, 7.5]``: one circle, and one dense map, per
    storey) replaces ``height_m`` when given; each height is checked like ``height_m``. With
    two or more heights the grids are named ``facade@<h>m`` / ``facade_map@<h>m`` (``h`` as
    written, e.g. ``facade@4.5m``) and every sensor carries its ``storey``: the height's index
    in the list (write the list from the ground up: storey 0 = the lowest). ``height_m`` still
    places what needs one point (the sensor dome, the crown photo's camera, the wall cap's
    sensor point) and picks the circle the report compares (the nearest height)."""

    TABLE: ClassVar[str] = "sensors"
    height_m: float = _positive(5.0)
    count: int = field(default=8, metadata=meta(1, 10000))
    radius_m: float = _positive(0.25)
    offset_m: float = _positive(0.01)
    x_m: float = 0.0
    dense_grid: bool = True
    dense_size_m: float = _positive(6.0)
    dense_spacing_m: float = _positive(0.5)
    dense_hours: tuple[str, ...] = field(default=(), metadata=meta(kind="times", switch=False))
    heights_m: tuple[float, ...] | None = field(default=None, metadata=meta(
        0.0, lo_open=True, kind="numbers", switch=False))

    def check(self) -> None:
        if self.heights_m is not None and len(set(self.heights_m)) != len(self.heights_m):
            raise self.fail("heights_m", f"got {list(self.heights_m)}: a height is given twice")

    @property
    def levels(self) -> tuple[float, ...]:
        """The circles' centre heights above the street (m): ``heights_m``, else ``height_m``."""
        return tuple(self.heights_m) if self.heights_m else (self.height_m,)


@dataclass(frozen=True)
class Office(Checked):
    """A block of offices in the studied façade (the building application, reference case §5).

    ``bays`` × ``storeys`` identical offices (any counts, even too), each ``width_m`` wide,
    ``height_m`` high (floor to ceiling) and ``depth_m`` deep, with a glazed façade towards
    the street; the block is centred on ``sensors.x_m``. Storey ``k`` (0 = ground) has its
    floor at ``ground_floor_m + k·storey_height_m``. The glazing's measured normal
    transmittance ``glazing_transmittance`` becomes a Radiance ``glass`` transmissivity;
    ``frame_fraction`` of each façade opening is opaque frame. Results are read in the
    ``rooms``: ``"all"`` (default) or a list of ``"STOREY-BAY"`` names — storey 0 = the ground
    floor (lowest), bay 0 = the leftmost office seen from the street (smallest u), e.g.
    ``["0-1", "1-1"]``. Work plane at ``workplane_height_m``, grids at ``grid_spacing_m``
    spacing, ``wall_offset_m`` from the walls.
    """

    TABLE: ClassVar[str] = "office"
    bays: int = field(default=3, metadata=meta(1, 21))
    storeys: int = field(default=3, metadata=meta(1, 21))
    width_m: float = _positive(3.0)
    height_m: float = _positive(2.5)
    depth_m: float = _positive(6.0)
    storey_height_m: float = _positive(2.5)
    ground_floor_m: float = 1.25
    glazing_transmittance: float = field(default=0.8, metadata=meta(0.0, 0.9183, lo_open=True))
    frame_fraction: float = _fraction(0.1)
    window_sill_m: float = 0.0
    window_head_m: float = 2.5
    floor_reflectance: float = _fraction(0.2)
    wall_reflectance: float = _fraction(0.5)
    ceiling_reflectance: float = _fraction(0.7)
    workplane_height_m: float = 0.8
    grid_spacing_m: float = _positive(0.5)
    wall_offset_m: float = 0.5
    facade_grid_spacing_m: float = _positive(0.5)
    rooms: str | tuple[str, ...] = field(default="all", metadata=meta(kind="rooms",
                                                                       switch=False))

    def check(self) -> None:
        for name in self.room_names:
            k, j = (int(v) for v in name.split("-"))
            if k >= self.storeys or j >= self.bays:
                raise self.fail("rooms", f"got room {name!r}: the block has storeys 0–"
                                f"{self.storeys - 1} and bays 0–{self.bays - 1} ('STOREY-BAY', "
                                "storey 0 = ground floor)")
        if self.height_m > self.storey_height_m:
            raise self.fail("height_m", f"office height {self.height_m} m exceeds the storey "
                            f"height {self.storey_height_m} m")

    @property
    def room_names(self) -> tuple[str, ...]:
        """The sensed rooms ``"STOREY-BAY"``, storey by storey from the ground, bay by bay."""
        if self.rooms == "all":
            return tuple(f"{k}-{j}" for k in range(self.storeys) for j in range(self.bays))
        return tuple(self.rooms)


@dataclass(frozen=True)
class Scenario(Checked):
    """One simulated case: a crown model, how ground-reflected light is handled, sky on/off.

    ``switches`` maps dotted keys (``"louvers.layers"``, ``"engine.ab"``,
    ``"reflection.unfiltered"``, …) to values; each key and value is checked on creation
    against the one registry, :mod:`radtree.config.switches`."""

    TABLE: ClassVar[str] = "scenario"
    name: str
    model: str = field(metadata=meta(choices=CROWN_MODELS))
    reflection: str = field(default="traced", metadata=meta(choices=REFLECTION_MODES))
    sky: str | None = field(default=None, metadata=meta(choices=SKY_CHOICES))
    form: str | None = field(default=None, metadata=meta(choices=TREE_FORMS))
    description: str = ""
    switches: dict[str, Any] = field(default_factory=dict)
    #: the scenario without trees the report measures the trees' effect against (issue 38);
    #: default: the one scenario of model ``none``
    baseline: bool = field(default=False, metadata=meta(switch=False))

    #: the registry's check of a ``switches`` table; :mod:`radtree.config.switches` installs
    #: it on import (the registry is built from these dataclasses, so it cannot be imported here)
    switch_check: ClassVar[Callable[[dict[str, Any]], None] | None] = None

    def check(self) -> None:
        if Scenario.switch_check is None:   # pragma: no cover - config/__init__ installs it
            raise RuntimeError("radtree.config.switches was not imported")
        Scenario.switch_check(self.switches)


@dataclass(frozen=True)
class Project:
    """A loaded project file: its tables, scenarios and where it lives (``root``)."""

    name: str
    root: Path
    source: Path
    site: Site
    street: Street
    light: Light
    tree: Tree
    sensors: Sensors
    engine: EngineParams
    scenarios: tuple[Scenario, ...]
    measured: Path | None = None
    measured_rows: Path | None = None
    office: Office | None = None
    extra_geometry: tuple[tuple[Path, str], ...] = ()
    honeybee: HoneybeeSite | None = None   # [site] honeybee (radtree.config.honeybee)
    limits: Limits = field(default_factory=Limits)
    district: Any = None   # radtree.config.district.District: [site] trees / buildings

    @property
    def build_dir(self) -> Path:
        return self.root / "build"

    @property
    def results_dir(self) -> Path:
        return self.root / "results"

    @property
    def report_dir(self) -> Path:
        return self.root / "report"

    def scenario(self, name: str) -> Scenario:
        for s in self.scenarios:
            if s.name == name:
                return s
        raise ConfigError(f"no scenario named {name!r} (have: "
                          f"{', '.join(s.name for s in self.scenarios)})", source=str(self.source))

    def to_dict(self) -> dict[str, Any]:
        """Every table as plain data; ``engine`` flat, as the project file holds it."""
        return {**plain(self), "engine": plain(self.engine.flat())}

    def params_hash(self, scenario: Scenario) -> str:
        """Short hash of everything that changes a scenario's numbers (input files by their
        path relative to the project folder and their content): :mod:`.params_hash`."""
        return self.params_hashes([scenario])[scenario.name]

    def params_hashes(self, scenarios: list[Scenario]) -> dict[str, str]:
        """``{scenario name: params_hash}``, the project's part read once for all."""
        return params_hashes(self, scenarios)


def parse_time(value: Any, where: str = "time", source: str | None = None) -> str:
    """Validate a local clock time ``HH:MM`` (24 h)."""
    if not isinstance(value, str) or not TIME_RE.match(value):
        raise ConfigError(f"got {value!r}, expected a local clock time HH:MM such as '10:30'",
                          source=source, field=where)
    return value
