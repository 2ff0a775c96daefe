"""``radtree new``: a commented ``radtree.toml`` (tomlkit) from one's own data.

:func:`new_project` writes ``DIR/radtree.toml`` and copies the inputs into ``DIR/data/``:

* ``--trees`` (GeoJSON points or CSV) → ``[site] trees``; ``--buildings`` (GeoJSON
  footprints) → ``[site] buildings``; ``--honeybee`` (HBJSON) → ``[site] honeybee``. They are
  read with plain ``json``/``csv`` only to summarise them (trees per species, buildings,
  rooms); their full validation belongs to the readers of those keys.
* ``--epw``: the site's latitude, longitude, time zone and elevation from the weather file
  (``pvlib`` through :func:`radtree.light.weather.read_epw`) and ``[light] epw``. Without it
  the site comes from the inputs' coordinates (longitude/latitude; time zone estimated as
  round(longitude / 15) h, said so) or is the Mendoza reference site, and a clear-sky year is
  generated into ``data/generated_clear_sky.epw`` (labelled GENERATED).
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
import shutil
import textwrap
from collections import Counter
from dataclasses import MISSING, dataclass, field, fields
from pathlib import Path
from typing import Any

import tomlkit

from radtree.config import Scenario, load_project
from radtree.config.spec import spec_of, toml_name
from radtree.config.species import find_species
from radtree.config.switches import TABLES, TREE_TABLES
from radtree.errors import ConfigError
from radtree.fileio import write_text
from radtree.light.clearsky import write_generated_epw
from radtree.light.weather import read_epw
from radtree.site.inventory import read_features

TEMPLATES = ("street", "office", "district")
#: the site without an EPW or geographic inputs: the reference study (reference case §1)
MENDOZA = {"name": "Mendoza, Argentina (reference site)", "latitude": -32.89,
           "longitude": -68.83, "elevation_m": 750.0, "utc_offset_hours": -3.0}
HOURS = ["10:30", "11:30", "12:30", "13:30", "14:30", "15:30", "16:30"]
GENERATED_EPW = "generated_clear_sky.epw"
DEFAULT_SPECIES = "morus_alba"
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
        if crs.upper().endswith(("4326", "CRS84")):
            for f in feats:
                info.lonlat += _points(f.coords)
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


def _centroid(inputs: Inputs) -> tuple[float, float] | None:
    if not inputs.lonlat:
        return None
    lon = sum(p[0] for p in inputs.lonlat) / len(inputs.lonlat)
    lat = sum(p[1] for p in inputs.lonlat) / len(inputs.lonlat)
    return (lon, lat) if -180 <= lon <= 180 and -90 <= lat <= 90 else None


def site_facts(epw: Path | None, inputs: Inputs) -> tuple[dict[str, Any], str]:
    """The ``[site]`` place and where it came from: latitude/longitude from the inputs'
    longitude/latitude centroid (the site origin of their local frame) or else the EPW; time
    zone and elevation from the EPW, else estimated; else the Mendoza reference site."""
    centre = _centroid(inputs)
    if epw is not None:
        w = read_epw(epw)
        site = {"name": w.path.stem.replace("_", " "), "latitude": round(w.latitude, 4),
                "longitude": round(w.longitude, 4), "elevation_m": float(w.elevation_m),
                "utc_offset_hours": float(w.utc_offset_hours)}
        why = f"from the EPW {epw.name} (pvlib)"
        if centre is not None:
            if abs(centre[0] - w.longitude) > 0.5 or abs(centre[1] - w.latitude) > 0.5:
                raise ConfigError(f"the EPW {epw} is for latitude {w.latitude}, longitude "
                                  f"{w.longitude}, more than 0.5° from the inputs' centre "
                                  f"({centre[1]:.4f}, {centre[0]:.4f})")
            site.update(latitude=round(centre[1], 5), longitude=round(centre[0], 5))
            why = (f"latitude/longitude the centroid of the inputs; time zone and elevation "
                   f"from the EPW {epw.name} (pvlib)")
        return site, why
    if centre is not None:
        return ({"name": "site of the inputs", "latitude": round(centre[1], 5),
                 "longitude": round(centre[0], 5), "elevation_m": 0.0,
                 "utc_offset_hours": float(round(centre[0] / 15.0))},
                "the centroid of the inputs' longitude/latitude; time zone ESTIMATED as "
                "round(longitude / 15) h and elevation 0 m: check both")
    return dict(MENDOZA), "the Mendoza reference site (no EPW, no geographic inputs): edit it"


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
    f = next(f for f in fields(cls) if f.name == name)
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
    for f in fields(cls):
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


def document(template: str, site: dict[str, Any], site_source: str, data: dict[str, str],
             light: dict[str, Any], inputs: Inputs, species: str) -> Any:
    """The commented project document of ``template``."""
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
    date = "2024-12-22" if site["latitude"] < 0 else "2024-06-21"
    s = table(TABLES["site"], {**site, "date": date, "hours": HOURS},
              {"date": "the summer solstice of the site's hemisphere",
               "hours": "the reference study's seven hours"})
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
    doc.add("site", s)
    doc.add("street", table(TABLES["street"], {}))
    doc.add("light", table(TABLES["light"], light,
                           {"sky": "Perez sky from the EPW's diffuse illuminance"}))
    tree = table(TABLES["tree"], {"form": "free", "species": species},
                 {"species": "fills leaf optics, tilt and permeability left out below"})
    for sub in TREE_TABLES:
        tree.add(sub, table(TABLES[f"tree.{sub}"], {}))
    doc.add("tree", tree)
    doc.add("sensors", table(TABLES["sensors"], {}))
    doc.add("engine", table(TABLES["engine"], {}))
    doc.add("limits", table(TABLES["limits"], {}))
    if template == "office":
        doc.add("office", table(TABLES["office"], {}))
    scenarios = tomlkit.aot()
    for name, model, what in (("trees", "louvers", "the crowns (louvers model)"),
                              ("open", "none", "the same site without trees")):
        sc = table(TABLES_SCENARIO, {"name": name, "model": model, "reflection": "traced",
                                     "description": what})
        sc.add(tomlkit.comment('switches = {}   # dotted keys, e.g. {"louvers.layers" = 6}'))
        scenarios.append(sc)
    doc.add("scenario", scenarios)
    return doc


# ---------------------------------------------------------------- the command's function
@dataclass
class NewProject:
    path: Path
    inputs: Inputs
    site: dict[str, Any]
    site_source: str
    template: str
    copied: list[Path]
    generated_epw: bool


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
                template: str | None = None) -> NewProject:
    """Write ``folder/radtree.toml`` (+ ``data/``) and check it loads; see the module text."""
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
    site, site_source = site_facts(epw, inputs)
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
        if epw is not None:
            light = {"epw": _copy(Path(epw), data_dir, made), "sky": "perez"}
        else:
            out = data_dir / GENERATED_EPW
            write_generated_epw(out, site["name"], site["latitude"], site["longitude"],
                                site["elevation_m"], site["utc_offset_hours"])
            made.append(out)
            light = {"epw": f"data/{GENERATED_EPW}", "sky": "perez"}
        doc = document(template, site, site_source, data, light, inputs, species)
        write_text(tmp, tomlkit.dumps(doc))
        try:
            load_project(tmp)                   # what build will read, as written
        except ConfigError as exc:
            raise ConfigError(f"the project written for {target} does not load, nothing was "
                              f"kept: {exc}") from None
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
    return NewProject(target, inputs, site, site_source, template, made, epw is None)
