"""The BSDF shell's facets grouped for the three-phase method (:mod:`radtree.annual.threephase`):
one Klems hemisphere per group of one material and orientation (and, for the wall cap, one
tile of a world grid). A group's Klems frame is its facets' mean normal and either rfluxmtx's
default up or its ``BSDF`` material's up vector (the frame rtrace applies the XML in).

:data:`FACETS` groups only facets of one plane orientation (normals within
:data:`PLANE_TOLERANCE`): every group's Klems frame is then each of its facets' own, the frame
rtrace applies the XML in — on a curved crown the coarser levels apply the XML at the group's
mean normal instead of each facet's (measured, issue 40: radtree verify's small crown,
uniform sky, chain / rcontrib 0.936 at level 0, 0.929 at level 2, 1.09 at level 3, 1.02
with one frame per facet)."""

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
#: the grouping level of one group per facet plane orientation (and wall-cap tile)
FACETS = -1
#: facets whose unit normals differ by less than this (≈ 0.06°) share a plane orientation
PLANE_TOLERANCE = 1e-3


def group_directions(level: int) -> np.ndarray:
    """Unit directions facets are grouped by: level 0 the 14 of :data:`_DIRS`; level k ≥ 1
    the vertices of an icosphere of k − 1 subdivisions (12, 42, 162, 642 directions: a
    facet's normal within ≈ 37°, 19°, 10°, 5° of its group's direction). :data:`FACETS` has
    no fixed directions (:func:`facet_groups`)."""
    if level <= 0:
        return _DIRS
    import trimesh

    v = np.asarray(trimesh.creation.icosphere(subdivisions=level - 1).vertices, float)
    return v / np.linalg.norm(v, axis=1)[:, None]


@dataclass
class FacetGroup:
    """Shell facets of one material and orientation; ``triangles`` wound to the sensors;
    ``up`` the world up vector of the group's Klems frame (None: rfluxmtx's default);
    ``coarse`` the index of the nearest of the 14 level-0 directions (groups merged for the
    daylight matrices share it) and ``weight`` the group's share (0–1) of the area of its
    level-0 group (material, coarse direction, tile): the daylight matrix of a group takes
    that share of the rays per Klems patch (:class:`radtree.annual.threephase.ThreePhase`)."""

    material: str
    triangles: np.ndarray  # (k, 3, 3)
    normal: np.ndarray     # unit mean normal, towards the sensors
    direction: int = -1    # index of the nearest grouping direction
    up: tuple[float, float, float] | None = None
    coarse: int = -1
    weight: float = 1.0
    part: int = -1

    @property
    def area(self) -> float:
        t = self.triangles
        return float(0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]),
                                          axis=1).sum())

    @property
    def key(self) -> str:
        return f"{self.material}_{len(self.triangles)}"


def shell_parts(faces: np.ndarray) -> np.ndarray:
    """(k,) label of the connected piece of a mesh each of its ``faces`` (k, 3) vertex indices
    belongs to (faces sharing a vertex index are connected). A free crown row's envelopes
    are glued where neighbours meet but keep their own vertices
    (:func:`radtree.trees.bsdf_shell.build_bsdf_crown`), so each crown's part of a band is
    its own piece."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    k = len(faces)
    if k == 0:
        return np.zeros(0, np.int64)
    _, vid = np.unique(np.asarray(faces, np.int64).ravel(), return_inverse=True)
    n_v = int(vid.max()) + 1
    graph = coo_matrix((np.ones(3 * k), (np.repeat(np.arange(k), 3), k + vid.ravel())),
                       shape=(k + n_v, k + n_v))
    return connected_components(graph, directed=False)[1][:k].astype(np.int64)


def facet_groups(model: TreeModel, sensors_inside: bool, tile_m: float = 0.0,
                 tiled: tuple[str, ...] | None = None, level: int = 0,
                 material_up: bool = False) -> list[FacetGroup]:
    """The shell's facets grouped by BSDF material, by the nearest of the grouping directions
    (:func:`group_directions`; :data:`FACETS`: by plane orientation) and (``tile_m`` > 0, for
    the materials in ``tiled`` or all when None) by the cell of a world grid of ``tile_m``
    holding their centroid; each triangle wound so that its normal points to the sensors (the
    shell's own normals point inwards: to the sensors inside a dome, away from them for free
    crowns)."""
    groups = []
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
        tri, n, area = tri[keep], n[keep] / area[keep][:, None], 0.5 * area[keep]
        faces = mesh.faces[keep]
        coarse = np.argmax(n @ _DIRS.T, axis=1)
        if level == FACETS:
            _, direction = np.unique(np.round(n / PLANE_TOLERANCE).astype(np.int64), axis=0,
                                     return_inverse=True)
            direction = direction.ravel()
        else:
            direction = np.argmax(n @ group_directions(level).T, axis=1)
        cell = np.zeros((len(tri), 3), np.int64)
        part = np.zeros(len(tri), np.int64)
        if tile_m > 0 and (tiled is None or mesh.material in tiled):
            cell = np.floor(tri.mean(axis=1) / tile_m).astype(np.int64)
        else:     # untiled: never one group across the crowns of a row (CROWN_PARTS)
            part = shell_parts(faces)
        _, which = np.unique(np.column_stack([direction, cell, part]), axis=0,
                             return_inverse=True)
        _, parent = np.unique(np.column_stack([coarse, cell, part]), axis=0,
                              return_inverse=True)
        which, parent = which.ravel(), parent.ravel()
        parent_area = np.bincount(parent, weights=area)
        for d in np.unique(which):
            pick = which == d
            mean = (n[pick] * area[pick][:, None]).sum(axis=0)
            weight = float(area[pick].sum() / parent_area[parent[pick][0]])
            groups.append(FacetGroup(mesh.material, tri[pick], mean / np.linalg.norm(mean),
                                     int(direction[pick][0]), up, int(coarse[pick][0]),
                                     min(1.0, weight), int(part[pick][0])))
    return groups
