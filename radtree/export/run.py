"""``export_project``: one project out in one format (see :mod:`radtree.export`).

``honeybee`` / ``idf`` / ``schedule`` need the scenario's crowns and their year of hourly
transmittances (:mod:`radtree.export.transmittance`); ``gltf`` / ``obj`` the scenario's whole
scene. The scenario is the one named, else the first with a crown model.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from radtree.config import Project, Scenario
from radtree.errors import ConfigError
from radtree.export import FORMATS


def export_scenario(project: Project, name: str | None, needs_crown: bool) -> Scenario:
    """The named scenario, else the first with a crown (any when no crown is needed)."""
    if name is not None:
        return project.scenario(name)
    for sc in project.scenarios:
        if sc.model != "none" or not needs_crown:
            return sc
    raise ConfigError("no scenario has a crown model to export (all are model 'none')",
                      source=str(project.source), field="scenario")


def leaf_material(meshes, materials):
    """The crown model's leaf material: that of its largest non-trunk mesh."""
    from radtree.trees.model import TRUNK

    crown = [m for m in meshes if m.material != TRUNK and m.n_triangles]
    return materials[max(crown, key=lambda m: m.n_triangles).material]


def export_project(project: Project, fmt: str, out: Path, scenario: str | None = None,
                   rays: int = 128, leaf_on: str | None = None, leaf_off: str | None = None,
                   seasons: bool = True, echo: Callable[[str], None] = print,
                   progress: bool = True, definition: str = "total") -> list[Path]:
    """Write ``project`` in format ``fmt`` into folder ``out``; return the files written.
    ``definition``: the schedules' transmittance, ``total`` or ``beam``
    (:mod:`radtree.export.transmittance`); the caveats that remain are echoed."""
    from radtree.pipeline.assemble import facade_frame, make_scene

    if fmt not in FORMATS:
        raise ConfigError(f"got {fmt!r}, expected one of {', '.join(FORMATS)}", field="--format")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    frame = facade_frame(project)
    sc = export_scenario(project, scenario, fmt not in ("gltf", "obj"))
    if fmt in ("gltf", "obj"):
        from radtree.export.scene_files import write_scene

        built = make_scene(project, sc)
        path = write_scene(built.scene, out, fmt, f"{sc.name}_scene")
        echo(f"{sc.name}: {len(built.scene.solid_meshes())} meshes, {built.triangles} "
             f"triangles → {path}")
        return [path]
    from radtree.export.transmittance import (
        CAVEATS,
        DEFINITIONS,
        crown_models,
        default_leaf_schedule,
        year_schedules,
    )
    from radtree.log import progress as progress_bar

    if sc.model == "none":
        raise ConfigError(f"scenario {sc.name!r} has no crown (model 'none'): choose one with "
                          "a crown model", source=str(project.source), field="--scenario")
    if definition not in DEFINITIONS:
        raise ConfigError(f"got {definition!r}, expected one of {', '.join(DEFINITIONS)}",
                          field="--definition")
    leaf = default_leaf_schedule(project, leaf_on, leaf_off)
    echo(f"{sc.name}: hourly crown transmittance ({definition}) along the sun for {8760} hours, "
         f"{rays} rays per hour and crown; leaf " + (
             f"on {leaf.leaf_on} → off {leaf.leaf_off} (MM-DD)" if seasons else "on all year"))

    def bar(idx, crown, state):
        chunks = [idx[i:i + 240] for i in range(0, len(idx), 240)]
        return progress_bar(chunks, desc=f"{crown} ({'leaf-on' if state else 'leaf-off'})",
                            unit="chunk") if progress else chunks

    models = crown_models(project, sc, frame)
    schedules = year_schedules(project, sc, frame, rays, leaf_on, leaf_off, seasons, bar, models,
                               definition)
    for cs in schedules:
        echo(f"  {cs.crown.name}: transmittance {cs.values.min():.4f}–{cs.values.max():.4f}, "
             f"mean {cs.values.mean():.4f} ({int(cs.leaf_on.sum())} leaf-on hours)")
    for caveat in CAVEATS:
        echo(f"  caveat: {caveat}")
    if fmt == "schedule":
        from radtree.export.honeybee import write_schedule_csv

        return list(write_schedule_csv(schedules, out))
    from radtree.export.honeybee import crown_shades, shade_model, write_hbjson, write_idf

    meshes, _, materials, _ = models
    base = None
    if project.honeybee is not None:
        from radtree.site.honeybee_model import load_model

        base = load_model(project.honeybee.model)
    model = shade_model(project.name, crown_shades(schedules, leaf_material(meshes, materials)),
                        base)
    path = write_hbjson(model, out) if fmt == "honeybee" else write_idf(model, out)
    echo(f"{len(schedules)} crown shades → {path}")
    return [path]
