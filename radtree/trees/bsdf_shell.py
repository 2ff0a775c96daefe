"""The BSDF representation of a crown (``[tree] representation = "bsdf"``): the sensor dome or
the free crowns' envelopes as a shell of the Radiance ``BSDF`` material, no slats.

The shell's normals point inwards (to the sensors, inside the crown): the XML's back side,
genBSDF's +z. Its up vector is world +z, so the XML's +y (the planar sample's "up", towards
higher elevation on the dome) follows the shell's upward tangent, as the dome's slats are tilted
about the horizontal tangent. The XML is computed by :mod:`radtree.pipeline.crown_bsdf` (or
given as ``tree.bsdf.xml``); this module only builds the geometry.

Free crowns: the envelope is closed, so light reaching the façade through a crown crosses the
shell twice (in and out); the slab behind the XML is one crossing's depth
(``tree.bsdf.depth_m``, default the vertical semi-axis).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from radtree.config import Sensors, Street, Tree
from radtree.optics import Bsdf, Plastic
from radtree.scene import Mesh
from radtree.site.frame import FacadeFrame
from radtree.trees.envelope import crown_row_spec, dome_notes, dome_spec, icosphere_level, row_notes
from radtree.trees.model import BARK_REFLECTANCE, TRUNK, TreeModel

BSDF_SHELL = "crown_bsdf"


def inward(verts: np.ndarray, faces: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """``faces`` re-wound so every triangle's normal points towards ``centre``."""
    t = verts[faces]
    n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    out = np.einsum("ij,ij->i", n, t.mean(axis=1) - centre) > 0
    faces = faces.copy()
    faces[out] = faces[out][:, ::-1]
    return faces


def build_bsdf_crown(tree: Tree, sensors: Sensors, street: Street, frame: FacadeFrame,
                     form: str, xml: Path, recommended_ab: int, source: str | None = None
                     ) -> TreeModel:
    """The crown of ``form`` as a BSDF shell carrying ``xml`` (see the module text)."""
    materials: dict = {BSDF_SHELL: Bsdf(BSDF_SHELL, str(Path(xml).resolve()))}
    meshes: list[Mesh] = []
    notes: list[str] = []
    if form == "dome":
        spec = dome_spec(tree, sensors, street, source)
        verts, faces = spec.shell(max(3, spec.segments // 4))
        verts = frame.to_world(verts)
        centre = frame.to_world(spec.centre[None, :])[0]
        meshes.append(Mesh(BSDF_SHELL, BSDF_SHELL, verts, inward(verts, faces, centre)))
        notes.extend(dome_notes(spec))
        info = {"dome_radius_m": spec.radius}
    else:
        spec_r = crown_row_spec(tree, sensors, street, source)
        level = icosphere_level(360.0 / tree.crown.segments)
        parts = []
        for i in range(spec_r.count):
            v, f, _ = spec_r.envelope(i, level)
            v = frame.to_world(v)
            inner = frame.to_world(spec_r.hull_point(i)[None, :])[0]
            parts.append(Mesh(f"{BSDF_SHELL}_{i}", BSDF_SHELL, v, inward(v, f, inner)))
        meshes.append(Mesh.merge(BSDF_SHELL, BSDF_SHELL, parts))
        tv, tf = spec_r.trunks()
        materials[TRUNK] = Plastic(TRUNK, BARK_REFLECTANCE)
        meshes.append(Mesh("tree_trunks", TRUNK, frame.to_world(tv), tf))
        notes.extend(row_notes(spec_r, tree, sensors))
        info = {"clip_plane_n_m": spec_r.n_clip}
    notes.append(f"Representation: BSDF — the crown is a shell of the Radiance BSDF material "
                 f"({Path(xml).name}, Klems 145 × 145), the planar periodic sample of its slat "
                 "layer; no slats are traced. A BSDF moves light only in direction, not "
                 "sideways: light entering a thick layer at one place leaves it at the same place.")
    info["area_m2"] = float(sum(m.area() for m in meshes if m.material == BSDF_SHELL))
    return TreeModel(meshes=meshes, materials=materials, notes=notes,
                     recommended_ab=recommended_ab, info=info, form=form, model="louvers")
