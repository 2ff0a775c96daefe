"""The project file ``radtree.toml`` read into the dataclasses of :mod:`radtree.config.schema`.

Every invalid field raises :class:`radtree.errors.ConfigError` naming the file, the field, the
value found and what was expected; an unknown field or table lists every known one (close
matches first). Values are typed by the fields' :class:`radtree.config.spec.Spec`; relative
paths are resolved against the project folder.
"""

from __future__ import annotations

import re
from dataclasses import fields, replace
from pathlib import Path
from typing import Any

import tomllib

from radtree.config.district import DISTRICT_KEYS, read_district
from radtree.config.honeybee import read_honeybee
from radtree.config.schema import Project, Scenario, Site, Street, parse_time
from radtree.config.spec import SchemaError, Spec, spec_for, spec_of, table_fields, toml_name
from radtree.config.species import find_species, tree_defaults, unknown_species_message
from radtree.config.switches import (
    FIELD,
    TABLES,
    TREE_TABLES,
    check_switches,
    known_text,
    lookup_key,
    table_keys,
)
from radtree.config.timezone import site_time_zone, standard_offset_hours
from radtree.errors import ConfigError

TOP_TABLES = ("project", "site", "street", "light", "tree", "sensors", "engine", "office",
              "geometry", "scenario", "sweep", "limits")
SCENARIO_KEYS = tuple(f.name for f in fields(Scenario))
GEOMETRY_KEYS = ("file", "material")


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

    def value(self, key: str, spec: Spec, default: Any = None, *, required: bool = False) -> Any:
        """The value of ``key`` checked by ``spec`` (``default`` when absent)."""
        self.used.add(key)
        if key not in self.data:
            if required or default is None and not spec.optional:
                raise self.error(key, f"missing ({spec.expected()} is required)")
            return default
        try:
            return spec.check(self.data[key])
        except ValueError as exc:
            raise self.error(key, str(exc)) from None

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

    def check_unknown(self, known: tuple[str, ...]) -> None:
        unknown = sorted(set(self.data) - set(known))
        if unknown:
            what = "table" if isinstance(self.data[unknown[0]], dict | list) else "field"
            raise self.error(unknown[0], f"unknown {what} (" + known_text(
                unknown[0], known, "known here") + ")")


def _table(r: _Reader, table: str, base: Path, **given: Any) -> Any:
    """The dataclass of ``table`` from its TOML table: every field with a Spec that the table
    holds (paths resolved), then ``given``; the table's unknown fields are rejected."""
    cls = TABLES[table]
    kwargs: dict[str, Any] = {}
    for f in table_fields(cls):
        spec = spec_of(cls, f.name)
        key = toml_name(cls, f.name)
        if spec is None or f.name in given or not r.has(key):
            continue
        kwargs[f.name] = (r.optional_path(key, base) if spec.kind == "path"
                          else r.value(key, spec))
    kwargs.update(given)
    r.check_unknown(table_keys(table))
    try:
        return cls(**kwargs)
    except SchemaError as exc:
        raise ConfigError(exc.detail, source=r.source, field=exc.key) from None


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
    """Load and validate a project. ``overrides`` maps dotted field names (:data:`FIELD` keys
    of :mod:`radtree.config.switches`) to values."""
    path = find_project_file(project)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"not valid TOML: {exc}", source=str(path)) from exc
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f"cannot read: {exc}", source=str(path)) from exc
    for key, value in (overrides or {}).items():
        lookup_key(key, FIELD, source=str(path))
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


def parse_project(data: dict, path: Path) -> Project:
    """The :class:`Project` of the TOML ``data`` of the file at ``path``: each table read in
    turn (unknown tables and fields refused with the known ones listed)."""
    src = str(path)
    base = path.parent
    top = _Reader(data, "", src)

    proj = top.sub("project")
    name = proj.value("name", Spec("str"), path.parent.name)
    measured = proj.optional_path("measured", base)
    measured_rows = proj.optional_path("measured_rows", base)
    proj.check_unknown(table_keys("project"))
    site, honeybee, district = _site(top.sub("site", required=True), base, name)
    street = _street(top.sub("street"), base)
    light = _table(top.sub("light"), "light", base)
    tree = _tree(top.sub("tree"), base)
    _one_crown_inputs(top.sub("tree"), tree, district)
    sensors = _sensors(top.sub("sensors"), base, site.hours)
    engine = _table(top.sub("engine"), "engine", base)
    office = _table(top.sub("office"), "office", base) if top.has("office") else None
    limits = _table(top.sub("limits"), "limits", base)
    extra = _extra_geometry(top, base)
    scenarios = _scenarios(top, src)
    top.raw("sweep")  # read by radtree.sweep
    top.check_unknown(TOP_TABLES)
    return Project(name=name, root=path.parent, source=path, site=site, street=street,
                   light=light, tree=tree, sensors=sensors, engine=engine,
                   scenarios=scenarios, measured=measured, measured_rows=measured_rows,
                   office=office, extra_geometry=tuple(extra), honeybee=honeybee,
                   limits=limits, district=district)


def _site(s: _Reader, base: Path, name: str) -> tuple[Site, Any, Any]:
    """``[site]``: the Site (hours, the date — left out: the summer solstice of the site's
    hemisphere —, the time zone and its standard offset), its Honeybee model and its
    inventory district (:mod:`radtree.config.honeybee`, :mod:`radtree.config.district`)."""
    src = s.source
    s.data = dict(s.data)  # [site] honeybee = "model.hbjson" (radtree.config.honeybee)
    honeybee = read_honeybee(s.data, base, src)
    district = read_district(s.data, base, src)   # [site] trees / buildings (own module)
    s.data = {k: v for k, v in s.data.items() if k not in DISTRICT_KEYS}
    hours_raw = s.raw("hours")
    if not isinstance(hours_raw, list) or not hours_raw:
        raise s.error("hours", f"expected a non-empty list of 'HH:MM' times, got {hours_raw!r}")
    hours = tuple(parse_time(h, f"site.hours[{i}]", src) for i, h in enumerate(hours_raw))
    if len(set(hours)) != len(hours):
        raise s.error("hours", "hours repeat")
    lat = s.value("latitude", spec_for(Site, "latitude"), required=True)
    date = s.value("date", spec_for(Site, "date"), "2024-06-21" if lat >= 0 else "2024-12-21")
    zone, _fixed = site_time_zone(
        s.value("time_zone", Spec("str", optional=True), None),
        s.value("utc_offset_hours", replace(spec_for(Site, "utc_offset_hours"), optional=True),
                None), source=src)
    site = _table(s, "site", base, hours=hours, name=s.value("name", Spec("str"), name),
                  elevation_m=s.value("elevation_m", spec_for(Site, "elevation_m"), 0.0),
                  date=date, time_zone=zone,
                  utc_offset_hours=standard_offset_hours(zone, date),
                  **{k: s.value(k, spec_for(Site, k), required=True)
                     for k in ("latitude", "longitude")})
    return site, honeybee, district


def _street(st: _Reader, base: Path) -> Street:
    """``[street]``; a ``ground_reflectance`` given as a file is the per-sun-angle table."""
    g = st.raw("ground_reflectance")
    ground: dict[str, Any] = {}
    if isinstance(g, str):
        ground = {"ground_reflectance": Street().ground_reflectance,
                  "ground_reflectance_table": st.optional_path("ground_reflectance", base)}
    return _table(st, "street", base, **ground)


def _tree(tr: _Reader, base: Path) -> Any:
    """``[tree]`` and its crown tables, the species filling what they leave out."""
    filled = species_fill(tr)
    crowns = {t: _table(r, f"tree.{t}", base, **{k: v for k, v in filled.get(t, {}).items()
                                                   if not r.has(k)})
              for t, r in ((t, tr.sub(t)) for t in TREE_TABLES)}
    return _table(tr, "tree", base, **crowns)


def _one_crown_inputs(tr: _Reader, tree: Any, district: Any) -> None:
    """``[tree] points``, ``points_scans`` and ``voxels`` describe one crown (repeated along a
    row); an inventory's crowns come from its rows, so they are refused there, not ignored."""
    if district is None or getattr(district, "trees", None) is None:
        return
    for key in ("points", "points_scans", "voxels"):
        if getattr(tree, key) is not None:
            raise tr.error(key, f"got {tr.raw(key)!r}, but the project's crowns come from the "
                           "tree inventory ([site] trees: one crown per row, from its species, "
                           "height, crown diameter and outline); remove [tree] " + key + " or "
                           "study that one crown in a project without [site] trees")


def _sensors(se: _Reader, base: Path, hours: tuple[str, ...]) -> Any:
    """``[sensors]``; its ``dense_hours`` must be among the site's hours."""
    dense = se.value("dense_hours", spec_for(TABLES["sensors"], "dense_hours"), ())
    unknown = [h for h in dense if h not in hours]
    if unknown:
        raise se.error("dense_hours", f"{', '.join(unknown)} not among site.hours")
    return _table(se, "sensors", base, dense_hours=dense)


def _extra_geometry(top: _Reader, base: Path) -> list[tuple[Path, str]]:
    """Extra user geometry: ``[[geometry]] file = "x.obj", material = "name"``."""
    extra = []
    for i, item in enumerate(top.raw("geometry", []) or []):
        r = _Reader(item, f"geometry[{i}]", top.source)
        gpath = r.optional_path("file", base)
        if gpath is None:
            raise r.error("file", "missing (an OBJ/STL/PLY or .rad file)")
        extra.append((gpath, r.value("material", Spec("str"), required=True)))
        r.check_unknown(GEOMETRY_KEYS)
    return extra


def species_fill(tr: _Reader) -> dict[str, dict[str, float]]:
    """``[tree] species``: the crown-table fields its species fills (those the file does not
    give are taken, see :func:`radtree.config.species.tree_defaults`); {} without a species."""
    if not tr.has("species"):
        return {}
    name = tr.value("species", Spec("str"))
    sp = find_species(name)
    if sp is None:
        raise tr.error("species", unknown_species_message(name))
    given = {t: dict(tr.data[t]) for t in ("louvers", "homogeneous", "perforated")
             if isinstance(tr.data.get(t), dict)}
    return tree_defaults(sp, given)


def _scenarios(top: _Reader, src: str) -> tuple[Scenario, ...]:
    raw_sc = top.raw("scenario", None)
    if raw_sc is None:
        raw_sc = [{"name": "base", "model": "louvers"}]
    if not isinstance(raw_sc, list) or not raw_sc:
        raise ConfigError("expected one or more [[scenario]] tables", source=src, field="scenario")
    scenarios = []
    for i, item in enumerate(raw_sc):
        r = _Reader(item, f"scenario[{i}]", src)
        kwargs: dict[str, Any] = {}
        for f in fields(Scenario):
            spec = spec_of(Scenario, f.name)
            if spec is not None:
                kwargs[f.name] = r.value(f.name, spec, f.default if f.name not in (
                    "name", "model") else None, required=f.name in ("name", "model"))
        sw = r.raw("switches", {})
        check_switches(sw, source=src, where=f"scenario[{i}].switches")
        if not re.match(r"^[A-Za-z0-9_.-]+$", kwargs["name"]):
            raise r.error("name", f"got {kwargs['name']!r}: use letters, digits, _ . - only "
                          "(it names a folder)")
        r.check_unknown(SCENARIO_KEYS)
        scenarios.append(Scenario(switches=dict(sw), **kwargs))
    names = [sc.name for sc in scenarios]
    if len(set(names)) != len(names):
        raise ConfigError(f"scenario names repeat: {names}", source=src, field="scenario")
    marked = [sc.name for sc in scenarios if sc.baseline]
    if len(marked) > 1:
        raise ConfigError(f"baseline = true on scenarios {', '.join(marked)}: mark one (the "
                          "scenario the report measures the trees against)", source=src,
                          field="scenario.baseline")
    return tuple(scenarios)
