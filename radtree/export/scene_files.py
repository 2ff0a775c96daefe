"""The whole scene of a scenario as glTF (binary ``.glb``) or OBJ for any 3-D viewer (trimesh).

One node per scene mesh (street, rooms, glazing, crowns, trunks; holes left out), named as the
mesh, coloured by its material: grey of its reflectance, glass light blue and half transparent,
translucent leaves green. Coordinates are radtree's (metres, x east, y north, z up); glTF is
y-up by convention, so the glTF scene gets a root rotation of −90° about x (z up → y up).
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import trimesh

from radtree.fileio import atomic_path
from radtree.optics import Bsdf, Glass, Material, Trans
from radtree.scene import Scene

if TYPE_CHECKING:
    from radtree.export.registry import ExportInputs

log = logging.getLogger(__name__)


def material_rgba(material: Material) -> list[int]:
    """Display colour (RGBA 0–255) of a material."""
    if isinstance(material, Glass):
        return [150, 200, 235, 110]
    if isinstance(material, Trans | Bsdf):     # a leaf, or a crown shell carrying its BSDF
        return [70, 140, 60, 230]
    g = int(round(60 + 195 * float(material.reflectance)))
    return [g, g, g, 255]


def trimesh_scene(scene: Scene) -> trimesh.Scene:
    """A trimesh Scene of every solid mesh, one coloured geometry per mesh."""
    out = trimesh.Scene()
    for m in scene.solid_meshes():
        if not m.n_triangles:
            continue
        tm = trimesh.Trimesh(m.vertices, m.faces, process=False)
        tm.visual = trimesh.visual.ColorVisuals(
            tm, face_colors=np.tile(material_rgba(scene.materials[m.material]),
                                    (m.n_triangles, 1)))
        out.add_geometry(tm, node_name=m.name, geom_name=m.name)
    return out


def write_scene(scene: Scene, out: Path, fmt: str, name: str = "scene") -> Path:
    """``out/<name>.glb`` (fmt ``gltf``) or ``out/<name>.obj`` (fmt ``obj``)."""
    ts = trimesh_scene(scene)
    if fmt == "gltf":
        path = out / f"{name}.glb"
        z_up_to_y_up = trimesh.transformations.rotation_matrix(-np.pi / 2, [1, 0, 0])
        ts.apply_transform(z_up_to_y_up)
        data = ts.export(file_type="glb")
    elif fmt == "obj":
        path = out / f"{name}.obj"
        data = trimesh.exchange.obj.export_obj(ts, include_color=True, include_normals=False,
                                               include_texture=False)
    else:
        raise ValueError(f"unknown scene format {fmt!r}")
    with atomic_path(path) as tmp:
        Path(tmp).write_bytes(data if isinstance(data, bytes) else data.encode())
    return path


def export_scene(inputs: ExportInputs, out: Path, fmt: str) -> list[Path]:
    """The scenario's scene as ``out/<scenario>_scene.glb`` or ``.obj`` (:func:`write_scene`)."""
    built = inputs.built_scene()
    path = write_scene(built.scene, out, fmt, f"{inputs.scenario.name}_scene")
    log.info("%s: %d meshes, %d triangles → %s", inputs.scenario.name,
             len(built.scene.solid_meshes()), built.triangles, path)
    return [path]


def export_gltf(inputs: ExportInputs, out: Path) -> list[Path]:
    """Format ``gltf`` (:mod:`radtree.export.registry`): ``<scenario>_scene.glb``."""
    return export_scene(inputs, out, "gltf")


def export_obj(inputs: ExportInputs, out: Path) -> list[Path]:
    """Format ``obj``: ``<scenario>_scene.obj``."""
    return export_scene(inputs, out, "obj")
