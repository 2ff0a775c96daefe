"""A scenario's scene: street canyon (or office block), crown model, sensor grids, and the one
rule for its diffuse bounces (``-ab``)."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

from radtree.config import Project, Scenario, effective_project
from radtree.errors import RadtreeError
from radtree.pipeline.limits import check_triangles
from radtree.scene import Scene
from radtree.sensor_grid import street_grids
from radtree.site.district import street_frame as placed_frame
from radtree.site.frame import FacadeFrame
from radtree.site.street import street_materials, street_meshes

#: -ab of a scene without a crown model (direct + one interreflection)
OPEN_STREET_AB = 2


@dataclass
class BuiltScene:
    """A scenario's scene plus what the build learnt about it (``ab``: its diffuse bounces)."""

    scenario: Scenario
    scene: Scene
    ab: int
    notes: list[str]
    triangles: int
    geometry_seconds: float
    info: dict[str, float] = field(default_factory=dict)
    tree: Any = None


def facade_frame(project: Project) -> FacadeFrame:
    """The studied façade's local frame (x east, y north, z up; azimuth clockwise from north),
    placed by :func:`radtree.site.district.street_frame` (``[street] facade_line``, …)."""
    return placed_frame(project)


def scene_ab(project: Project, tree_ab: int | None) -> int:
    """The scene's ``-ab``: ``engine.ab`` when set (after the scenario's switches), else the
    crown model's recommendation (open street: 2), at least the rooms' 6 for an office block."""
    if project.engine.ab is not None:
        return int(project.engine.ab)
    ab = OPEN_STREET_AB if tree_ab is None else int(tree_ab)
    if project.office is not None:
        from radtree.site.office import RECOMMENDED_AB

        ab = max(ab, RECOMMENDED_AB)   # rooms need ~6 bounces (see the office notes)
    return ab


def make_scene(project: Project, scenario: Scenario, dense_grid: bool | None = None) -> BuiltScene:
    """The in-memory scene of one scenario: street canyon, crown model, sensor grids.

    Plan (the site: canyon, office block or Honeybee rooms) → execute (the crown model) →
    publish (user geometry, ``-ab``, triangle limit, the BuiltScene)."""
    if project.district is not None:   # [site] trees / buildings
        from radtree.pipeline.district import district_scene

        return district_scene(project, scenario, dense_grid, scene_ab, BuiltScene)  # type: ignore[no-any-return]
    project = effective_project(project, scenario)
    frame = facade_frame(project)
    meshes, materials, grids, notes = _site_parts(project, frame=frame, dense_grid=dense_grid)
    t0 = time.perf_counter()
    info: dict[str, float] = {}
    tree = None
    if scenario.model != "none":
        tree = _crown(project, scenario=scenario, frame=frame)
        clash = set(tree.materials) & set(materials)
        if clash:
            raise RadtreeError(f"crown model materials clash with the street's: {clash}")
        materials.update(tree.materials)
        meshes = meshes + list(tree.meshes)
        notes += list(tree.notes)
        info = dict(tree.info)
    geometry_seconds = time.perf_counter() - t0
    if project.extra_geometry:
        from radtree.site.user_geometry import load_user_meshes

        meshes = meshes + load_user_meshes(project.extra_geometry, materials)
    ab = scene_ab(project, None if tree is None else tree.recommended_ab)
    scene = Scene(meshes, materials, grids, notes, media=None if tree is None else tree.media)
    check_triangles(project, scenario, scene.n_triangles)
    return BuiltScene(scenario, scene, ab, notes, scene.n_triangles, geometry_seconds, info, tree)


def _site_parts(project: Project, *, frame: FacadeFrame,   # type: ignore[no-untyped-def]
                dense_grid: bool | None):
    """Meshes, materials, sensor grids and notes of the street canyon, with the office block
    or the Honeybee model's rooms when the project has them."""
    materials: dict = dict(street_materials(project.street))
    meshes = street_meshes(project.street, frame)
    use_dense = project.sensors.dense_grid if dense_grid is None else dense_grid
    grids = street_grids(project.sensors, frame, use_dense)
    notes = [f"street canyon {project.street.width_m:g} m wide, façade looks "
             f"{project.street.facade_azimuth_deg:g}° (compass), façade ρ "
             f"{project.street.facade_reflectance:g}"]
    if project.office is not None:
        from radtree.site.office import office_parts

        o_meshes, o_materials, o_grids, o_notes = office_parts(project, frame)
        meshes = [m for m in meshes if m.name != "facade"] + o_meshes
        materials.update(o_materials)
        grids = o_grids
        notes += o_notes
    if project.honeybee is not None:
        from radtree.site.honeybee_model import honeybee_parts

        if project.office is not None:
            raise RadtreeError("[office] and [site] honeybee both build the rooms: keep one")
        hbp = honeybee_parts(project.honeybee, project.street.length_m / 2.0)
        meshes = hbp.meshes   # the model and its ground plane replace the street canyon
        materials.update(hbp.materials)
        same = sorted(set(hbp.grids) & set(grids))
        if same:
            raise RadtreeError(f"Honeybee sensor grid names {same} are radtree's own grids: "
                               "rename them in the model")
        grids.update(hbp.grids)
        notes = list(hbp.notes)
    return meshes, materials, grids, notes


def _crown(project: Project, *, scenario: Scenario, frame: FacadeFrame):   # type: ignore[no-untyped-def]
    """The scenario's crown model (its switches applied): a BSDF crown, else the built one."""
    from radtree.trees.build import apply_switches, build_tree

    crown, _ = apply_switches(project.tree, dict(scenario.switches),
                              source=str(project.source))
    tree = None
    if crown.representation == "bsdf":   # imported only then: it pulls in trimesh (~1 s)
        from radtree.pipeline.crown_bsdf import bsdf_crown

        tree = bsdf_crown(project, scenario, frame)
    return tree or build_tree(project, scenario, frame)
