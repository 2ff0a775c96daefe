"""The tracer of a scene's turbid media, whatever they hold (:data:`radtree.media_voxels.Media`):
spheroid crowns (:class:`~radtree.engines.common.turbid.MediumTracer`), voxel crowns
(:class:`~radtree.engines.common.voxels.VoxelTracer`) or both
(:class:`SuperposedMedia`: the two overlap freely).

Both tracers answer the engines' hooks — ``collide``, ``leaf_events``, ``transmittance``,
``material_index``, ``corners`` — with one numbering of the media: the spheroid crowns first
(0 … n_s − 1), then the grids (n_s …); each (path, medium) pair draws from its own stream.
"""

from __future__ import annotations

import hashlib

import numpy as np

from radtree.engines.common.streams import Draws
from radtree.engines.common.turbid import MediumTracer
from radtree.engines.common.voxels import VoxelTracer
from radtree.media_voxels import Media, media_parts
from radtree.optics import Material


class SuperposedMedia:
    """Spheroid and voxel crowns traced together (module text): the first collision is the
    nearer of each part's own (the voxel walk stops at the spheroid's collision), the
    transmittance the product of theirs."""

    def __init__(self, spheroids: MediumTracer, voxels: VoxelTracer):
        self.spheroids, self.voxels = spheroids, voxels
        self.n_s = spheroids.n

    def corners(self) -> np.ndarray:
        return np.vstack([self.spheroids.corners(), self.voxels.corners()])

    def material_index(self, met: np.ndarray, names: list[str]) -> np.ndarray:
        out = np.empty(len(met), np.int64)
        s = met < self.n_s
        out[s] = self.spheroids.material_index(met[s], names)
        out[~s] = self.voxels.material_index(met[~s] - self.n_s, names)
        return out

    def collide(self, o: np.ndarray, d: np.ndarray, t: np.ndarray, draws: Draws,
                parallel: bool = True) -> tuple[np.ndarray, np.ndarray]:
        met, dist = self.spheroids.collide(o, d, t, draws, parallel)
        met_v, dist_v = self.voxels.collide(o, d, dist, draws, parallel)
        return np.where(met_v >= 0, met_v, met), dist_v

    def leaf_events(self, met: np.ndarray, d: np.ndarray, draws: Draws
                    ) -> tuple[np.ndarray, np.ndarray]:
        normal, coef = np.zeros((len(met), 3)), np.zeros((4, len(met)))
        for part, rows, first in ((self.spheroids, (met < self.n_s).nonzero()[0], 0),
                                  (self.voxels, (met >= self.n_s).nonzero()[0], self.n_s)):
            if len(rows):
                normal[rows], coef[:, rows] = part.leaf_events(met[rows] - first, d[rows],
                                                               draws.rows(rows))
        return normal, coef

    def transmittance(self, o: np.ndarray, d: np.ndarray, parallel: bool = True) -> np.ndarray:
        return (self.spheroids.transmittance(o, d, parallel)
                * self.voxels.transmittance(o, d, parallel))


MediaTracer = MediumTracer | VoxelTracer | SuperposedMedia


def media_tracer(media: Media | None, *, materials: dict[str, Material],
                 backend: str = "auto", workers: int = 1) -> MediaTracer | None:
    """The tracer of ``media`` (None when it holds no crown)."""
    crowns, voxels = media_parts(media)
    s = None if crowns is None else MediumTracer(crowns, materials, backend, workers)
    v = None if voxels is None else VoxelTracer(voxels, materials=materials, backend=backend,
                                                workers=workers,
                                                first_id=0 if s is None else s.n)
    if s is not None and v is not None:
        return SuperposedMedia(s, v)
    return s if s is not None else v


def media_bounds(media: Media | None) -> np.ndarray:
    """(2k, 3) lower and upper corners of the media's envelopes (empty: (0, 3))."""
    crowns, voxels = media_parts(media)
    out = [np.zeros((0, 3))]
    if crowns is not None:
        half = np.stack([crowns.a, crowns.a, crowns.b], 1)
        out += [crowns.centres - half, crowns.centres + half]
    if voxels is not None:
        out += list(voxels.bounds())
    return np.vstack(out)


def media_digest(media: Media | None) -> bytes:
    """A digest of what the media hold (envelopes, densities, cuts) for geometry caches."""
    h = hashlib.blake2b(digest_size=16)
    crowns, voxels = media_parts(media)
    if crowns is not None:
        for a in (crowns.centres, crowns.a, crowns.b, crowns.lad, crowns.planes):
            h.update(np.ascontiguousarray(a).tobytes())
    if voxels is not None:
        for a in (voxels.origins, voxels.size_m, voxels.pad_of, voxels.planes, *voxels.pads):
            h.update(np.ascontiguousarray(a).tobytes())
    return h.digest()
