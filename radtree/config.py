"""The project file ``radtree.toml`` loaded into typed, validated dataclasses.

Every invalid field raises :class:`radtree.errors.ConfigError` naming the file, the field, the
value found and what was expected. Lengths in metres, angles in degrees (azimuth clockwise from
north), illuminance in lux, times as local clock ``HH:MM``.
"""

from __future__ import annotations

import hashlib
import json
import math
import re
from dataclasses import asdict, dataclass, field, fields, is_dataclass, replace
from datetime import date as _date
from pathlib import Path
from typing import Any

import tomllib

from radtree.errors import ConfigError

TIME_RE = re.compile(r"^([01]\d|2[0-3]):([0-5]\d)$")
CROWN_MODELS = ("homogeneous", "perforated", "louvers", "none")
TREE_FORMS = ("dome", "free")
LOUVER_ARRANGEMENTS = ("layers", "volume")
REFLECTION_MODES = ("traced", "calculated")
SKY_CHOICES = ("none", "perez")
ENGINES = ("auto", "radiance", "numpy", "forward")


# ---------------------------------------------------------------- field readers
class _Reader:
    """Reads one TOML table, remembering the dotted path for error messages."""

    def __init__(self, data: dict, path: str, source: str):
        if not isinstance(data, dict):
            raise ConfigError(f"expected a table, got {type(data).__name__}", source=source,
                              field=path)
        self.data, self.path, self.source = data, path, source
        self.used: set[str] = set()

    def _name(self, key: str) -> str:
        return f"{self.path}.{key}" if self.path else key

    def error(self, key: str, msg: str) -> ConfigError:
        return ConfigError(msg, source=self.source, field=self._name(key))

    def has(self, key: str) -> bool:
        return key in self.data

    def sub(self, key: str, required: bool = False) -> _Reader:
        self.used.add(key)
        if key not in self.data:
            if required:
                raise self.error(key, "missing table")
            return _Reader({}, self._name(key), self.source)
        return _Reader(self.data[key], self._name(key), self.source)

    def raw(self, key: str, default: Any = None) -> Any:
        self.used.add(key)
        return self.data.get(key, default)

    def number(self, key: str, default: float | None = None, *, lo: float | None = None,
               hi: float | None = None, lo_open: bool = False, required: bool = False) -> float:
        self.used.add(key)
        if key not in self.data:
            if required or default is None:
                raise self.error(key, "missing (a number is required)")
            value = default
        else:
            value = self.data[key]
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self.error(key, f"expected a number, got {value!r}")
        value = float(value)
        if math.isnan(value) or math.isinf(value):
            raise self.error(key, f"expected a finite number, got {value}")
        if lo is not None and (value < lo or (lo_open and value <= lo)):
            raise self.error(key, f"got {value}, expected {'>' if lo_open else '≥'} {lo}")
        if hi is not None and value > hi:
            raise self.error(key, f"got {value}, expected ≤ {hi}")
        return value

    def integer(self, key: str, default: int | None = None, *, lo: int | None = None,
                hi: int | None = None) -> int:
        self.used.add(key)
        value = self.data.get(key, default)
        if value is None:
            raise self.error(key, "missing (an integer is required)")
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.error(key, f"expected an integer, got {value!r}")
        if lo is not None and value < lo:
            raise self.error(key, f"got {value}, expected ≥ {lo}")
        if hi is not None and value > hi:
            raise self.error(key, f"got {value}, expected ≤ {hi}")
        return int(value)

    def string(self, key: str, default: str | None = None, *,
               choices: tuple[str, ...] | None = None) -> str:
        self.used.add(key)
        value = self.data.get(key, default)
        if value is None:
            raise self.error(key, "missing (a text value is required)")
        if not isinstance(value, str):
            raise self.error(key, f"expected text, got {value!r}")
        if choices is not None and value not in choices:
            raise self.error(key, f"got {value!r}, expected one of {', '.join(choices)}")
        return value

    def boolean(self, key: str, default: bool) -> bool:
        self.used.add(key)
        value = self.data.get(key, default)
        if not isinstance(value, bool):
            raise self.error(key, f"expected true or false, got {value!r}")
        return value

    def optional_path(self, key: str, base: Path, *, must_exist: bool = True) -> Path | None:
        self.used.add(key)
        value = self.data.get(key)
        if value is None:
            return None
        if not isinstance(value, str) or not value:
            raise self.error(key, f"expected a file path, got {value!r}")
        p = (base / value).resolve() if not Path(value).is_absolute() else Path(value)
        if must_exist and not p.exists():
            raise self.error(key, f"file not found: {p}")
        return p

    def check_unknown(self) -> None:
        unknown = sorted(set(self.data) - self.used)
        if unknown:
            raise self.error(unknown[0], f"unknown field (known here: {', '.join(sorted(self.used))})")


def parse_time(value: Any, where: str = "time", source: str | None = None) -> str:
    """Validate a local clock time ``HH:MM`` (24 h)."""
    if not isinstance(value, str) or not TIME_RE.match(value):
        raise ConfigError(f"got {value!r}, expected a local clock time HH:MM such as '10:30'",
                          source=source, field=where)
    return value


# ---------------------------------------------------------------- dataclasses
@dataclass(frozen=True)
class Site:
    """Place and times: latitude north +, longitude east + (west negative), UTC offset hours."""

    name: str
    latitude: float
    longitude: float
    elevation_m: float
    utc_offset_hours: float
    date: str
    hours: tuple[str, ...]


@dataclass(frozen=True)
class Street:
    """An east–west (by default) street canyon.

    ``facade_azimuth_deg`` is the compass direction the studied façade looks towards (its
    outward normal): 0 = north. The façade lies at the canyon's side y' = 0 of a local frame
    rotated by that azimuth; the opposite façade is ``width_m`` away.
    """

    width_m: float = 20.0
    length_m: float = 80.0
    facade_azimuth_deg: float = 0.0
    facade_reflectance: float = 0.9
    building_height_m: float = 15.0
    opposite_building_height_m: float = 15.0
    opposite_reflectance: float = 0.35
    ground_reflectance: float = 0.15
    ground_reflectance_table: Path | None = None


@dataclass(frozen=True)
class Light:
    """Sun and sky inputs: a DNI table (``time,direct_normal_lux``) or an EPW file.

    ``sky``: ``none`` = sun only (the study's set-up) or ``perez`` = clear-sky Perez sky of
    ``diffuse_horizontal_lux`` (a stated substitute: the study gives no diffuse values).
    """

    direct_normal_table: Path | None = None
    epw: Path | None = None
    sky: str = "none"
    diffuse_horizontal_lux: float = 12000.0


@dataclass(frozen=True)
class Dome:
    """Study form: hemisphere of ``radius_m`` centred on the sensor grid, flat side on the wall."""

    radius_m: float = 4.0
    segments: int = 48


@dataclass(frozen=True)
class Crown:
    """Free-standing crowns: spheroids on trunks in a row along the façade.

    Trunk ``trunk_distance_m`` from the façade, trees every ``spacing_m`` (``count`` trees,
    centred on the sensors), crown of horizontal radius ``radius_m`` and vertical semi-axis
    ``vertical_radius_m``, crown base ``base_height_m`` above the street; the crown is clipped
    ``clearance_m`` from the façade plane.
    """

    trunk_distance_m: float = 3.0
    spacing_m: float = 8.0
    count: int = 3
    radius_m: float = 5.0
    vertical_radius_m: float = 4.75
    base_height_m: float = 3.0
    clearance_m: float = 0.0
    trunk_diameter_m: float = 0.45
    segments: int = 32


@dataclass(frozen=True)
class Homogeneous:
    """One translucent sheet. ``transmittance`` None → chosen so the crown passes ``permeability``
    (T in the dome form, crossed once; √permeability for a free crown, crossed twice)."""

    transmittance: float | None = None
    reflectance: float = 0.11
    permeability: float = 0.055


@dataclass(frozen=True)
class Perforated:
    """Opaque sheet (leaf reflectance) with holes where the photo shows sky.

    ``photo`` a fisheye image (with ``lens`` and ``mask`` = cx,cy,r px), else a seeded random
    gap pattern of ``openness``.
    """

    photo: Path | None = None
    lens: str = "equidistant"
    mask: tuple[float, float, float] | None = None
    openness: float = 0.06
    reflectance: float = 0.11
    resolution: int = 64


@dataclass(frozen=True)
class Louvers:
    """Inclined translucent leaf slats in ``layers`` filtration stages.

    Each slat is a ``slat_size_m`` square inclined ``inclination_deg`` (leaf inclination), slat
    centres on a triangular grid along branches inclined ``branch_inclination_deg``; each layer
    covers ``cover_fraction`` of the horizontal plane. Slat optics: reflectance, total
    transmittance, and the fraction of that transmittance that is specular (undeviated).

    ``arrangement`` (free-standing crowns only): ``"layers"`` — nested lens-shaped layers, every
    vertical line crosses ``layers`` slats; ``"volume"`` — slat centres uniform at random in the
    crown, azimuths random, density such that a vertical line through the crown centre crosses
    ``crossings`` slats on average (0: use ``layers``), times ``cover_fraction``.
    ``realisations``: how many random crowns (``seed``, ``seed`` + 1, …) ``simulate`` traces
    and averages; the results' ``lux_stderr`` is then the standard error over them.
    """

    layers: int = 4
    slat_size_m: float = 0.3
    inclination_deg: float = 30.0
    branch_inclination_deg: float = 40.0
    cover_fraction: float = 1.0
    reflectance: float = 0.11
    transmittance: float = 0.5
    specular_fraction: float = 0.9
    seed: int = 1
    arrangement: str = "layers"
    crossings: float = 0.0
    realisations: int = 1


@dataclass(frozen=True)
class Tree:
    form: str = "dome"
    dome: Dome = field(default_factory=Dome)
    crown: Crown = field(default_factory=Crown)
    homogeneous: Homogeneous = field(default_factory=Homogeneous)
    perforated: Perforated = field(default_factory=Perforated)
    louvers: Louvers = field(default_factory=Louvers)


@dataclass(frozen=True)
class Sensors:
    """The façade sensor circle: ``count`` points at equal angle steps on a ``radius_m`` circle
    centred ``height_m`` above the street and ``offset_m`` off the wall, normal out of the wall.
    Rows by height: top third ``higher``, middle ``intermediate``, bottom ``lower``. The dense
    façade map grid (``dense_*``) is traced at ``dense_hours`` only (empty = every hour)."""

    height_m: float = 5.0
    count: int = 8
    radius_m: float = 0.25
    offset_m: float = 0.01
    x_m: float = 0.0
    dense_grid: bool = True
    dense_size_m: float = 6.0
    dense_spacing_m: float = 0.5
    dense_hours: tuple[str, ...] = ()


@dataclass(frozen=True)
class Office:
    """A block of offices in the studied façade (the building application, SPEC.md §5).

    ``bays`` × ``storeys`` identical offices, each ``width_m`` wide, ``height_m`` high (floor to
    ceiling) and ``depth_m`` deep, with a glazed façade towards the street. Storey ``k`` (0 =
    ground) has its floor at ``ground_floor_m + k·storey_height_m``. The glazing's measured
    normal transmittance ``glazing_transmittance`` becomes a Radiance ``glass`` transmissivity;
    ``frame_fraction`` of each façade opening is opaque frame. Results are read in the central
    office. Work plane at ``workplane_height_m``, grids at ``grid_spacing_m`` spacing,
    ``wall_offset_m`` from the walls.
    """

    bays: int = 3
    storeys: int = 3
    width_m: float = 3.0
    height_m: float = 2.5
    depth_m: float = 6.0
    storey_height_m: float = 2.5
    ground_floor_m: float = 1.25
    glazing_transmittance: float = 0.8
    frame_fraction: float = 0.1
    window_sill_m: float = 0.0
    window_head_m: float = 2.5
    floor_reflectance: float = 0.2
    wall_reflectance: float = 0.5
    ceiling_reflectance: float = 0.7
    workplane_height_m: float = 0.8
    grid_spacing_m: float = 0.5
    wall_offset_m: float = 0.5
    facade_grid_spacing_m: float = 0.5


@dataclass(frozen=True)
class EngineParams:
    """Tracing parameters. Radiance: ``ab`` (None = from the crown model), ``ad``, ``as_``,
    ``ar``, ``aa``, ``lw``. The defaults (``-aa 0 -as 0``: no irradiance cache, no
    super-sampling) are pure Monte Carlo: behind slat crowns the cache and ``-as`` bias ``-I``
    low by 4–8 % and the cache makes ``-ab 7`` runs take minutes instead of seconds. NumPy engine: ``rays`` per sensor, ``max_bounces``, ``seed``."""

    name: str = "auto"
    ab: int | None = None
    ad: int = 2048
    as_: int = 0
    ar: int = 256
    aa: float = 0.0
    lw: float = 0.0001
    rays: int = 4096
    max_bounces: int = 8
    seed: int = 1
    workers: int = 2
    # forward engine (radtree.engines.forward.settings): photons per hour, flux threshold
    # relative to a photon's launched flux, ray splitting (else Russian roulette), sun beam
    # diameter aimed at the first grid (None = the whole scene), square detector side, batches
    photons: int = 1_000_000
    forward_threshold: float = 0.05
    forward_splitting: bool = False
    beam_diameter_m: float | None = None
    patch_m: float = 0.5
    forward_batches: int = 16


#: the :class:`EngineParams` fields only the forward engine reads
FORWARD_KEYS = ("photons", "forward_threshold", "forward_splitting", "beam_diameter_m",
                "patch_m", "forward_batches")


@dataclass(frozen=True)
class Scenario:
    """One simulated case: a crown model, how ground-reflected light is handled, sky on/off."""

    name: str
    model: str
    reflection: str = "traced"
    sky: str | None = None
    form: str | None = None
    description: str = ""
    switches: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Project:
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
        return _plain(self)

    def params_hash(self, scenario: Scenario) -> str:
        """Short hash of everything that changes a scenario's numbers."""
        d = self.to_dict()
        payload = {k: d[k] for k in ("site", "street", "light", "tree", "sensors", "engine",
                                     "office", "extra_geometry")}
        payload["engine"].pop("workers", None)
        for key in FORWARD_KEYS:  # forward-engine settings at their defaults: hashes unchanged
            if payload["engine"].get(key) == getattr(EngineParams, key):
                payload["engine"].pop(key, None)
        payload["scenario"] = _plain(scenario)
        text = json.dumps(payload, sort_keys=True, default=str)
        return hashlib.sha256(text.encode()).hexdigest()[:12]


def _plain(obj: Any) -> Any:
    if is_dataclass(obj) and not isinstance(obj, type):
        return {f.name: _plain(getattr(obj, f.name)) for f in fields(obj)}
    if isinstance(obj, dict):
        return {k: _plain(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_plain(v) for v in obj]
    if isinstance(obj, Path):
        return str(obj)
    return obj


# ---------------------------------------------------------------- loading
def find_project_file(project: str | Path) -> Path:
    """PROJECT is a folder holding ``radtree.toml`` or the file itself."""
    p = Path(project)
    if p.is_dir():
        p = p / "radtree.toml"
    if not p.exists():
        raise ConfigError(f"project file not found: {p}")
    return p.resolve()


def load_project(project: str | Path, overrides: dict[str, Any] | None = None) -> Project:
    """Load and validate a project. ``overrides`` maps dotted field names to values."""
    path = find_project_file(project)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"not valid TOML: {exc}", source=str(path)) from exc
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f"cannot read: {exc}", source=str(path)) from exc
    for key, value in (overrides or {}).items():
        set_dotted(data, key, value)
    return parse_project(data, path)


def set_dotted(data: dict, key: str, value: Any) -> None:
    """Set ``a.b.c = value`` inside nested dicts (used by overrides and sweeps)."""
    parts = key.split(".")
    d = data
    for part in parts[:-1]:
        d = d.setdefault(part, {})
        if not isinstance(d, dict):
            raise ConfigError(f"cannot set {key}: {part} is not a table")
    d[parts[-1]] = value


def _dataclass_from(reader: _Reader, cls: type, base: Path, **special: Any) -> Any:
    """Fill a dataclass of numbers/ints/bools/strings from a table, validating types."""
    kwargs: dict[str, Any] = {}
    default = cls()
    for f in fields(cls):
        key = f.name.rstrip("_")
        if key in special:
            continue
        dv = getattr(default, f.name)
        if not reader.has(key):
            continue
        if isinstance(dv, bool):
            kwargs[f.name] = reader.boolean(key, dv)
        elif isinstance(dv, int) and not isinstance(dv, bool):
            kwargs[f.name] = reader.integer(key, dv)
        elif isinstance(dv, float):
            kwargs[f.name] = reader.number(key, dv)
        elif isinstance(dv, str):
            kwargs[f.name] = reader.string(key, dv)
        elif f.type in ("float | None", "int | None"):
            kwargs[f.name] = (reader.number(key) if f.type.startswith("float")
                              else reader.integer(key))
        else:
            kwargs[f.name] = reader.raw(key)
    for key, fn in special.items():
        if reader.has(key):
            kwargs[key] = fn(reader, key)
    return replace(default, **kwargs)


def _fraction(r: _Reader, key: str) -> None:
    if r.has(key):
        r.number(key, lo=0.0, hi=1.0)


def _positive(r: _Reader, key: str) -> None:
    if r.has(key):
        r.number(key, lo=0.0, lo_open=True)


def parse_project(data: dict, path: Path) -> Project:
    src = str(path)
    base = path.parent
    top = _Reader(data, "", src)

    # project
    proj = top.sub("project")
    name = proj.string("name", path.parent.name)
    measured = proj.optional_path("measured", base)
    measured_rows = proj.optional_path("measured_rows", base)
    proj.check_unknown()

    # site
    s = top.sub("site", required=True)
    hours_raw = s.raw("hours")
    if not isinstance(hours_raw, list) or not hours_raw:
        raise s.error("hours", f"expected a non-empty list of 'HH:MM' times, got {hours_raw!r}")
    hours = tuple(parse_time(h, f"site.hours[{i}]", src) for i, h in enumerate(hours_raw))
    if len(set(hours)) != len(hours):
        raise s.error("hours", "hours repeat")
    date = s.string("date", "2024-12-22")
    try:
        _date.fromisoformat(date)
    except ValueError as exc:
        raise s.error("date", f"got {date!r}, expected YYYY-MM-DD") from exc
    site = Site(
        name=s.string("name", name),
        latitude=s.number("latitude", required=True, lo=-90, hi=90),
        longitude=s.number("longitude", required=True, lo=-180, hi=180),
        elevation_m=s.number("elevation_m", 0.0, lo=-500, hi=9000),
        utc_offset_hours=s.number("utc_offset_hours", required=True, lo=-14, hi=14),
        date=date,
        hours=hours,
    )
    s.check_unknown()

    # street
    st = top.sub("street")
    for k in ("facade_reflectance", "opposite_reflectance"):
        _fraction(st, k)
    for k in ("width_m", "length_m", "building_height_m", "opposite_building_height_m"):
        _positive(st, k)
    if st.has("facade_azimuth_deg"):
        st.number("facade_azimuth_deg", lo=-360, hi=360)
    ground_table = None
    ground_value = Street().ground_reflectance
    g = st.raw("ground_reflectance")
    if isinstance(g, str):
        ground_table = st.optional_path("ground_reflectance", base)
    elif g is not None:
        ground_value = st.number("ground_reflectance", lo=0.0, hi=1.0)
    street = _dataclass_from(st, Street, base, ground_reflectance=lambda r, k: ground_value)
    street = replace(street, ground_reflectance=ground_value,
                     ground_reflectance_table=ground_table)
    st.check_unknown()

    # light
    li = top.sub("light")
    light = Light(
        direct_normal_table=li.optional_path("direct_normal", base),
        epw=li.optional_path("epw", base),
        sky=li.string("sky", "none", choices=SKY_CHOICES),
        diffuse_horizontal_lux=li.number("diffuse_horizontal_lux", 12000.0, lo=0.0, hi=150000.0),
    )
    if light.direct_normal_table is None and light.epw is None:
        raise li.error("direct_normal", "missing: give a DNI table (time,direct_normal_lux) "
                       "or an 'epw' weather file")
    li.check_unknown()

    # tree
    tr = top.sub("tree")
    form = tr.string("form", "dome", choices=TREE_FORMS)
    dr = tr.sub("dome")
    _positive(dr, "radius_m")
    dome = _dataclass_from(dr, Dome, base)
    dr.check_unknown()
    cr = tr.sub("crown")
    for k in ("trunk_distance_m", "spacing_m", "radius_m", "vertical_radius_m", "base_height_m",
              "trunk_diameter_m"):
        _positive(cr, k)
    if cr.has("clearance_m"):
        cr.number("clearance_m", lo=0.0)
    if cr.has("count"):
        cr.integer("count", lo=1, hi=50)
    crown = _dataclass_from(cr, Crown, base)
    cr.check_unknown()
    hr = tr.sub("homogeneous")
    for k in ("reflectance", "permeability"):
        _fraction(hr, k)
    if hr.has("transmittance"):
        hr.number("transmittance", lo=0.0, hi=1.0)
    homog = _dataclass_from(hr, Homogeneous, base)
    if homog.transmittance is not None and homog.transmittance + homog.reflectance > 1:
        raise hr.error("transmittance", "reflectance + transmittance exceeds 1")
    hr.check_unknown()
    pr = tr.sub("perforated")
    _fraction(pr, "openness")
    _fraction(pr, "reflectance")
    photo = pr.optional_path("photo", base)
    mask = None
    if pr.has("mask"):
        m = pr.raw("mask")
        if (not isinstance(m, list) or len(m) != 3
                or not all(isinstance(v, int | float) and not isinstance(v, bool) for v in m)):
            raise pr.error("mask", f"expected [centre_x, centre_y, radius] in pixels, got {m!r}")
        mask = (float(m[0]), float(m[1]), float(m[2]))
    perf = _dataclass_from(pr, Perforated, base, photo=lambda r, k: photo, mask=lambda r, k: mask)
    pr.check_unknown()
    lr = tr.sub("louvers")
    for k in ("cover_fraction", "reflectance", "transmittance", "specular_fraction"):
        _fraction(lr, k)
    if lr.has("layers"):
        lr.integer("layers", lo=1, hi=20)
    if lr.has("slat_size_m"):
        lr.number("slat_size_m", lo=0.02, hi=3.0)
    if lr.has("inclination_deg"):
        lr.number("inclination_deg", lo=0.0, hi=90.0)
    if lr.has("arrangement"):
        lr.string("arrangement", choices=LOUVER_ARRANGEMENTS)
    if lr.has("crossings"):
        lr.number("crossings", lo=0.0, hi=60.0)
    if lr.has("realisations"):
        lr.integer("realisations", lo=1, hi=64)
    louv = _dataclass_from(lr, Louvers, base)
    if louv.reflectance + louv.transmittance > 1:
        raise lr.error("transmittance", f"reflectance {louv.reflectance} + transmittance "
                       f"{louv.transmittance} exceeds 1")
    lr.check_unknown()
    tree = Tree(form=form, dome=dome, crown=crown, homogeneous=homog, perforated=perf,
                louvers=louv)
    tr.check_unknown()

    # sensors
    se = top.sub("sensors")
    for k in ("height_m", "radius_m", "offset_m", "dense_size_m", "dense_spacing_m"):
        _positive(se, k)
    if se.has("count"):
        se.integer("count", lo=1, hi=10000)
    dense_hours: tuple[str, ...] = ()
    if se.has("dense_hours"):
        dh = se.raw("dense_hours")
        if not isinstance(dh, list):
            raise se.error("dense_hours", f"expected a list of 'HH:MM' times, got {dh!r}")
        dense_hours = tuple(parse_time(h, f"sensors.dense_hours[{i}]", src)
                            for i, h in enumerate(dh))
        unknown = [h for h in dense_hours if h not in hours]
        if unknown:
            raise se.error("dense_hours", f"{', '.join(unknown)} not among site.hours")
    sensors = _dataclass_from(se, Sensors, base, dense_hours=lambda r, k: dense_hours)
    se.check_unknown()

    # engine
    en = top.sub("engine")
    if en.has("ab"):
        en.integer("ab", lo=0, hi=20)
    for k in ("ad", "as", "ar", "rays", "max_bounces", "workers"):
        if en.has(k):
            en.integer(k, lo=0 if k == "as" else 1)
    for k in ("aa", "lw"):
        if en.has(k):
            en.number(k, lo=0.0, hi=1.0)
    for k in ("photons", "forward_batches"):
        if en.has(k):
            en.integer(k, lo=1 if k == "photons" else 2)
    for k in ("beam_diameter_m", "patch_m"):
        if en.has(k):
            en.number(k, lo=0.0, lo_open=True)
    if en.has("forward_threshold") and not 0.0 < en.number("forward_threshold") < 1.0:
        raise en.error("forward_threshold", "must be strictly between 0 and 1 (a fraction of "
                       f"the launched flux), got {en.raw('forward_threshold')!r}")
    if en.has("name"):
        en.string("name", choices=ENGINES)
    engine = _dataclass_from(en, EngineParams, base)
    en.check_unknown()

    # office block (optional)
    office = None
    if top.has("office"):
        orr = top.sub("office")
        for k in ("width_m", "height_m", "depth_m", "storey_height_m", "grid_spacing_m",
                  "facade_grid_spacing_m"):
            _positive(orr, k)
        for k in ("floor_reflectance", "wall_reflectance", "ceiling_reflectance",
                  "frame_fraction"):
            _fraction(orr, k)
        if orr.has("glazing_transmittance"):
            orr.number("glazing_transmittance", lo=0.0, lo_open=True, hi=0.9183)
        for k in ("bays", "storeys"):
            if orr.has(k):
                orr.integer(k, lo=1, hi=21)
        office = _dataclass_from(orr, Office, base)
        if office.bays % 2 == 0 or office.storeys % 2 == 0:
            raise orr.error("bays", "bays and storeys must be odd so that a central office exists")
        if office.height_m > office.storey_height_m:
            raise orr.error("height_m", f"office height {office.height_m} m exceeds the storey "
                            f"height {office.storey_height_m} m")
        orr.check_unknown()

    # extra user geometry: [[geometry]] file = "x.obj", material = "name"
    extra = []
    for i, item in enumerate(top.raw("geometry", []) or []):
        r = _Reader(item, f"geometry[{i}]", src)
        gpath = r.optional_path("file", base)
        if gpath is None:
            raise r.error("file", "missing (an OBJ/STL/PLY or .rad file)")
        extra.append((gpath, r.string("material")))
        r.check_unknown()

    # scenarios
    raw_sc = top.raw("scenario", None)
    if raw_sc is None:
        raw_sc = [{"name": "base", "model": "louvers"}]
    if not isinstance(raw_sc, list) or not raw_sc:
        raise ConfigError("expected one or more [[scenario]] tables", source=src, field="scenario")
    scenarios = []
    for i, item in enumerate(raw_sc):
        r = _Reader(item, f"scenario[{i}]", src)
        sw = r.raw("switches", {})
        if not isinstance(sw, dict):
            raise r.error("switches", f"expected a table, got {sw!r}")
        sky = r.raw("sky")
        if sky is not None:
            sky = r.string("sky", choices=SKY_CHOICES)
        sform = r.raw("form")
        if sform is not None:
            sform = r.string("form", choices=TREE_FORMS)
        scenarios.append(Scenario(
            name=r.string("name"),
            model=r.string("model", choices=CROWN_MODELS),
            reflection=r.string("reflection", "traced", choices=REFLECTION_MODES),
            sky=sky,
            form=sform,
            description=r.string("description", ""),
            switches=dict(sw),
        ))
        if not re.match(r"^[A-Za-z0-9_.-]+$", scenarios[-1].name):
            raise r.error("name", f"got {scenarios[-1].name!r}: use letters, digits, _ . - only "
                          "(it names a folder)")
        r.check_unknown()
    names = [sc.name for sc in scenarios]
    if len(set(names)) != len(names):
        raise ConfigError(f"scenario names repeat: {names}", source=src, field="scenario")
    top.raw("sweep")  # read by radtree.sweep
    top.check_unknown()

    return Project(name=name, root=path.parent, source=path, site=site, street=street,
                   light=light, tree=tree, sensors=sensors, engine=engine,
                   scenarios=tuple(scenarios), measured=measured, measured_rows=measured_rows,
                   office=office, extra_geometry=tuple(extra))


def project_dict(project: Project) -> dict[str, Any]:
    """Plain dictionary of the project (for manifests and reports)."""
    return asdict(project)


PROJECT_SWITCH_SECTIONS = ("site", "street", "light", "sensors", "engine")


def effective_project(project: Project, scenario: Scenario) -> Project:
    """The project as a scenario sees it: switches named ``street.*``, ``light.*``, ``site.*``,
    ``sensors.*`` or ``engine.*`` replace that field (e.g. ``"street.opposite_reflectance" = 0``,
    ``"light.diffuse_horizontal_lux" = 8000``, ``"engine.ab" = 6``). ``"street.ground_reflectance"
    = 0.15`` also drops the per-hour table (constant reflectance). Other switches (tree.*,
    louvers.*, reflection.*, …) are read by the code they concern."""
    changes: dict[str, dict[str, Any]] = {}
    for key, value in scenario.switches.items():
        section, _, name = key.partition(".")
        if section not in PROJECT_SWITCH_SECTIONS:
            continue
        target = getattr(project, section)
        attr = "as_" if name == "as" else name
        if not name or attr not in {f.name for f in fields(target)}:
            raise ConfigError(f"scenario {scenario.name}: switch {key!r} names no field of "
                              f"[{section}]", source=str(project.source), field="switches")
        current = getattr(target, attr)
        if isinstance(current, bool) or not isinstance(value, type(current) | int | float | None):
            if not (current is None and isinstance(value, int | float)):
                raise ConfigError(f"scenario {scenario.name}: switch {key!r} = {value!r} has the "
                                  f"wrong type (expected like {current!r})",
                                  source=str(project.source), field="switches")
        if isinstance(current, float) and isinstance(value, int):
            value = float(value)
        changes.setdefault(section, {})[attr] = value
        if section == "street" and attr == "ground_reflectance":
            changes[section]["ground_reflectance_table"] = None
    if not changes:
        return project
    return replace(project, **{s: replace(getattr(project, s), **c) for s, c in changes.items()})
