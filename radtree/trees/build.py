"""Build the crown of a scenario: ``build_tree(project, scenario, frame) -> TreeModel``.

The form is ``scenario.form or project.tree.form`` (``"dome"`` | ``"free"``), the model
``scenario.model`` (``"homogeneous"`` | ``"perforated"`` | ``"louvers"`` | ``"none"``).

Scenario ``switches`` override crown parameters with dotted keys naming a table of ``[tree]``
and one of its fields, e.g. ``"louvers.layers" = 6``, ``"louvers.specular_fraction" = 0``,
``"homogeneous.transmittance" = 0.2``, ``"dome.radius_m" = 3.5``, ``"crown.clearance_m" = 0.2``
(a leading ``"tree."`` is allowed). ``"louvers.reading" = "study" | "gap"`` applies a preset
(:data:`radtree.trees.louvers.READINGS`). Switches whose first part is not a tree table
(``dome``, ``crown``, ``homogeneous``, ``perforated``, ``louvers``) belong to other parts of
radtree and are ignored here; an unknown field of a tree table is an error.
"""

from __future__ import annotations

import time
from dataclasses import fields, replace
from pathlib import Path
from typing import Any

from radtree.config import (
    TREE_FORMS,
    Crown,
    Dome,
    Homogeneous,
    Louvers,
    Perforated,
    Project,
    Scenario,
    Tree,
)
from radtree.errors import ConfigError
from radtree.site.frame import FacadeFrame
from radtree.trees.homogeneous import build_homogeneous
from radtree.trees.louvers import READINGS, build_louvers
from radtree.trees.model import TreeModel
from radtree.trees.perforated import build_perforated

__all__ = ["TreeModel", "apply_switches", "build_crown", "build_tree", "resolve_form"]

SECTIONS: dict[str, type] = {
    "dome": Dome, "crown": Crown, "homogeneous": Homogeneous, "perforated": Perforated,
    "louvers": Louvers,
}


def _coerce(value: Any, current: Any, annotation: Any, where: str, source: str | None,
            root: Path | None) -> Any:
    def bad(expected: str) -> ConfigError:
        return ConfigError(f"got {value!r}, expected {expected}", source=source, field=where)

    text = str(annotation)
    if isinstance(current, bool) or text == "bool":
        if not isinstance(value, bool):
            raise bad("true or false")
        return value
    if isinstance(current, int) or text == "int":
        if isinstance(value, bool) or not isinstance(value, int | float) or int(value) != value:
            raise bad("an integer")
        return int(value)
    if isinstance(current, float) or text in ("float", "float | None"):
        if value is None and "None" in text:
            return None
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise bad("a number")
        return float(value)
    if isinstance(current, str) or text == "str":
        if not isinstance(value, str):
            raise bad("text")
        return value
    if "Path" in text:
        if value is None:
            return None
        if not isinstance(value, str | Path):
            raise bad("a file path")
        p = Path(value)
        return p if p.is_absolute() or root is None else (root / p).resolve()
    if "tuple" in text:
        if value is None:
            return None
        if not isinstance(value, list | tuple) or len(value) != 3:
            raise bad("[centre_x, centre_y, radius]")
        return tuple(float(v) for v in value)
    return value


def apply_switches(tree: Tree, switches: dict[str, Any], *, source: str | None = None,
                   root: Path | None = None) -> tuple[Tree, list[str]]:
    """Apply dotted crown-parameter switches; returns the new Tree and what was changed."""
    changed: list[str] = []
    for key, value in (switches or {}).items():
        parts = str(key).split(".")
        if parts and parts[0] == "tree":
            parts = parts[1:]
        where = f"switches.{key}"
        if len(parts) == 1 and parts[0] == "form":
            if value not in TREE_FORMS:
                raise ConfigError(f"got {value!r}, expected one of {', '.join(TREE_FORMS)}",
                                  source=source, field=where)
            tree = replace(tree, form=value)
            changed.append(f"tree.form = {value!r}")
            continue
        if len(parts) != 2 or parts[0] not in SECTIONS:
            continue
        section, name = parts
        current = getattr(tree, section)
        if section == "louvers" and name == "reading":
            if value not in READINGS:
                raise ConfigError(f"got {value!r}, expected one of {', '.join(READINGS)}",
                                  source=source, field=where)
            current = replace(current, **READINGS[value])
            tree = replace(tree, louvers=current)
            changed.append(f"louvers.reading = {value!r} ({READINGS[value]})")
            continue
        known = {f.name: f for f in fields(current)}
        fname = name if name in known else (name + "_" if name + "_" in known else None)
        if fname is None:
            raise ConfigError(f"unknown crown parameter '{name}' of [tree.{section}] (known: "
                              f"{', '.join(sorted(known))})", source=source, field=where)
        new = _coerce(value, getattr(current, fname), str(known[fname].type), where, source,
                      root)
        tree = replace(tree, **{section: replace(current, **{fname: new})})
        changed.append(f"{section}.{fname} = {new!r}")
    return tree, changed


def resolve_form(project: Project, scenario: Scenario | None) -> str:
    form = (scenario.form if scenario is not None else None) or project.tree.form
    if form not in TREE_FORMS:
        raise ConfigError(f"got {form!r}, expected one of {', '.join(TREE_FORMS)}",
                          source=str(project.source), field="tree.form")
    return form


def build_crown(project: Project, model: str, form: str, frame: FacadeFrame,
                tree: Tree | None = None) -> TreeModel:
    """Build ``model`` in ``form`` from ``tree`` (default the project's) without a scenario."""
    tree = tree or project.tree
    source = str(project.source)
    t0 = time.perf_counter()
    if model == "none":
        result = TreeModel(meshes=[], materials={}, notes=[
            "No crown (model 'none'): the unobstructed reference."], recommended_ab=2,
            form=form, model="none")
    elif model == "homogeneous":
        result = build_homogeneous(tree, project.sensors, project.street, frame, form, source)
    elif model == "perforated":
        result = build_perforated(tree, project.sensors, project.street, frame, form, source)
    elif model == "louvers":
        result = build_louvers(tree, project.sensors, project.street, frame, form, source)
    else:
        raise ConfigError(f"got {model!r}, expected homogeneous, perforated, louvers or none",
                          source=source, field="scenario.model")
    result.build_seconds = time.perf_counter() - t0
    result.frame = frame
    result.triangles = sum(m.n_triangles for m in result.meshes)
    result.info.setdefault("triangles", float(result.triangles))
    result.info["triangles"] = float(result.triangles)
    return result


def build_tree(project: Project, scenario: Scenario, frame: FacadeFrame) -> TreeModel:
    """The crown model of ``scenario`` (form, model and switches applied), in world space."""
    source = str(project.source)
    tree, changed = apply_switches(project.tree, scenario.switches, source=source,
                                   root=project.root)
    form = (scenario.form or tree.form)
    if form not in TREE_FORMS:
        raise ConfigError(f"got {form!r}, expected one of {', '.join(TREE_FORMS)}",
                          source=source, field="tree.form")
    model = build_crown(project, scenario.model, form, frame, tree)
    if changed:
        model.notes.insert(0, f"Scenario '{scenario.name}' switches: " + "; ".join(changed) + ".")
    return model
