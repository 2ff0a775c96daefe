"""Straight-ray direct transmission through crown meshes (trimesh; Embree when installed).

A ray's direct transmission is the product over all surfaces it crosses of each surface's
*specular* transmittance (``Trans``: T_s; ``Glass``: its normal transmittance; ``Plastic``: 0;
``Hole``: 1, i.e. holes pass). Diffuse transmission and reflection are not followed: this is the
undeviated beam only.
"""

from __future__ import annotations

import numpy as np
import trimesh

from radtree.optics import Glass, Hole, Material, Plastic, Trans
from radtree.scene import Mesh


def specular_transmittance(material: Material) -> float:
    if isinstance(material, Hole):
        return 1.0
    if isinstance(material, Trans):
        return material.specular_transmittance
    if isinstance(material, Glass):
        return material.transmittance
    if isinstance(material, Plastic):
        return 0.0
    raise TypeError(f"unknown material {material!r}")


class DirectTracer:
    """Casts straight rays through a fixed set of meshes and multiplies specular transmittances.

    Rays are cast in chunks (bounded memory); each chunk asks for every hit along each ray.
    """

    def __init__(self, meshes: list[Mesh], materials: dict[str, Material], chunk: int = 200_000):
        self.chunk = chunk
        solid = [m for m in meshes if m.n_triangles and not isinstance(materials[m.material], Hole)]
        if solid:
            verts, faces, ts, off = [], [], [], 0
            for m in solid:
                verts.append(m.vertices)
                faces.append(m.faces + off)
                ts.append(np.full(m.n_triangles, specular_transmittance(materials[m.material])))
                off += len(m.vertices)
            self.mesh: trimesh.Trimesh | None = trimesh.Trimesh(np.vstack(verts), np.vstack(faces),
                                                                process=False)
            self.face_t = np.concatenate(ts)
        else:
            self.mesh = None
            self.face_t = np.zeros(0)

    def hits(self, origins: np.ndarray, directions: np.ndarray
             ) -> tuple[np.ndarray, np.ndarray]:
        """(face index, ray index) of every crossing."""
        if self.mesh is None:
            return np.zeros(0, np.int64), np.zeros(0, np.int64)
        tri, ray = [], []
        for i in range(0, len(origins), self.chunk):
            t, r = self.mesh.ray.intersects_id(origins[i:i + self.chunk],
                                               directions[i:i + self.chunk],
                                               multiple_hits=True, max_hits=200)[:2]
            tri.append(np.asarray(t, np.int64))
            ray.append(np.asarray(r, np.int64) + i)
        return np.concatenate(tri), np.concatenate(ray)

    def transmission(self, origins: np.ndarray, directions: np.ndarray) -> np.ndarray:
        """Direct transmission of each ray (1 where nothing is hit)."""
        origins = np.asarray(origins, float).reshape(-1, 3)
        directions = np.asarray(directions, float).reshape(-1, 3)
        if len(origins) == 1 and len(directions) > 1:
            origins = np.repeat(origins, len(directions), axis=0)
        tri, ray = self.hits(origins, directions)
        t = self.face_t[tri]
        blocked = np.bincount(ray[t <= 0.0], minlength=len(origins)) > 0
        logs = np.bincount(ray[t > 0.0], weights=np.log(t[t > 0.0]), minlength=len(origins))
        out = np.exp(logs)
        out[blocked] = 0.0
        return out

    def crossings(self, origins: np.ndarray, directions: np.ndarray) -> np.ndarray:
        origins = np.asarray(origins, float).reshape(-1, 3)
        directions = np.asarray(directions, float).reshape(-1, 3)
        if len(origins) == 1 and len(directions) > 1:
            origins = np.repeat(origins, len(directions), axis=0)
        _, ray = self.hits(origins, directions)
        return np.bincount(ray, minlength=len(origins))
