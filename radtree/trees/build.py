"""Build the crown of a scenario: ``build_tree(project, scenario, frame) -> TreeModel``.

The form is ``scenario.form or project.tree.form`` (``"dome"`` | ``"free"``), the model
``scenario.model``, one of the registered crown models (:mod:`radtree.trees.registry`:
``homogeneous``, ``perforated``, ``louvers``, ``none``), built by the registry's builder for
``[tree] representation``.

Scenario ``switches`` override crown parameters with dotted keys naming a table of ``[tree]``
and one of its fields, e.g. ``"louvers.layers" = 6``, ``"louvers.specular_fraction" = 0``,
``"homogeneous.transmittance" = 0.2``, ``"dome.radius_m" = 3.5``, ``"crown.clearance_m" = 0.2``
(a leading ``"tree."`` is allowed). ``"louvers.reading" = "study" | "gap"`` applies a preset
(:data:`radtree.config.LOUVER_READINGS`). The keys and their types are those of the one
registry, :mod:`radtree.config.switches`; switches whose first part is not ``tree`` or a tree
table belong to other parts of radtree and are left to them here.
"""

from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path
from typing import Any

from radtree.config import (
    LOUVER_READINGS,
    TREE_FORMS,
    TREE_TABLES,
    Project,
    Scenario,
    SchemaError,
    Tree,
    check_key,
)
from radtree.errors import ConfigError
from radtree.site.frame import FacadeFrame
from radtree.trees.model import TreeModel
from radtree.trees.registry import crown_builder
from radtree.trees.species import load_species

__all__ = ["TreeModel", "apply_switches", "build_crown", "build_tree", "resolve_form"]

def apply_switches(tree: Tree, switches: dict[str, Any], *, source: str | None = None,
                   root: Path | None = None) -> tuple[Tree, list[str]]:
    """Apply the crown switches (keys of ``[tree]``, typed by :mod:`radtree.config.switches`;
    relative paths against ``root``); returns the new Tree and what was changed. Keys of the
    rest of radtree are left to the code they concern."""
    changed: list[str] = []
    for name, value in (switches or {}).items():
        first = str(name).split(".")[0]
        if first != "tree" and first not in TREE_TABLES:
            continue
        key, new = check_key(name, value, source=source)
        if key.name == "tree.louvers.reading":
            preset: dict[str, Any] = LOUVER_READINGS[new]
            tree = replace(tree, louvers=replace(tree.louvers, **preset))
            changed.append(f"louvers.reading = {new!r} ({LOUVER_READINGS[new]})")
            continue
        if key.spec.kind == "path" and new is not None:
            p = Path(new)
            new = p if p.is_absolute() or root is None else (root / p).resolve()
        try:
            if len(key.attr) == 2:  # tree.form
                tree = replace(tree, **{key.attr[1]: new})
                changed.append(f"tree.{key.attr[1]} = {new!r}")
                continue
            _, section, attr = key.attr
            tree = replace(tree, **{section: replace(getattr(tree, section), **{attr: new})})
        except SchemaError as exc:
            raise ConfigError(exc.detail, source=source, field=exc.key) from None
        changed.append(f"{section}.{attr} = {new!r}")
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
    builder = crown_builder(model, tree.representation, source)
    result = builder(tree, sensors=project.sensors, street=project.street, frame=frame,
                     form=form, source=source)
    if tree.species is not None and model != "none":
        sp = load_species(tree.species)
        result.notes.insert(0, f"Species {sp.name} ({sp.common_name}, "
                            f"materials/species/{sp.key}.toml) fills the leaf optics, leaf tilt "
                            f"and permeability the [tree.*] tables leave out: {sp.describe(project.site.latitude)}.")
    result.build_seconds = time.perf_counter() - t0
    result.frame = frame
    result.triangles = sum(m.n_triangles for m in result.meshes)
    result.info["triangles"] = float(result.triangles)
    return result


def _crown_key(project: Project, model: str, form: str, frame: FacadeFrame,
               tree: Tree) -> str:
    """The build-cache key of a crown: model, form, tree tables (files by path and content:
    a photo crown records its photo's path), sensors, street (files by name and content),
    frame and radtree's code (:func:`radtree.cache.content_key`)."""
    from radtree.cache import content_key

    return content_key(what="crown", model=model, form=form, tree=tree, located=("tree",),
                       sensors=project.sensors, street=project.street, frame=frame)


def _crown_of(project: Project, model: str, form: str, frame: FacadeFrame,
              tree: Tree) -> TreeModel:
    """:func:`build_crown`, or the same crown from the build cache (:mod:`radtree.cache`);
    ``TreeModel.from_cache`` says which."""
    if model == "none":
        return build_crown(project, model, form, frame, tree)
    from radtree.cache import cached_object

    crown, hit = cached_object(_crown_key(project, model, form, frame, tree),
                               lambda: build_crown(project, model, form, frame, tree))
    crown.from_cache = hit
    return crown  # type: ignore[no-any-return]


def scenario_tree(project: Project, scenario: Scenario) -> tuple[Tree, list[str], str]:
    """The scenario's ``[tree]`` after its switches, what they changed, and its form."""
    source = str(project.source)
    tree, changed = apply_switches(project.tree, scenario.switches, source=source,
                                   root=project.root)
    form = (scenario.form or tree.form)
    if form not in TREE_FORMS:
        raise ConfigError(f"got {form!r}, expected one of {', '.join(TREE_FORMS)}",
                          source=source, field="tree.form")
    return tree, changed, form


def crown_in_cache(project: Project, scenario: Scenario, frame: FacadeFrame,
                   tree_form: tuple[Tree, str] | None = None) -> bool:
    """True when the build cache holds the scenario's crown (``project``: the scenario's
    effective project), so building it costs no crown geometry. ``tree_form``: the scenario's
    tree and form from :func:`scenario_tree` when the caller has them."""
    from radtree.cache import has_object

    if scenario.model == "none":
        return True
    if tree_form is None:
        tree, _, form = scenario_tree(project, scenario)
    else:
        tree, form = tree_form
    return has_object(_crown_key(project, scenario.model, form, frame, tree))


def build_tree(project: Project, scenario: Scenario, frame: FacadeFrame) -> TreeModel:
    """The crown model of ``scenario`` (form, model and switches applied), in world space."""
    tree, changed, form = scenario_tree(project, scenario)
    model = _crown_of(project, scenario.model, form, frame, tree)
    if changed:
        model.notes.insert(0, f"Scenario '{scenario.name}' switches: " + "; ".join(changed) + ".")
    return model
