"""``radtree new``: a commented ``radtree.toml`` (tomlkit) from one's own data.

:func:`new_project` writes ``DIR/radtree.toml`` and copies the inputs into ``DIR/data/``:

* ``--trees`` (GeoJSON points or CSV) → ``[site] trees``; ``--buildings`` (GeoJSON
  footprints) → ``[site] buildings``; ``--honeybee`` (HBJSON) → ``[site] honeybee``. They are
  read with plain ``json``/``csv`` only to summarise them (trees per species, buildings,
  rooms); their full validation belongs to the readers of those keys.
* ``--lat/--lon`` (degrees), ``--tz Area/City`` or ``--utc ±H``, ``--elevation``, ``--date``:
  the site (:class:`Location`). What is left out comes from the inputs' coordinates, then the
  EPW (``--epw``: ``[light] epw``, checked against the site), the time zone from the
  coordinates (timezonefinder's offline IANA boundaries); every source is printed. Without an
  EPW the weather is ``[light] weather = "clear-sky"`` (pvlib's clear sky of the site and date,
  no file).
* ``--template street|office|district``: the street canyon with free-standing crowns; the
  same with the office block (``[office]``); the inventory district (default when buildings
  are given).

Every field of every table is written with its unit, bounds and default (from the schema's
dataclasses and field metadata): the fields the inputs decide as values, the rest as
commented ``# key = default`` lines to uncomment. The file is loaded with
:func:`radtree.config.load_project` before it is moved into place, so what is written is what
``radtree build`` accepts; on any error nothing is left behind.
"""

from __future__ import annotations

import inspect
import json
import math
import shutil
import textwrap
from collections import Counter
from collections.abc import Callable
from dataclasses import MISSING, dataclass, field
from datetime import date as _date
from pathlib import Path
from typing import Any

import tomlkit

from radtree.config import Project, Scenario, load_project
from radtree.config.spec import spec_of, table_field, table_fields, toml_name
from radtree.config.species import find_species
from radtree.config.switches import TABLES, TREE_TABLES
from radtree.config.timezone import fixed_name, parse_time_zone, standard_offset_hours
from radtree.errors import ConfigError
from radtree.fileio import write_text
from radtree.light.sun import daylight_hours
from radtree.light.weather import Epw, read_epw
from radtree.site.inventory import read_features

TEMPLATES = ("street", "office", "district")
#: the species of a project whose inputs name none from the library: a common street tree
DEFAULT_SPECIES = "platanus_x_acerifolia"
_UNITS = (("_m", "m"), ("_deg", "degrees"), ("_lux", "lx"), ("_hours", "h"))
_WRAP = 96
TABLES_SCENARIO = Scenario
#: the ``[site]`` keys of the inventory district (read by the district inputs' reader)
DISTRICT_LINES = [
    'crs = "EPSG:4326"   # CRS of CSV x, y / GeoJSON without a crs member; default EPSG:4326',
    'facades = "street"   # "street" (faces towards open ground) or ["BUILDING:FACE", …]',
    "facade_spacing_m = 3.0   # m; sensor spacing along a façade; default 3.0",
    "window_height_m = 1.5   # m; sensors above each storey floor; default 1.5",
    "storey_height_m = 3.0   # m; when a building gives no storeys; default 3.0",
    "facade_chunk = 8   # façades per traced grid (the unit of work on Dask); default 8",
    'instancing = "auto"   # "auto" (one instance octree per species × realisation) | "never"',
]
#: the ``[site]`` keys of a Honeybee model (read by the Honeybee site's reader)
HONEYBEE_LINES = [
    "honeybee_grid_spacing_m = 0.5   # m; grids generated for rooms without one; default 0.5",
    "honeybee_workplane_m = 0.8   # m; their height above each floor; default 0.8",
]


@dataclass
class Inputs:
    """What the inputs say: counts, species, coordinates (longitude, latitude) if geographic."""

    trees: int = 0
    species: Counter[str] = field(default_factory=Counter)
    buildings: int = 0
    rooms: int = 0
    lonlat: list[tuple[float, float]] = field(default_factory=list)

    def lines(self) -> list[str]:
        out = []
        if self.trees:
            parts = []
            for name, n in self.species.most_common():
                sp = find_species(name)
                parts.append(f"{name}: {n}" + ("" if sp else " (not in the species library)"))
            out.append(f"{self.trees} trees — " + "; ".join(parts))
        if self.buildings:
            out.append(f"{self.buildings} buildings")
        if self.rooms:
            out.append(f"Honeybee model: {self.rooms} rooms")
        return out


def _points(coords: Any) -> list[tuple[float, float]]:
    if isinstance(coords, list | tuple) and len(coords) >= 2 and all(
            isinstance(c, int | float) for c in coords[:2]):
        return [(float(coords[0]), float(coords[1]))]
    out: list[tuple[float, float]] = []
    for c in coords if isinstance(coords, list | tuple) else []:
        out += _points(c)
    return out


def read_inputs(trees: Path | None, buildings: Path | None, honeybee: Path | None) -> Inputs:
    """Count the inputs; ConfigError naming the file when it cannot be read."""
    info = Inputs()
    for path, kind, geometry in ((trees, "trees", "Point"), (buildings, "buildings", "Polygon")):
        if path is None:
            continue
        try:   # the district reader's parsing (radtree.site.inventory); counted here only
            feats, crs = read_features(path, "EPSG:4326", geometry, kind[0].upper())
        except ConfigError as exc:
            raise ConfigError(f"{path}: cannot read the {kind} ({exc})") from None
        pts = [pt for f in feats for pt in _points(f.coords)]
        if crs.upper().endswith(("4326", "CRS84")):
            info.lonlat += pts
        elif pts and crs != "local":    # a projected CRS: its coordinates as longitude/latitude
            from pyproj import Transformer

            t = Transformer.from_crs(crs, "EPSG:4326", always_xy=True)
            lon, lat = t.transform([p[0] for p in pts], [p[1] for p in pts])
            info.lonlat += list(zip(map(float, lon), map(float, lat)))
        if kind == "trees":
            info.trees = len(feats)
            info.species = Counter(str(f.props.get("species", "")).strip() or "(no species)"
                                   for f in feats)
        else:
            info.buildings = len(feats)
    if honeybee is not None:
        try:
            model = json.loads(honeybee.read_text(encoding="utf-8"))
            info.rooms = len(model.get("rooms") or []) if isinstance(model, dict) else 0
        except (OSError, ValueError, UnicodeDecodeError) as exc:
            raise ConfigError(f"{honeybee}: cannot read the Honeybee model ({exc})") from None
    return info


def _east_west_span_m(inputs: Inputs) -> float:
    """East–west extent of the inputs' coordinates (m; equirectangular, enough to size the
    street along the default east–west façade); 0 without geographic inputs."""
    if not inputs.lonlat:
        return 0.0
    lon = [p[0] for p in inputs.lonlat]
    lat = sum(p[1] for p in inputs.lonlat) / len(inputs.lonlat)
    return (max(lon) - min(lon)) * 111320.0 * math.cos(math.radians(lat))


def _centroid(inputs: Inputs) -> tuple[float, float] | None:
    if not inputs.lonlat:
        return None
    lon = sum(p[0] for p in inputs.lonlat) / len(inputs.lonlat)
    lat = sum(p[1] for p in inputs.lonlat) / len(inputs.lonlat)
    return (lon, lat) if -180 <= lon <= 180 and -90 <= lat <= 90 else None


@dataclass(frozen=True)
class Location:
    """Where the user says the site is (``radtree new --lat --lon --tz|--utc --elevation
    --date``); every field optional: what is left out comes from the EPW or the inputs."""

    latitude: float | None = None
    longitude: float | None = None
    time_zone: str | None = None
    elevation_m: float | None = None
    date: str | None = None

    def __post_init__(self) -> None:
        if (self.latitude is None) != (self.longitude is None):
            raise ConfigError("give both --lat and --lon (degrees; latitude north +, longitude "
                              "east +, west negative)")
        if self.latitude is not None and not -90 <= self.latitude <= 90:
            raise ConfigError(f"--lat {self.latitude:g}: expected −90 … 90 degrees (north +)")
        if self.longitude is not None and not -180 <= self.longitude <= 180:
            raise ConfigError(f"--lon {self.longitude:g}: expected −180 … 180 degrees (east +)")
        if self.time_zone is not None:
            try:
                parse_time_zone(self.time_zone)
            except ValueError as exc:
                raise ConfigError(f"--tz/--utc: {exc}") from None
        if self.date is not None:
            try:
                _date.fromisoformat(self.date)
            except ValueError:
                raise ConfigError(f"--date {self.date!r}: expected YYYY-MM-DD") from None


def zone_at(latitude: float, longitude: float) -> str | None:
    """The IANA time zone at a point (``timezonefinder``, offline boundary data), or None at
    sea / where it finds none."""
    from timezonefinder import TimezoneFinder

    return TimezoneFinder().timezone_at(lng=longitude, lat=latitude)


def site_facts(epw: Path | None, *, inputs: Inputs, where: Location | None = None
               ) -> tuple[dict[str, Any], str]:
    """The ``[site]`` place and where it came from, in order: ``--lat/--lon`` (``where``); the
    inputs' longitude/latitude centroid (the site origin of their local frame); the EPW. The
    time zone: ``--tz/--utc``, else the EPW's standard offset, else the IANA zone at the point
    (timezonefinder). Elevation: ``--elevation``, else the EPW's, else 0 m (said so). Without
    any of them: ConfigError asking for ``--lat/--lon``."""
    where = where or Location()
    w = read_epw(epw) if epw is not None else None
    lat, lon, said_place = _place(where, centre=_centroid(inputs), w=w)
    # inputs far from the site: each feature is checked by the inventory readers
    # (radtree.site.inventory.check_spread), naming the feature
    if w is not None and (abs(w.latitude - lat) > 0.5 or abs(w.longitude - lon) > 0.5):
        raise ConfigError(f"the EPW {epw} is for latitude {w.latitude}, longitude "
                          f"{w.longitude}, more than 0.5° from the site ({lat:g}, {lon:g}): "
                          "give the site's EPW, or leave --epw out (clear-sky weather)")
    zone, said_zone = _zone(where, lat=lat, lon=lon, w=w)
    if w is not None and abs(standard_offset_hours(zone) - w.utc_offset_hours) > 1e-6:
        raise ConfigError(f"the EPW {epw} is in standard time UTC{w.utc_offset_hours:+g} h, "
                          f"but the time zone {zone} has standard time "
                          f"UTC{standard_offset_hours(zone):+g} h: give the site's EPW or "
                          "the right --tz")
    elevation, said_elevation = (
        (float(where.elevation_m), "elevation from --elevation") if where.elevation_m is not None
        else (float(w.elevation_m), "elevation from the EPW") if w is not None
        else (0.0, "elevation 0 m (ASSUMED: give --elevation)"))
    name = (w.path.stem.replace("_", " ") if w is not None and where.latitude is None
            else f"site at {abs(lat):.4f}°{'N' if lat >= 0 else 'S'} "
                 f"{abs(lon):.4f}°{'E' if lon >= 0 else 'W'}")
    site = {"name": name, "latitude": round(lat, 5), "longitude": round(lon, 5),
            "elevation_m": elevation, "time_zone": zone}
    return site, "; ".join([said_place, said_zone, said_elevation])


def _place(where: Location, *, centre: tuple[float, float] | None, w: Epw | None
           ) -> tuple[float, float, str]:
    """Latitude, longitude (degrees) and where they came from (:func:`site_facts`)."""
    if where.latitude is not None:
        lat, lon = float(where.latitude), float(where.longitude)  # type: ignore[arg-type]
        return lat, lon, "latitude/longitude from --lat/--lon"
    if centre is not None:
        return centre[1], centre[0], "latitude/longitude the centroid of the inputs' coordinates"
    if w is not None:
        return w.latitude, w.longitude, f"latitude/longitude from the EPW {w.path.name}"
    raise ConfigError("radtree new needs the site: give --lat LAT --lon LON (degrees, "
                      "north and east positive) and --tz Area/City (e.g. --lat 40.42 "
                      "--lon -3.70 --tz Europe/Madrid), or an EPW, or geographic inputs")


def _zone(where: Location, *, lat: float, lon: float, w: Epw | None) -> tuple[str, str]:
    """The time zone and where it came from (:func:`site_facts`)."""
    if where.time_zone is not None:
        return where.time_zone, "time zone from --tz/--utc"
    if w is not None:
        zone = fixed_name(w.utc_offset_hours)
        return zone, (f"time zone the EPW's standard time {zone} (no daylight saving: give "
                      "--tz Area/City for clock times with daylight saving)")
    found = zone_at(lat, lon)
    if found is None:
        raise ConfigError(f"no time zone known at latitude {lat:g}, longitude {lon:g}: "
                          "give --tz Area/City or --utc ±H")
    return found, f"time zone {found} looked up from the coordinates (timezonefinder)"


# ---------------------------------------------------------------- the document
def _unit(name: str, kind: str, fraction: bool) -> str:
    if kind not in ("float", "int"):
        return ""
    for suffix, unit in _UNITS:
        if name.endswith(suffix):
            return unit
    if fraction:
        return "fraction"
    return {"latitude": "degrees, north +", "longitude": "degrees, east + (west negative)"
            }.get(name, "")


def _default(cls: type, name: str) -> Any:
    f = table_field(cls, name)
    if f.default is not MISSING:
        return f.default
    if f.default_factory is not MISSING:
        return f.default_factory()
    return MISSING


def _shown(value: Any) -> str:
    if value is None or value is MISSING:
        return "(unset)"
    if isinstance(value, tuple):
        value = list(value)
    return tomlkit.item(value).as_string()


def _describe(cls: type, name: str) -> str:
    spec = spec_of(cls, name)
    assert spec is not None
    unit = _unit(name, spec.kind, spec.lo == 0 and spec.hi == 1)
    d = _default(cls, name)
    bits = [unit] if unit else []
    bits.append(spec.expected())
    bits.append("required" if d is MISSING else f"default {_shown(d)}")
    return "; ".join(bits)


def _doc_lines(cls: type) -> list[str]:
    text = inspect.cleandoc(cls.__doc__ or "").split("\n\n")[0].replace("\n", " ")
    return textwrap.wrap(text.replace("``", ""), _WRAP - 2)


def table(cls: type, values: dict[str, Any], notes: dict[str, str] | None = None
          ) -> Any:
    """A tomlkit table of dataclass ``cls``: its doc, ``values`` written, every other field
    as a commented ``# key = default`` line; each with unit, bounds and default."""
    t = tomlkit.table()
    for line in _doc_lines(cls):
        t.add(tomlkit.comment(line))
    for f in table_fields(cls):
        spec = spec_of(cls, f.name)
        if spec is None:
            continue
        key = toml_name(cls, f.name)
        about = _describe(cls, f.name) + (f" — {notes[key]}" if notes and key in notes else "")
        if key in values:
            v = values[key]
            t.add(key, list(v) if isinstance(v, tuple) else v)
            t[key].comment(about)
        else:
            t.add(tomlkit.comment(f"{key} = {_shown(_default(cls, f.name))}   # {about}"))
    return t


def _comments(t: Any, lines: list[str]) -> None:
    for line in lines:
        for part in textwrap.wrap(line, _WRAP - 2) or [""]:
            t.add(tomlkit.comment(part))


def document(template: str, *, site: dict[str, Any], site_source: str, data: dict[str, str],
             light: dict[str, Any], inputs: Inputs, species: str) -> Any:
    """The commented project document of ``template``: the header, ``[project]``, ``[site]``
    (:func:`_site_table`), the schema's tables with the values decided, two scenarios."""
    doc = tomlkit.document()
    _comments(doc, [f"radtree project written by `radtree new` (template {template!r}).",
                    "Units: metres, degrees (azimuth clockwise from north), lux, local clock "
                    "time. Every field is listed with its unit, bounds and default; uncomment "
                    "a line to change it.", f"Site: {site_source}."]
              + [f"Inputs: {line}." for line in inputs.lines()])
    doc.add(tomlkit.nl())
    proj = tomlkit.table()
    proj.add("name", site["name"])
    proj["name"].comment("text; default the folder's name")
    proj.add(tomlkit.comment('measured = "data/…"   # measured façade illuminance (time,lux); '
                             "optional"))
    proj.add(tomlkit.comment('measured_rows = "data/…"   # per-row measured means; optional'))
    doc.add("project", proj)
    doc.add("site", _site_table(site, data=data, template=template))
    span = _east_west_span_m(inputs)
    street_len = TABLES["street"]().length_m
    doc.add("street", table(TABLES["street"], {} if span + 40.0 <= street_len else {
        "length_m": float(math.ceil((span + 40.0) / 10.0) * 10.0)},
        {"length_m": "covers the inventory's trees along the façade, 20 m beyond each end"}))
    doc.add("light", table(TABLES["light"], light,
                           {"sky": "Perez sky of the weather's diffuse illuminance",
                            "weather": "clear-sky needs no file; epw = \"data/site.epw\" for "
                                       "measured or typical-year weather"}))
    tree = table(TABLES["tree"], {"form": "free", "species": species},
                 {"species": "fills leaf optics, tilt and permeability left out below"})
    for sub in TREE_TABLES:
        tree.add(sub, table(TABLES[f"tree.{sub}"], {}))
    doc.add("tree", tree)
    for name in ("sensors", "engine", "limits") + (("office",) if template == "office" else ()):
        doc.add(name, table(TABLES[name], {}))
    scenarios = tomlkit.aot()
    for name, model, what in (("trees", "louvers", "the crowns (louvers model)"),
                              ("open", "none", "the same site without trees")):
        sc = table(TABLES_SCENARIO, {"name": name, "model": model, "reflection": "traced",
                                     "description": what})
        sc.add(tomlkit.comment('switches = {}   # dotted keys, e.g. {"louvers.layers" = 6}'))
        scenarios.append(sc)
    doc.add("scenario", scenarios)
    return doc


def _site_table(site: dict[str, Any], *, data: dict[str, str], template: str) -> Any:
    """``[site]``: the place, the date (popped from ``site``) and its sunlit hours, the data."""
    date = site.pop("date")
    args = (site["latitude"], site["longitude"], site["elevation_m"],
            parse_time_zone(site["time_zone"]), date)
    hours = daylight_hours(*args, min_altitude_deg=5.0) or daylight_hours(*args)
    if not hours:
        raise ConfigError(f"the sun stays below the horizon at every whole hour of {date} at "
                          f"latitude {site['latitude']:g} (polar night): choose another "
                          "--date")
    s = table(TABLES["site"], {**site, "date": date, "hours": hours},
              {"date": "local date of the hours",
               "hours": "local civil clock times (daylight saving applied with an IANA zone); "
                        "written: the whole hours with the sun ≥ 5° high on the date",
               "time_zone": "IANA name (daylight saving applied) or a fixed offset 'UTC+1'",
               "utc_offset_hours": "derived from time_zone; give it instead for a fixed offset"})
    data_notes = {"trees": "tree inventory: points with species, height_m, crown_diameter_m, "
                           "crown_base_m", "buildings": "footprints with height_m",
                  "honeybee": "a Honeybee model (HBJSON)"}
    for key, about in data_notes.items():
        if key in data:
            s.add(key, data[key])
            s[key].comment(about + " (copied into data/)")
        else:
            s.add(tomlkit.comment(f'{key} = "data/…"   # {about}; not given'))
    for line in (DISTRICT_LINES if template == "district" else []) + (
            HONEYBEE_LINES if "honeybee" in data else []):
        s.add(tomlkit.comment(line))
    return s


# ---------------------------------------------------------------- the command's function
@dataclass
class NewProject:
    path: Path
    inputs: Inputs
    site: dict[str, Any]
    site_source: str
    template: str
    copied: list[Path]
    weather: str


def _copy(src: Path, data_dir: Path, made: list[Path]) -> str:
    dst = data_dir / src.name
    if dst.exists() and dst.resolve() != src.resolve():
        raise ConfigError(f"{dst} exists already: move it away or choose another folder")
    if not dst.exists():
        shutil.copyfile(src, dst)
        made.append(dst)
    return f"data/{src.name}"


def new_project(folder: Path, trees: Path | None = None, buildings: Path | None = None,
                honeybee: Path | None = None, epw: Path | None = None,
                template: str | None = None, where: Location | None = None,
                validate: Callable[[Project], None] | None = None) -> NewProject:
    """Write ``folder/radtree.toml`` (+ ``data/``), load it and run ``validate`` on it (the
    build's input checks) before it is moved into place; see the module text."""
    folder = Path(folder)
    template = template or ("district" if buildings is not None else "street")
    if template not in TEMPLATES:
        raise ConfigError(f"unknown template {template!r} (known: {', '.join(TEMPLATES)})")
    if template == "office" and honeybee is not None:
        raise ConfigError("the office template and --honeybee both build the rooms: use the "
                          "Honeybee model with --template street (or district)")
    if template == "district" and trees is None and buildings is None:
        raise ConfigError("the district template needs --trees and/or --buildings")
    for p in (trees, buildings, honeybee, epw):
        if p is not None and not Path(p).is_file():
            raise ConfigError(f"file not found: {p}")
    target = folder / "radtree.toml"
    if target.exists():
        raise ConfigError(f"{target} exists already: radtree new does not overwrite a project")
    inputs = read_inputs(trees, buildings, honeybee)
    site, site_source = site_facts(epw, inputs=inputs, where=where)
    site["date"] = (where.date if where is not None and where.date
                    else "2024-06-21" if site["latitude"] >= 0 else "2024-12-21")
    known = [s for s, _ in inputs.species.most_common() if find_species(s)]
    species = find_species(known[0]).key if known else DEFAULT_SPECIES  # type: ignore[union-attr]
    made_folder = not folder.exists()
    data_dir = folder / "data"
    made_data = not data_dir.exists()
    made: list[Path] = []
    tmp = folder / ".radtree.toml.new"
    try:
        data_dir.mkdir(parents=True, exist_ok=True)
        data = {key: _copy(Path(p), data_dir, made) for key, p in
                (("trees", trees), ("buildings", buildings), ("honeybee", honeybee))
                if p is not None}
        light: dict[str, Any] = ({"weather": "epw", "epw": _copy(Path(epw), data_dir, made),
                                  "sky": "perez"} if epw is not None
                                 else {"weather": "clear-sky", "sky": "perez"})
        doc = document(template, site=site, site_source=site_source, data=data,
                       light=light, inputs=inputs, species=species)
        write_text(tmp, tomlkit.dumps(doc))
        try:
            project = load_project(tmp)         # what build will read, as written
            if validate is not None:
                validate(project)               # and the build's checks of the inputs
        except ConfigError as exc:
            raise ConfigError(f"{exc} — nothing was written to {folder}") from None
        tmp.replace(target)
    except BaseException:
        tmp.unlink(missing_ok=True)
        for p in made:
            p.unlink(missing_ok=True)
        if made_data and data_dir.exists() and not any(data_dir.iterdir()):
            data_dir.rmdir()
        if made_folder and folder.exists() and not any(folder.iterdir()):
            folder.rmdir()
        raise
    return NewProject(target, inputs, site, site_source, template, made, light["weather"])
