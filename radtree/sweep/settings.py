"""The ``[sweep]`` table of a project file, and checking swept field names (the registry).

``radtree.config`` does not read ``[sweep]``; the sweep reads the raw TOML itself and hands the
rest to :func:`radtree.config.parse_project`. The table (every key optional)::

    [sweep]
    design = "full"           # or "lhs"
    samples = 24              # lhs only (default 10 per parameter)
    seed = 1                  # lhs only
    scenarios = ["A"]         # default: every scenario
    hours = ["10:30"]         # default: the project's hours
    engine = "auto"           # auto | radiance | numpy
    workers = 2               # local cluster size (default: CPU cores)
    scheduler = "tcp://10.0.0.5:8786"   # an existing dask cluster (default: a local one)
    out = "sweep"             # output folder, relative to the project

    [sweep.params]            # field = "low:high:n" | "v1,v2" | [v1, v2]
    "tree.crown.trunk_distance_m" = "2:6:5"
    "tree.louvers.layers" = [3, 4, 5]

    [sweep.set]               # fixed overrides applied to every case
    "sensors.dense_grid" = false

Dotted keys may be quoted (as above) or written as nested tables; both mean the same field.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import tomllib

from radtree.config import KEYS, Project, check_fields, find_project_file, parse_project
from radtree.engines.registry import ENGINE_CHOICES
from radtree.errors import ConfigError
from radtree.sweep.design import DESIGNS, Parameter, parse_spec

SCHEDULER_KINDS = ("local", "sequential")
_KEYS = {"design", "samples", "seed", "scenarios", "hours", "engine", "workers", "scheduler",
         "out", "params", "set"}


@dataclass
class SweepSettings:
    """What the ``[sweep]`` table says (None = not given)."""

    params: list[Parameter] = field(default_factory=list)
    fixed: dict[str, Any] = field(default_factory=dict)
    design: str | None = None
    samples: int | None = None
    seed: int | None = None
    scenarios: list[str] | None = None
    hours: list[str] | None = None
    engine: str | None = None
    workers: int | None = None
    scheduler: str | None = None
    out: str | None = None


def read_raw(project: str | Path) -> tuple[Path, dict[str, Any]]:
    """The project file's path and its raw TOML data (``[sweep]`` included)."""
    path = find_project_file(project)
    try:
        return path, tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"not valid TOML: {exc}", source=str(path)) from exc
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f"cannot read: {exc}", source=str(path)) from exc


def split_sweep(data: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
    """(project data without ``[sweep]``, the ``[sweep]`` table) — the input is not changed."""
    rest = copy.deepcopy(data)
    table = rest.pop("sweep", {})
    return rest, table


def _flatten(table: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    out: dict[str, Any] = {}
    for k, v in table.items():
        name = f"{prefix}.{k}" if prefix else k
        if isinstance(v, dict):
            out.update(_flatten(v, name))
        else:
            out[name] = v
    return out


def parse_sweep_table(table: dict[str, Any], source: str) -> SweepSettings:
    """Validate the ``[sweep]`` table."""
    if not isinstance(table, dict):
        raise ConfigError("expected a table", source=source, field="sweep")
    unknown = sorted(set(table) - _KEYS)
    if unknown:
        raise ConfigError(f"unknown field (known here: {', '.join(sorted(_KEYS))})",
                          source=source, field=f"sweep.{unknown[0]}")
    s = SweepSettings()

    def err(key: str, msg: str) -> ConfigError:
        return ConfigError(msg, source=source, field=f"sweep.{key}")

    params = table.get("params", {})
    if not isinstance(params, dict):
        raise err("params", "expected a table of field = values")
    for name, spec in _flatten(params).items():
        try:
            s.params.append(parse_spec(name, spec))
        except ConfigError as exc:
            raise ConfigError(str(exc), source=source, field=f"sweep.params.{name}") from None
    fixed = table.get("set", {})
    if not isinstance(fixed, dict):
        raise err("set", "expected a table of field = value")
    s.fixed = _flatten(fixed)
    if "design" in table:
        if table["design"] not in DESIGNS:
            raise err("design", f"got {table['design']!r}, expected one of {', '.join(DESIGNS)}")
        s.design = table["design"]
    for key in ("samples", "seed", "workers"):
        if key in table:
            v = table[key]
            if isinstance(v, bool) or not isinstance(v, int) or v < (0 if key == "seed" else 1):
                raise err(key, f"expected a whole number ≥ {0 if key == 'seed' else 1}, "
                          f"got {v!r}")
            setattr(s, key, v)
    for key in ("scenarios", "hours"):
        if key in table:
            v = table[key]
            if not isinstance(v, list) or not v or not all(isinstance(x, str) for x in v):
                raise err(key, f"expected a non-empty list of text values, got {v!r}")
            setattr(s, key, list(v))
    for key in ("engine", "scheduler", "out"):
        if key in table:
            if not isinstance(table[key], str) or not table[key]:
                raise err(key, f"expected text, got {table[key]!r}")
            setattr(s, key, table[key])
    if s.engine is not None and s.engine not in ENGINE_CHOICES:
        raise err("engine", f"got {s.engine!r}, expected {', '.join(ENGINE_CHOICES)}")
    return s


def load_base(project: str | Path) -> tuple[Path, dict[str, Any], SweepSettings, Project]:
    """Project file path, its data without ``[sweep]``, the sweep settings, the loaded project."""
    path, data = read_raw(project)
    rest, table = split_sweep(data)
    settings = parse_sweep_table(table, str(path))
    return path, rest, settings, parse_project(copy.deepcopy(rest), path)


# ---------------------------------------------------------------- fields
def check_names(parameters: list[str], fixed: list[str], path: Path) -> None:
    """Swept and fixed names must be fields of the project file (the one registry,
    :mod:`radtree.config.switches`); the message lists the known fields."""
    check_fields(parameters, source=str(path), verb="sweep")
    check_fields(fixed, source=str(path), verb="set")


def resolve_parameters(parameters: list[Parameter]) -> list[Parameter]:
    """Mark ranges over integer fields (from the field's registered kind) as integer."""
    out = []
    for p in parameters:
        key = KEYS.get(p.name)
        if p.kind == "range" and key is not None:
            if key.spec.kind not in ("int", "float"):
                raise ConfigError(f"{p.name}={p.text}: a numeric range for a field holding "
                                  f"{key.spec.expected()}; give a list of values", field=p.name)
            p = replace(p, integer=key.spec.kind == "int")
        out.append(p)
    return out
