"""The scene of a project with a tree inventory and/or building footprints (``[site] trees``,
``[site] buildings``; :mod:`radtree.config.district`).

With buildings: extruded footprints, one ground rectangle (the street's reflectance, per hour
as in the canyon) and sensor grids on the selected façades (``facades_000`` …, every sensor
labelled building / facade / storey). Without buildings: the street canyon and its façade
circle (and dense map), as in the hand-written project. Crowns: one per inventory tree
(:func:`radtree.trees.district.inventory_crowns`), louvers model (free form), or none.
"""

from __future__ import annotations

import time

from radtree.config import Project, Scenario, effective_project
from radtree.errors import ConfigError, RadtreeError
from radtree.optics import Material
from radtree.scene import Scene
from radtree.sensor_grid import street_grids
from radtree.site.buildings import building_meshes, facade_grids, ground_mesh
from radtree.site.district import load_district
from radtree.site.frame import FacadeFrame
from radtree.site.street import street_materials, street_meshes

INVENTORY_MODELS = ("louvers", "none")


def district_scene(project: Project, scenario: Scenario, dense_grid: bool | None,
                   scene_ab, built_scene_cls):   # type: ignore[no-untyped-def]
    """The BuiltScene of ``scenario`` for an inventory project (see the module doc).

    Plan (inputs, species and crown–wall checks, the site: buildings or street canyon) →
    execute (the crowns) → publish (the scene, its ``-ab``, the BuiltScene)."""
    project = effective_project(project, scenario)
    inputs = load_district(project)
    notes, clips = _inventory_checks(project, inputs=inputs)
    if inputs.buildings:
        meshes, materials, grids = _buildings_site(project, inputs=inputs, notes=notes)
    else:
        meshes, materials, grids = _street_site(project, inputs=inputs, dense_grid=dense_grid,
                                                notes=notes)
    t0 = time.perf_counter()
    tree = _inventory_crowns(project, scenario=scenario, inputs=inputs, clips=clips, notes=notes)
    if tree is not None:
        clash = set(tree.materials) & set(materials)
        if clash:
            raise RadtreeError(f"crown materials clash with the buildings': {clash}")
        materials.update(tree.materials)
        meshes = meshes + list(tree.meshes)
        notes += tree.notes
    seconds = time.perf_counter() - t0
    return _publish(project, scenario=scenario, meshes=meshes, materials=materials, grids=grids,
                    notes=notes, tree=tree, seconds=seconds, scene_ab=scene_ab,
                    built_scene_cls=built_scene_cls)


def _inventory_checks(project: Project, *, inputs) -> tuple[list[str], dict]:   # type: ignore[no-untyped-def]
    """The notes so far and the crown–wall clips; species are checked for every scenario
    (also 'none'): nothing is built with a bad one."""
    notes: list[str] = []
    clips: dict = {}
    if inputs.trees:
        from radtree.trees.district import species_of, wall_clips

        d = project.district
        species_of(inputs.trees, str(d.trees))
        # the crown–wall policy for every scenario (also 'none'): a refusal stops them all
        clips, wall_notes = wall_clips(project, inputs.trees, inputs.walls, str(d.trees))
        notes += wall_notes
    return notes, clips


def _buildings_site(project: Project, *, inputs, notes: list[str]):   # type: ignore[no-untyped-def]
    """Extruded footprints, one ground rectangle and the façade grids (appends a note)."""
    d = project.district
    materials: dict[str, Material]
    meshes, walls = building_meshes(inputs.buildings)
    materials = {**walls, "ground": street_materials(project.street)["ground"]}
    meshes.append(ground_mesh(inputs.buildings, inputs.trees))
    grids = facade_grids(inputs.facades, d.facade_spacing_m, d.window_height_m,
                         project.sensors.offset_m, d.facade_chunk)
    notes.append(f"District: {len(inputs.buildings)} buildings, {len(inputs.facades)} "
                 f"façades with sensors ({sum(len(g) for g in grids.values())} sensors "
                 f"every {d.facade_spacing_m:g} m, {d.window_height_m:g} m above each "
                 f"storey floor), {len(inputs.trees)} trees.")
    return meshes, materials, grids


def _street_site(project: Project, *, inputs, dense_grid: bool | None,   # type: ignore[no-untyped-def]
                 notes: list[str]):
    """The street canyon and its façade circle (and dense map) (appends notes)."""
    frame = inputs.street_frame or FacadeFrame(azimuth_deg=project.street.facade_azimuth_deg)
    if inputs.placement:
        notes.append(inputs.placement)
    materials: dict[str, Material] = dict(street_materials(project.street))
    meshes = street_meshes(project.street, frame)
    grids = street_grids(project.sensors, frame, project.sensors.dense_grid
                         if dense_grid is None else dense_grid)
    notes.append(f"street canyon {project.street.width_m:g} m wide with "
                 f"{len(inputs.trees)} inventory tree(s)")
    return meshes, materials, grids


def _inventory_crowns(project: Project, *, scenario: Scenario, inputs,   # type: ignore[no-untyped-def]
                      clips: dict, notes: list[str]):
    """One crown per inventory tree (louvers slats or turbid media), or None (model 'none' or
    no trees); refuses any other model. Appends the turbid_above note."""
    d = project.district
    if scenario.model not in INVENTORY_MODELS:
        raise ConfigError(f"got {scenario.model!r}: inventory crowns are built with the louvers "
                          f"model (or none)", source=str(project.source),
                          field=f"scenario {scenario.name}.model")
    if scenario.model == "none" or not inputs.trees:
        return None
    from radtree.trees.build import apply_switches
    from radtree.trees.district import inventory_crowns

    tr, _ = apply_switches(project.tree, scenario.switches, source=str(project.source),
                           root=project.root)
    if tr.representation == "explicit" and 0 < d.turbid_above < len(inputs.trees):
        from dataclasses import replace

        tr = replace(tr, representation="turbid")   # [site] turbid_above (config.district)
        notes.append(f"{len(inputs.trees)} trees > [site] turbid_above = {d.turbid_above}: "
                     "the crowns are turbid media (set turbid_above = 0 for slats).")
    if tr.representation == "turbid":   # one turbid crown per tree, no slats
        from radtree.trees.district import tree_outline
        from radtree.trees.turbid import inventory_turbid

        shaped = [t.id for t in inputs.trees if tree_outline(t)[0] is not None]
        if shaped:
            notes.append(f"{len(shaped)} tree(s) have a crown_outline that is not round: "
                         "turbid crowns stay spheroids of their crown_diameter_m (slat crowns "
                         "follow outlines; the turbid tracer knows spheroids only).")

        return inventory_turbid(project, inputs.trees, tr)
    return inventory_crowns(project, inputs.trees, tr, instancing=d.instancing, clips=clips)


def _publish(project: Project, *, scenario: Scenario, meshes, materials, grids,   # type: ignore[no-untyped-def]
             notes: list[str], tree, seconds: float, scene_ab, built_scene_cls):
    """The Scene (``notes`` shared with it: the instancing note lands in both), its ``-ab``
    and the BuiltScene."""
    prototypes: dict = {} if tree is None else tree.prototypes
    instances: list = [] if tree is None else tree.instances
    scene = Scene(meshes, materials, grids, notes, prototypes=prototypes, instances=instances,
                  media=None if tree is None else tree.media)
    if instances:
        notes.append(f"Instancing: {len(instances)} crowns placed from {len(prototypes)} "
                     f"prototype(s), {scene.n_triangles} triangles stored; engines without "
                     f"instancing expand them to {scene.instanced_triangles()} crown triangles.")
    ab = scene_ab(project, None if tree is None else tree.recommended_ab)
    return built_scene_cls(scenario, scene, ab, notes, scene.n_triangles, seconds,
                           dict(tree.info) if tree else {}, tree)


def facades_path(project: Project):   # type: ignore[no-untyped-def]
    """``PROJECT/results/facades.geojson``."""
    return project.results_dir / "facades.geojson"


def facade_features(project: Project, table) -> dict:   # type: ignore[no-untyped-def]
    """A GeoJSON FeatureCollection: one LineString per simulated façade (its footprint edge,
    coordinates in the input CRS), properties: building, facade, azimuth_deg (the way it
    looks, clockwise from north), length_m, storeys, sensors, and per scenario the façade-mean
    illuminance of each hour ``lux_<scenario>_<HH:MM>`` and over the hours ``lux_<scenario>``
    (lx, mean over the façade's sensors and storeys)."""
    import numpy as np

    inputs = load_district(project)
    rows = table[table["facade"].notna()] if "facade" in table.columns else table.iloc[0:0]
    means = rows.groupby(["facade", "scenario", "time"])["lux"].mean()
    counts = rows[rows["scenario"] == rows["scenario"].iloc[0]].groupby("facade")["sensor"] \
        .count() / max(1, rows["time"].nunique()) if len(rows) else {}
    frame = inputs.frame
    feats = []
    for f in inputs.facades:
        xs = np.array([f.start[0], f.end[0]])
        ys = np.array([f.start[1], f.end[1]])
        if frame is not None:
            xs, ys = frame.to_source(xs, ys)
        props: dict = {"building": f.building, "facade": f.id,
                       "azimuth_deg": round(f.azimuth_deg, 2) % 360.0, "length_m": round(f.length_m, 3),
                       "storeys": f.storeys, "sensors": int(counts.get(f.id, 0)) if len(rows) else 0}
        if f.id in means.index.get_level_values(0):
            sub = means.loc[f.id]
            for (scen, hour), lux in sub.items():
                props[f"lux_{scen}_{hour}"] = round(float(lux), 1)
            for scen, g in sub.groupby(level=0):
                props[f"lux_{scen}"] = round(float(g.mean()), 1)
        feats.append({"type": "Feature", "id": f.id, "properties": props,
                      "geometry": {"type": "LineString",
                                   "coordinates": [[float(x), float(y)] for x, y in zip(xs, ys)]}})
    out: dict = {"type": "FeatureCollection", "features": feats}
    if frame is not None and frame.crs not in ("EPSG:4326", "local"):
        out["crs"] = {"type": "name", "properties": {"name": frame.crs}}
    return out


def write_facades_geojson(project: Project, table) -> object:   # type: ignore[no-untyped-def]
    """Write ``results/facades.geojson`` (atomically); returns its path."""
    import json

    from radtree.fileio import write_text

    path = facades_path(project)
    write_text(path, json.dumps(facade_features(project, table), indent=1))
    return path
