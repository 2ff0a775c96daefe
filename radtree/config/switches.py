"""The ONE registry of dotted keys: every name a scenario switch, ``--set``, a sweep parameter
or a diagnose effect can give, typed, with the full list of known keys on a miss.

Two uses (a key may have both):

* :data:`FIELD` — a field of the project file by its TOML path (``tree.louvers.layers``,
  ``engine.as``, ``light.direct_normal``, ``office.bays``, ``project.measured``, …): what
  ``load_project(overrides=…)``, ``radtree sweep --param/--set`` and ``[sweep.params]`` /
  ``[sweep.set]`` name. Their values are checked when the case's project file is read.
* :data:`SWITCH` — a key of a scenario's ``switches`` (and what a diagnose effect writes
  there): the ``site``, ``street``, ``light``, ``sensors`` and ``engine`` fields that
  :func:`effective_project` replaces (not the data paths nor the lists of hours); the
  ``tree`` fields (the leading ``tree.`` may be dropped: ``"louvers.layers"``), which
  :func:`radtree.trees.build.apply_switches` applies; and the keys code reads:
  ``tree.louvers.reading`` (a preset of :data:`LOUVER_READINGS`) and ``reflection.*``
  (:mod:`radtree.light.ground`). Switch values are typed and bounded here.

The keys of the file's tables come from the dataclass fields of :mod:`radtree.config.schema`
(their TOML names, kinds, bounds and choices), so a new field is known everywhere at once.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable
from dataclasses import dataclass, replace
from typing import Any

from radtree.config.bsdf import CrownBsdf
from radtree.config.limits import Limits
from radtree.config.schema import (
    LOUVER_READINGS,
    Crown,
    Dome,
    EngineParams,
    Homogeneous,
    Light,
    Louvers,
    Office,
    Perforated,
    Project,
    Scenario,
    Sensors,
    Site,
    Street,
    Tree,
)
from radtree.config.spec import SchemaError, Spec, spec_of, table_fields, toml_name
from radtree.errors import ConfigError

FIELD = "field"
SWITCH = "switch"

#: The project file's tables and their dataclasses (``[project]`` is read into Project itself).
TABLES: dict[str, type] = {
    "site": Site, "street": Street, "light": Light, "tree": Tree, "tree.dome": Dome,
    "tree.crown": Crown, "tree.homogeneous": Homogeneous, "tree.perforated": Perforated,
    "tree.louvers": Louvers, "tree.bsdf": CrownBsdf, "sensors": Sensors, "engine": EngineParams,
    "office": Office, "limits": Limits,
}
#: Tables whose fields a scenario switch replaces through :func:`effective_project`.
PROJECT_SWITCH_SECTIONS = ("site", "street", "light", "sensors", "engine")
#: The crown tables of ``[tree]`` (switch keys may start with them instead of ``tree.``).
TREE_TABLES = ("dome", "crown", "homogeneous", "perforated", "louvers", "bsdf")
#: ``reflection.ground``: the street under the crown's shade, or the open street.
REFLECTION_GROUNDS = ("shaded", "open")
#: ``reflection.view_factor``: a street of the canyon's width, or an unbounded ground (0.5).
REFLECTION_VIEW_FACTORS = ("street", "unbounded")


@dataclass(frozen=True)
class Key:
    """One dotted key: canonical ``name``, the :class:`Spec` of its values, its ``uses``
    (:data:`FIELD`, :data:`SWITCH`) and, for a project field, its attribute path in a
    :class:`Project` (``("engine", "as_")``); ``()`` for a key that code reads."""

    name: str
    spec: Spec
    uses: frozenset[str]
    attr: tuple[str, ...] = ()
    doc: str = ""


def _field_keys() -> dict[str, Key]:
    keys = {f"project.{n}": Key(f"project.{n}", Spec(kind), frozenset({FIELD}), (n,))
            for n, kind in (("name", "str"), ("measured", "path"), ("measured_rows", "path"))}
    for table, cls in TABLES.items():
        section = table.split(".")[0]
        for f in table_fields(cls):
            s = spec_of(cls, f.name)
            if s is None:
                continue
            name = f"{table}.{toml_name(cls, f.name)}"
            switch = f.metadata.get("switch", True) and (
                section == "tree" or (section in PROJECT_SWITCH_SECTIONS and s.kind != "path"))
            uses = frozenset({FIELD, SWITCH} if switch else {FIELD})
            keys[name] = Key(name, s, uses, (*table.split("."), f.name))
    return keys


_CODE_KEYS = (
    Key("tree.louvers.reading", Spec("str", choices=tuple(LOUVER_READINGS)),
        frozenset({SWITCH}), doc="a preset of the slat optics"),
    Key("reflection.ground", Spec("str", choices=REFLECTION_GROUNDS), frozenset({SWITCH}),
        doc="calculated reflection: E_ground of the shaded or the open street"),
    Key("reflection.view_factor", Spec("str", choices=REFLECTION_VIEW_FACTORS),
        frozenset({SWITCH}), doc="calculated reflection: the view factor to the street"),
    Key("reflection.permeability", Spec("float", 0.0, 1.0), frozenset({SWITCH}),
        doc="calculated reflection: the crown's permeability shading the street"),
    Key("reflection.unfiltered", Spec("float", 0.0, 1.0), frozenset({SWITCH}),
        doc="share of the open street's reflected light reaching the façade unfiltered"),
)

#: Every key by its canonical name.
KEYS: dict[str, Key] = {**_field_keys(), **{k.name: k for k in _CODE_KEYS}}
#: The project file's data paths (resolved against the project folder).
PATH_FIELDS: tuple[str, ...] = tuple(k.name for k in KEYS.values()
                                     if k.spec.kind == "path" or k.spec.path_ok)


def known(use: str = SWITCH) -> tuple[str, ...]:
    """The canonical names of every key of ``use``, sorted."""
    return tuple(sorted(k.name for k in KEYS.values() if use in k.uses))


def table_keys(table: str) -> tuple[str, ...]:
    """The names a table of the project file holds (fields and sub-tables), sorted."""
    prefix = table + "."
    names = {n[len(prefix):].split(".")[0] for n, k in KEYS.items()
             if FIELD in k.uses and n.startswith(prefix)}
    return tuple(sorted(names))


def is_table(name: str) -> bool:
    """Whether ``name`` is a table of the project file (``tree.crown``, ``office``)."""
    return name in TABLES or name == "project"


def known_text(name: str, names: Iterable[str], what: str = "known") -> str:
    """``did you mean …? `` (close matches) followed by the full list ``names``."""
    names = list(names)
    close = difflib.get_close_matches(name, names, n=3, cutoff=0.6)
    hint = f"did you mean {' or '.join(close)}? " if close else ""
    return f"{hint}{what}: {', '.join(names)}"


def canonical(name: str, use: str = SWITCH) -> str:
    """The registry name of ``name``: a switch may drop the leading ``tree.``."""
    if use == SWITCH and name.split(".")[0] in TREE_TABLES:
        return "tree." + name
    return name


def lookup_key(name: Any, use: str = SWITCH, *, source: str | None = None,
           where: str | None = None) -> Key:
    """The :class:`Key` ``name`` names for ``use``; ConfigError naming it and listing the known
    keys (close matches first) otherwise."""
    text = str(name)
    key = KEYS.get(canonical(text, use)) if isinstance(name, str) else None
    if key is not None and use in key.uses:
        return key
    where = where or (f"switches.{text}" if use == SWITCH else text)
    names = known(use)
    if use == SWITCH:
        short = text.split(".")[0] in TREE_TABLES
        shown = [n[5:] if short and n.startswith("tree.") else n for n in names]
        why = (" (a field of the project file that a scenario cannot switch: data paths, "
               "lists of hours and [office] are set in the file)" if key is not None else "")
        raise ConfigError(f"unknown switch {text!r}{why}; " + known_text(
            text, shown, "known switches (tree.* may drop 'tree.')"), source=source, field=where)
    why = "" if key is None else " (it is not a field of the project file)"
    raise ConfigError(f"unknown field {text!r}{why}; " + known_text(
        text, names, "known fields"), source=source, field=where)


def check_key(name: Any, value: Any, use: str = SWITCH, *, source: str | None = None,
          where: str | None = None) -> tuple[Key, Any]:
    """The key and the value typed (a whole number for an integer field, a float for a number,
    a file path only in the file); ConfigError naming the key as written otherwise."""
    key = lookup_key(name, use, source=source, where=where)
    try:
        typed = key.spec.check(value, lenient=True, allow_path=use == FIELD)
    except ValueError as exc:
        also = f" ({key.name}: {key.spec.expected()})"
        raise ConfigError(f"{exc}{also}", source=source, field=where or (
            f"switches.{name}" if use == SWITCH else str(name))) from None
    return key, typed


def check_switches(switches: Any, *, source: str | None = None, where: str = "switches") -> None:
    """Check every key and value of a scenario's ``switches`` table."""
    if not isinstance(switches, dict):
        raise ConfigError(f"expected a table of dotted keys, got {switches!r}", source=source,
                          field=where)
    for name, value in switches.items():
        check_key(name, value, SWITCH, source=source, where=f"{where}.{name}")


def check_fields(names: Iterable[str], *, source: str | None = None, verb: str = "set") -> None:
    """Every name must be a field of the project file: ``cannot <verb> NAME: …`` otherwise."""
    for name in names:
        if is_table(name):
            raise ConfigError(f"cannot {verb} {name}: it is a table; {verb} one of its fields ("
                              f"{', '.join(table_keys(name))})", source=source, field=name)
        if FIELD not in getattr(KEYS.get(name), "uses", ()):
            raise ConfigError(f"cannot {verb} {name}: not a field of the project file; "
                              + known_text(name, known(FIELD), "known fields"),
                              source=source, field=name)


def effective_project(project: Project, scenario: Scenario) -> Project:
    """The project as a scenario sees it: switches naming a ``site``, ``street``, ``light``,
    ``sensors`` or ``engine`` field replace it (``"street.opposite_reflectance" = 0``,
    ``"light.diffuse_horizontal_lux" = 8000``, ``"engine.ab" = 6``); ``"street.ground_reflectance"
    = 0.15`` also drops the per-hour table (constant reflectance). The other switches (tree.*,
    reflection.*) are read by the code they concern."""
    source = str(project.source)
    changes: dict[str, dict[str, Any]] = {}
    for name, value in scenario.switches.items():
        key, typed = check_key(name, value, SWITCH, source=source)
        if not key.attr or key.attr[0] not in PROJECT_SWITCH_SECTIONS:
            continue
        section, attr = key.attr
        changes.setdefault(section, {})[attr] = typed
        if key.name == "street.ground_reflectance":
            changes[section]["ground_reflectance_table"] = None
    if not changes:
        return project
    try:
        return replace(project, **{s: replace(getattr(project, s), **c)
                                   for s, c in changes.items()})
    except SchemaError as exc:
        raise ConfigError(f"scenario {scenario.name}: {exc.detail}", source=source,
                          field=exc.key) from None


Scenario.switch_check = staticmethod(check_switches)  # type: ignore[assignment]
