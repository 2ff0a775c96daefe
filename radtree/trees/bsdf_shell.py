"""The BSDF representation of a crown (``[tree] representation = "bsdf"``): the sensor dome or
the free crowns' envelopes as a shell of the Radiance ``aBSDF`` material (``tree.bsdf.material``;
or ``BSDF``), no slats. ``aBSDF`` extracts the XML's straight-through peak, so the sun (a
shadow ray) passes the shell deterministically instead of being found by ambient sampling.

The shell's normals point inwards (to the sensors, inside the crown): the XML's back side,
genBSDF's +z. Its up vector is world +z, so the XML's +y (the planar sample's "up", towards
higher elevation on the dome) follows the shell's upward tangent, as the dome's slats are tilted
about the horizontal tangent. The dome's slats turn with elevation, so its shell is cut into
elevation bands, each carrying the BSDF of the slats as tilted at its middle; below the
horizon the slats are mirrored (tilted towards lower elevations), so the lower half carries
the same XMLs with up −z. The XML is computed by :mod:`radtree.pipeline.crown_bsdf` (or
given as ``tree.bsdf.xml``); this module only builds the geometry.

Free crowns: the envelope is closed, so light reaching the façade through a crown crosses the
shell twice (in and out); the XML holds one crossing (the half chord of the crown at each
incidence, :func:`radtree.trees.slab.chord_samples`). The crown's slats keep their
inclination from the vertical, so the envelope is cut into bands by the elevation of its
facets' outward normals, each with the slats as a facet of that orientation sees them.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from radtree.config import Sensors, Street, Tree
from radtree.optics import Bsdf, Plastic
from radtree.scene import Mesh
from radtree.site.frame import FacadeFrame
from radtree.trees.envelope import crown_row_spec, dome_notes, dome_spec, icosphere_level, row_notes
from radtree.trees.model import BARK_REFLECTANCE, TRUNK, TreeModel

BSDF_SHELL = "crown_bsdf"
#: the material (and mesh) of a free crown's wall cap
WALL_CAP = f"{BSDF_SHELL}_wall"
#: the wall cap is re-meshed into cells of this size (m) in the wall plane, so that the
#: three-phase method can cut it into tiles (the convex hull leaves it a fan of slivers)
CAP_CELL_M = 0.5
#: (lowest, highest) of a band entry that is a free crown's wall cap, not an elevation band
WALL_BAND = (-1.0, -1.0)


def inward(verts: np.ndarray, faces: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """``faces`` re-wound so every triangle's normal points towards ``centre``."""
    t = verts[faces]
    n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    out = np.einsum("ij,ij->i", n, t.mean(axis=1) - centre) > 0
    faces = faces.copy()
    faces[out] = faces[out][:, ::-1]
    return faces


def elevation_bands(el: np.ndarray, faces: np.ndarray, bands: list[tuple[float, float, Path]]
                    ) -> list[tuple[str, Bsdf, np.ndarray]]:
    """(material name, material, faces) per elevation band and half: a triangle belongs to
    the band of its |elevation| ``el`` (degrees, one per face); the upper half carries the
    XML with up +z, the lower half the same XML with up −z (mirrored: the dome's slats are
    tilted towards lower elevations there; a free crown's lower facets see the vertical as
    the upper ones do, up to sign)."""
    out = []
    for k, (lo, hi, xml) in enumerate(bands):
        last = k == len(bands) - 1
        inside = (np.abs(el) >= lo) & ((np.abs(el) <= hi) if last else (np.abs(el) < hi))
        for half, up, sel in (("", (0.0, 0.0, 1.0), el >= 0), ("_low", (0.0, 0.0, -1.0),
                                                               el < 0)):
            pick = inside & sel
            if np.any(pick):
                name = f"{BSDF_SHELL}{'' if len(bands) == 1 else f'_b{k}'}{half}"
                out.append((name, Bsdf(name, str(Path(xml).resolve()), up), faces[pick]))
    return out


def _clip(poly: list[np.ndarray], axis: int, value: float, keep_above: bool
          ) -> list[np.ndarray]:
    """Sutherland–Hodgman: the part of the polygon on one side of ``p[axis] = value``."""
    out = []
    for a, b in zip(poly, poly[1:] + poly[:1]):
        ina, inb = (a[axis] >= value) == keep_above, (b[axis] >= value) == keep_above
        if ina:
            out.append(a)
        if ina != inb:
            out.append(a + (value - a[axis]) / (b[axis] - a[axis]) * (b - a))
    return out


def cap_cells(triangles: np.ndarray, cell: float) -> np.ndarray:
    """Triangles in the wall plane (façade frame, n constant) cut along the grid lines
    u, z = k · ``cell``: the same surface, no triangle across a cell boundary (fans of the
    clipped polygons, winding kept)."""
    out = []
    for tri in triangles:
        lo, hi = tri.min(axis=0), tri.max(axis=0)
        for i in range(int(np.floor(lo[0] / cell)), int(np.ceil(hi[0] / cell))):
            for j in range(int(np.floor(lo[2] / cell)), int(np.ceil(hi[2] / cell))):
                poly = list(tri)
                for axis, value, above in ((0, i * cell, True), (0, (i + 1) * cell, False),
                                           (2, j * cell, True), (2, (j + 1) * cell, False)):
                    poly = _clip(poly, axis, value, above) if len(poly) >= 3 else []
                out += [[poly[0], poly[k], poly[k + 1]] for k in range(1, len(poly) - 1)]
    tris = np.array(out, float).reshape(-1, 3, 3)
    area = np.linalg.norm(np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]), axis=1)
    return tris[area > 1e-10]


def facade_angle(d: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """Horizontal angle (degrees, −90 … 90 in front of the wall) of the directions ``d`` (world
    axes) from the façade's outward ``normal``, positive towards z × normal."""
    n = np.asarray(normal, float) / np.linalg.norm(normal)
    u = np.cross([0.0, 0.0, 1.0], n)
    return np.degrees(np.arctan2(d @ u, d @ n))


def sector_bounds(sectors: int) -> list[tuple[float, float]]:
    """(lowest, highest) :func:`facade_angle` of each of ``sectors`` equal sectors, degrees."""
    step = 180.0 / sectors
    return [(-90.0 + k * step, -90.0 + (k + 1) * step) for k in range(sectors)]


def dome_bands(verts: np.ndarray, faces: np.ndarray, centre: np.ndarray,
               bands: list[tuple[float, float, Path]], normal: np.ndarray | None = None,
               sectors: int = 1) -> list[tuple[str, Bsdf, np.ndarray]]:
    """:func:`elevation_bands` by the elevation of each triangle's centroid seen from
    ``centre``; ``sectors`` > 1: ``bands`` holds one entry per elevation band and sector
    (band-major), a triangle's sector that of its centroid's :func:`facade_angle` from the
    façade ``normal``."""
    c = verts[faces].mean(axis=1) - centre
    el = np.degrees(np.arctan2(c[:, 2], np.hypot(c[:, 0], c[:, 1])))
    if sectors == 1:
        return elevation_bands(el, faces, bands)
    if normal is None or len(bands) % sectors:
        raise ValueError(f"dome_bands: {sectors} sectors need the façade normal and one XML "
                         f"per band and sector, got {len(bands)}")
    psi = facade_angle(c, normal)
    out = []
    for k, (lo, hi) in enumerate(sector_bounds(sectors)):
        sel = (psi >= lo) & ((psi <= hi) if k == sectors - 1 else (psi < hi))
        for name, mat, fs in elevation_bands(el[sel], faces[sel], bands[k::sectors]):
            out.append((f"{name}_s{k}", Bsdf(f"{name}_s{k}", mat.xml, mat.up), fs))
    return out


def normal_bands(verts: np.ndarray, faces: np.ndarray, bands: list[tuple[float, float, Path]]
                 ) -> list[tuple[str, Bsdf, np.ndarray]]:
    """:func:`elevation_bands` by the elevation of each (inward-wound) triangle's outward
    normal."""
    t = verts[faces]
    n = -np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    return elevation_bands(np.degrees(np.arctan2(n[:, 2], np.hypot(n[:, 0], n[:, 1]))),
                           faces, bands)


@dataclass(frozen=True)
class _Shell:
    """The form's meshes and materials (BSDF bands, wall cap, trunks), notes and info."""

    meshes: list[Mesh] = field(default_factory=list)
    materials: dict = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)
    info: dict[str, float] = field(default_factory=dict)

    def add(self, name: str, *, material: object, mesh: Mesh) -> None:
        """One material and its mesh."""
        self.materials[name] = material
        self.meshes.append(mesh)


def build_bsdf_crown(tree: Tree, sensors: Sensors, street: Street, frame: FacadeFrame,
                     form: str, bands: list[tuple[float, float, Path]], recommended_ab: int,
                     source: str | None = None) -> TreeModel:
    """The crown of ``form`` as a BSDF shell; ``bands``: (lowest, highest |elevation| in
    degrees, XML) — the elevation bands (the dome's seen from its centre, a free crown's by
    its facets' normals); an entry (:data:`WALL_BAND`, XML) gives free crowns' wall caps
    (the envelope's faces on the wall-side clip plane) their own XML."""
    wall = [b[2] for b in bands if (b[0], b[1]) == WALL_BAND]
    bands = [b for b in bands if (b[0], b[1]) != WALL_BAND]
    if form == "dome":
        shell = _dome_shell(tree, sensors=sensors, street=street, frame=frame, bands=bands,
                            source=source)
    else:
        shell = _free_shell(tree, sensors=sensors, street=street, frame=frame, bands=bands,
                            wall=wall, source=source)
    if tree.bsdf.material == "aBSDF":
        for name, mat in list(shell.materials.items()):
            if isinstance(mat, Bsdf):
                shell.materials[name] = replace(mat, peak=True)
    notes, info = shell.notes, shell.info
    notes.append(f"Representation: BSDF — the crown is a shell of the Radiance "
                 f"{tree.bsdf.material} material "
                 f"({', '.join(Path(b[2]).name for b in bands)}, Klems 145 × 145), the planar "
                 "periodic sample of its slat layer; no slats are traced. A BSDF moves light only in direction, not "
                 "sideways: light entering a thick layer at one place leaves it at the same place.")
    info["area_m2"] = float(sum(m.area() for m in shell.meshes
                                if m.material.startswith(BSDF_SHELL)))
    return TreeModel(meshes=shell.meshes, materials=shell.materials, notes=notes,
                     recommended_ab=recommended_ab, info=info, form=form, model="louvers")


def _dome_shell(tree: Tree, *, sensors: Sensors, street: Street, frame: FacadeFrame,
                bands: list[tuple[float, float, Path]], source: str | None) -> _Shell:
    """The sensor dome's hemisphere cut into elevation bands (and façade sectors)."""
    spec = dome_spec(tree, sensors, street, source)
    verts, faces = spec.shell(max(3, (tree.bsdf.segments or spec.segments) // 4))
    verts = frame.to_world(verts)
    centre = frame.to_world(spec.centre[None, :])[0]
    shell = _Shell(info={"dome_radius_m": spec.radius, "bsdf_bands": float(len(bands))})
    for name, mat, fs in dome_bands(verts, inward(verts, faces, centre), centre, bands,
                                    frame.normal, tree.bsdf.sectors):
        shell.add(name, material=mat, mesh=Mesh(name, name, verts, fs))
    shell.notes.extend(dome_notes(spec))
    return shell


def _free_shell(tree: Tree, *, sensors: Sensors, street: Street, frame: FacadeFrame,
                bands: list[tuple[float, float, Path]], wall: list[Path],
                source: str | None) -> _Shell:
    """The free crowns' envelopes in bands by their facets' normals, the wall caps (when
    ``wall`` gives their XML) and the trunks."""
    spec_r = crown_row_spec(tree, sensors, street, source)
    level = icosphere_level(360.0 / tree.crown.segments)
    verts_all, faces_all, caps, base = [], [], [], 0
    for i in range(spec_r.count):
        v, f, on_wall = spec_r.envelope(i, level)
        inner = frame.to_world(spec_r.hull_point(i)[None, :])[0]
        if wall and np.any(on_wall):     # the cap in cells, wound inwards
            t = frame.to_world(cap_cells(v[f[on_wall]], CAP_CELL_M).reshape(-1, 3))
            caps.append((t, inward(t, np.arange(len(t)).reshape(-1, 3), inner)))
            f = f[~on_wall]
        v = frame.to_world(v)
        verts_all.append(v)
        faces_all.append(inward(v, f, inner) + base)
        base += len(v)
    verts, faces = np.concatenate(verts_all), np.concatenate(faces_all)
    shell = _Shell(info={"clip_plane_n_m": spec_r.n_clip})
    for name, mat, fs in normal_bands(verts, faces, bands):
        shell.add(name, material=mat, mesh=Mesh(name, name, verts, fs))
    if caps:
        cv = np.concatenate([c[0] for c in caps])
        offsets = np.cumsum([0] + [len(c[0]) for c in caps[:-1]])
        cf = np.concatenate([c[1] + o for c, o in zip(caps, offsets)])
        shell.add(WALL_CAP, material=Bsdf(WALL_CAP, str(Path(wall[0]).resolve())),
                  mesh=Mesh(WALL_CAP, WALL_CAP, cv, cf))
    tv, tf = spec_r.trunks()
    shell.add(TRUNK, material=Plastic(TRUNK, BARK_REFLECTANCE),
              mesh=Mesh("tree_trunks", TRUNK, frame.to_world(tv), tf))
    shell.notes.extend(row_notes(spec_r, tree, sensors))
    return shell
