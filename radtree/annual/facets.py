"""The BSDF shell's facets grouped for the three-phase method (:mod:`radtree.annual.threephase`):
one Klems hemisphere per group of one material and orientation (and, for the wall cap, one
tile of a world grid). A group's Klems frame is its facets' mean normal and either rfluxmtx's
default up or its ``BSDF`` material's up vector (the frame rtrace applies the XML in)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from radtree.optics import Bsdf
from radtree.trees.bsdf_shell import BSDF_SHELL
from radtree.trees.model import TreeModel

#: facet orientations: the 14 directions of a cube's faces and corners (a facet's normal is
#: within 55° of its group's direction)
_DIRS = np.array([(i, j, k) for i in (-1, 0, 1) for j in (-1, 0, 1) for k in (-1, 0, 1)
                  if abs(i) + abs(j) + abs(k) in (1, 3)], float)
_DIRS /= np.linalg.norm(_DIRS, axis=1)[:, None]


def group_directions(level: int) -> np.ndarray:
    """Unit directions facets are grouped by: level 0 the 14 of :data:`_DIRS`; level k ≥ 1
    the vertices of an icosphere of k − 1 subdivisions (12, 42, 162, 642 directions: a
    facet's normal within ≈ 37°, 19°, 10°, 5° of its group's direction)."""
    if level <= 0:
        return _DIRS
    import trimesh

    v = np.asarray(trimesh.creation.icosphere(subdivisions=level - 1).vertices, float)
    return v / np.linalg.norm(v, axis=1)[:, None]


@dataclass
class FacetGroup:
    """Shell facets of one material and orientation; ``triangles`` wound to the sensors;
    ``up`` the world up vector of the group's Klems frame (None: rfluxmtx's default)."""

    material: str
    triangles: np.ndarray  # (k, 3, 3)
    normal: np.ndarray     # unit mean normal, towards the sensors
    direction: int = -1    # index of the nearest grouping direction
    up: tuple[float, float, float] | None = None

    @property
    def area(self) -> float:
        t = self.triangles
        return float(0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]),
                                          axis=1).sum())

    @property
    def key(self) -> str:
        return f"{self.material}_{len(self.triangles)}"


def facet_groups(model: TreeModel, sensors_inside: bool, tile_m: float = 0.0,
                 tiled: tuple[str, ...] | None = None, level: int = 0,
                 material_up: bool = False) -> list[FacetGroup]:
    """The shell's facets grouped by BSDF material, by the nearest of 14 directions and
    (``tile_m`` > 0, for the materials in ``tiled`` or all when None) by the cell of a world
    grid of ``tile_m`` holding their centroid; each triangle wound so that its normal points
    to the sensors (the shell's own normals point inwards: to the sensors inside a dome,
    away from them for free crowns)."""
    groups = []
    dirs = group_directions(level)
    for mesh in model.meshes:
        if not mesh.material.startswith(BSDF_SHELL):
            continue
        mat = model.materials.get(mesh.material)
        up = ((float(mat.up[0]), float(mat.up[1]), float(mat.up[2]))
              if material_up and isinstance(mat, Bsdf) else None)
        tri = mesh.triangles if sensors_inside else mesh.triangles[:, ::-1]
        n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        area = np.linalg.norm(n, axis=1)
        keep = area > 1e-12
        tri, n = tri[keep], n[keep] / area[keep][:, None]
        which = direction = np.argmax(n @ dirs.T, axis=1)
        if tile_m > 0 and (tiled is None or mesh.material in tiled):
            cell = np.floor(tri.mean(axis=1) / tile_m).astype(np.int64)
            _, which = np.unique(np.column_stack([which, cell]), axis=0, return_inverse=True)
            which = which.ravel()
        for d in np.unique(which):
            pick = which == d
            mean = (n[pick] * area[keep][pick][:, None]).sum(axis=0)
            groups.append(FacetGroup(mesh.material, tri[pick], mean / np.linalg.norm(mean),
                                     int(direction[pick][0]), up))
    return groups
