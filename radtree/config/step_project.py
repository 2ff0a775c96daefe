"""Writing a project file with one scenario added: what ``radtree diagnose`` leaves at each step.

:func:`write_step_project` copies the user's project file (the user's file is never touched)
to a new place with a scenario appended, or replacing one of the same name, rewrites the
relative data paths for the new folder, and checks that the written scenario reads back as
written. :func:`scenario_table` is a :class:`~radtree.config.Scenario` as its TOML table.
"""

from __future__ import annotations

import os
from dataclasses import replace
from pathlib import Path
from typing import Any

import tomllib

from radtree.config.reader import find_project_file, load_project
from radtree.config.schema import Project, Scenario
from radtree.config.switches import PATH_FIELDS
from radtree.errors import RadtreeError
from radtree.fileio import write_text


def _relocate(value: Any, old: Path, new: Path) -> Any:
    """A relative data path of the project at ``old`` as seen from ``new``: relative when
    ``new`` lies inside the project folder, else absolute."""
    if isinstance(value, str) and value and not Path(value).is_absolute():
        target = old / value
        if target.exists():
            if new.resolve().is_relative_to(old.resolve()):
                return os.path.relpath(target.resolve(), new.resolve())
            return str(target.resolve())
    return value


def scenario_table(sc: Scenario) -> dict[str, Any]:
    d: dict[str, Any] = {"name": sc.name, "model": sc.model, "reflection": sc.reflection}
    if sc.sky is not None:
        d["sky"] = sc.sky
    if sc.form is not None:
        d["form"] = sc.form
    if sc.description:
        d["description"] = sc.description
    if sc.switches:
        d["switches"] = dict(sc.switches)
    return d


def write_step_project(project: Project, scenario: Scenario, path: Path,
                       header: str = "") -> Scenario:
    """Write the user's project file with ``scenario`` appended (or replacing one of the same
    name) to ``path``; relative data paths are rewritten for the new folder. Returns the
    scenario as loaded back from the written file (checked to equal ``scenario``)."""
    from radtree.tomlout import dumps

    src = find_project_file(project.source)
    data = tomllib.loads(src.read_text(encoding="utf-8"))
    old, new = src.parent, path.parent
    new.mkdir(parents=True, exist_ok=True)
    for name in PATH_FIELDS:
        parts = name.split(".")
        table: Any = data
        for p in parts[:-1]:
            table = table.get(p) if isinstance(table, dict) else None
        if isinstance(table, dict) and parts[-1] in table:
            table[parts[-1]] = _relocate(table[parts[-1]], old, new)
    for item in data.get("geometry", []) or []:
        if isinstance(item, dict) and "file" in item:
            item["file"] = _relocate(item["file"], old, new)
    scs = [s for s in data.get("scenario", []) if s.get("name") != scenario.name]
    for s in scs:
        sw = s.get("switches")
        if isinstance(sw, dict):
            s["switches"] = {k: _relocate(v, old, new) for k, v in sw.items()}
    table_new = scenario_table(scenario)
    if "switches" in table_new:
        table_new["switches"] = {k: _relocate(v, old, new)
                                 for k, v in table_new["switches"].items()}
    data["scenario"] = scs + [table_new]
    write_text(path, dumps(data, header=header))
    loaded = load_project(path).scenario(scenario.name)
    same = (loaded.model == scenario.model and loaded.reflection == scenario.reflection
            and loaded.sky == scenario.sky and loaded.form == scenario.form
            and _plain_switches(loaded.switches) == _plain_switches(table_new.get("switches",
                                                                                  {})))
    if not same:
        raise RadtreeError(f"{path}: the written scenario {scenario.name} does not read back "
                           f"as written ({loaded} vs {scenario})")
    return replace(loaded, switches=dict(scenario.switches))


def _plain_switches(sw: dict[str, Any]) -> dict[str, Any]:
    return {k: (float(v) if isinstance(v, int | float) and not isinstance(v, bool) else v)
            for k, v in sw.items()}
