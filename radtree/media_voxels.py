"""Turbid-medium crowns on voxel grids, and scenes that mix them with spheroid crowns.

A voxel crown is a box of nx × ny × nz cubic voxels of side v (m) whose corner of voxel
(0, 0, 0) stands at ``origin`` (x east, y north, z up, metres); its axes are the horizontal
unit vector e_i (``axis_i``, world x by default), e_j = z × e_i and z, so voxel (i, j, k)
spans origin + i·v·e_i + j·v·e_j + k·v·z … one voxel further (a grid placed on a trunk of a
façade's row has its axes along and away from the façade) and holds a constant one-sided plant area density u_ijk
(m²/m³; a LiDAR inversion, :mod:`radtree.lidar.voxels`, or a file of an AMAPVox-like tool,
:mod:`radtree.trees.voxel_file`). Each crown may be cut by half-spaces like the spheroids of
:class:`radtree.media.TurbidCrowns` (the wall-side plane, the planes shared with neighbours).

The leaves follow the same law as the spheroid crowns (:mod:`radtree.media`): inside voxel i a
path meets leaves at the rate σ_i(Ω) = u_i · G(Ω)·Ω_c (one :class:`~radtree.media.LeafKind` per
crown), so a straight path crossing lengths ℓ_i of the voxels has the optical depth
τ = G·Ω_c(μ) · Σ_i u_i ℓ_i and the uncollided probability exp(−τ) — Beer–Lambert for a
piecewise-constant density (Ross 1981, *The Radiation Regime and Architecture of Plant
Stands*, ch. 2; the voxel form of LiDAR canopy transfer, e.g. Béland et al. 2019, Agric. For.
Meteorol. 276:107627). The engines trace it in :mod:`radtree.engines.common.voxels`.

Memory: the crowns of a row planted from one scan share one density array (``pads`` holds
the distinct arrays, ``pad_of`` names each crown's), so a scene costs O(distinct voxels +
crowns) whatever its leaf count.

:class:`MediaSet` holds spheroid and voxel crowns together (their media overlap freely:
superposed media, the first collision the nearest of each one's own); :data:`Media` is what a
:class:`radtree.scene.Scene` accepts as ``media``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from radtree.media import LeafKind, TurbidCrowns


@dataclass
class VoxelCrowns:
    """Voxel crowns: ``origins`` (n, 3) m of each grid's lower corner, voxel side ``size_m``
    (n,) m, ``pads`` the distinct density arrays (nx, ny, nz) m²/m³, ``pad_of`` (n,) the
    array of each crown, ``kind`` (n,) index into ``kinds``, ``planes`` (n, p, 4): each crown
    keeps the points x with n·x ≥ c for each row (n_x, n_y, n_z, c); ``axis_i`` (n, 2) the
    world (x, y) of each grid's first axis (module text)."""

    origins: np.ndarray
    size_m: np.ndarray
    pads: list[np.ndarray]
    pad_of: np.ndarray
    kind: np.ndarray
    kinds: list[LeafKind]
    planes: np.ndarray = field(default_factory=lambda: np.zeros((0, 0, 4)))
    axis_i: np.ndarray = field(default_factory=lambda: np.array([1.0, 0.0]))

    def __post_init__(self) -> None:
        """Scalars broadcast to one per crown; ValueError for a grid that is not 3-D,
        negative or non-finite densities, a non-positive voxel side, an unknown array or
        kind."""
        self.origins = np.asarray(self.origins, float).reshape(-1, 3)
        n = len(self.origins)
        self.size_m = np.broadcast_to(np.asarray(self.size_m, float), (n,)).copy()
        self.pad_of = np.broadcast_to(np.asarray(self.pad_of, np.int64), (n,)).copy()
        self.kind = np.broadcast_to(np.asarray(self.kind, np.int64), (n,)).copy()
        self.pads = [np.ascontiguousarray(p, dtype=float) for p in self.pads]
        axis = np.broadcast_to(np.asarray(self.axis_i, float), (n, 2))
        self.axis_i = axis / np.linalg.norm(axis, axis=1)[:, None]
        planes = np.asarray(self.planes, float)
        self.planes = (np.zeros((n, 0, 4)) if planes.size == 0 else planes.reshape(n, -1, 4))
        for p in self.pads:
            if p.ndim != 3 or min(p.shape) < 1:
                raise ValueError(f"voxel crowns: a density grid must be 3-D, got {p.shape}")
            if np.any(p < 0) or not np.all(np.isfinite(p)):
                raise ValueError("voxel crowns: plant area density must be finite and ≥ 0")
        if np.any(self.size_m <= 0) or not np.all(np.isfinite(self.size_m)):
            raise ValueError("voxel crowns: the voxel side must be positive")
        if n and (self.pad_of.min() < 0 or self.pad_of.max() >= len(self.pads)):
            raise ValueError("voxel crowns: a crown's density grid is not among the grids")
        if n and (self.kind.min() < 0 or self.kind.max() >= len(self.kinds)):
            raise ValueError("voxel crowns: a crown's kind is not among the leaf kinds")

    @classmethod
    def of(cls, origins: np.ndarray, *, size_m: float | np.ndarray, pads: list[np.ndarray],
           pad_of: int | np.ndarray = 0, kind: int | np.ndarray = 0,
           kinds: list[LeafKind], planes: np.ndarray | None = None,
           axis_i: np.ndarray | tuple[float, float] = (1.0, 0.0)) -> VoxelCrowns:
        """Crowns from per-crown arrays or scalars shared by all."""
        return cls(np.asarray(origins, float), np.asarray(size_m, float), list(pads),
                   np.asarray(pad_of, np.int64), np.asarray(kind, np.int64), kinds,
                   np.zeros((0, 0, 4)) if planes is None else planes,
                   np.asarray(axis_i, float))

    def __len__(self) -> int:
        return len(self.origins)

    @property
    def materials(self) -> list[str]:
        return [k.material for k in self.kinds]

    def dims(self) -> np.ndarray:
        """(n, 3) voxel counts (nx, ny, nz) of each crown."""
        shapes = np.array([p.shape for p in self.pads], np.int64).reshape(-1, 3)
        return shapes[self.pad_of]

    def basis(self) -> np.ndarray:
        """(n, 3, 3): rows e_i, e_j, z of each grid in world coordinates."""
        ei = np.column_stack([self.axis_i, np.zeros(len(self))])
        ej = np.column_stack([-self.axis_i[:, 1], self.axis_i[:, 0], np.zeros(len(self))])
        z = np.tile([0.0, 0.0, 1.0], (len(self), 1))
        return np.stack([ei, ej, z], 1)

    def to_world(self, i: int, grid_points: np.ndarray) -> np.ndarray:
        """Points (k, 3) in crown ``i``'s grid frame (m from its origin) → world."""
        return self.origins[i] + np.asarray(grid_points, float) @ self.basis()[i]

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """((n, 3) least, (n, 3) greatest world x, y, z of each grid's box), m."""
        corners = np.array([[i & 1, (i >> 1) & 1, (i >> 2) & 1] for i in range(8)], float)
        ext = self.dims() * self.size_m[:, None]
        local = corners[None] * ext[:, None, :]                     # (n, 8, 3)
        world = self.origins[:, None, :] + np.einsum("nkj,nji->nki", local, self.basis())
        return world.min(axis=1), world.max(axis=1)

    def _kept(self, i: int) -> np.ndarray:
        """Which voxels of crown ``i`` have their centre inside its half-spaces."""
        p = self.pads[self.pad_of[i]]
        idx = np.indices(p.shape).reshape(3, -1).T
        centres = self.to_world(i, (idx + 0.5) * self.size_m[i])
        keep = np.ones(len(idx), bool)
        for pl in self.planes[i]:
            keep &= centres @ pl[:3] >= pl[3]
        return keep.reshape(p.shape)

    def leaf_area(self) -> float:
        """One-sided plant area (m²) of all crowns: Σ u·v³ over the voxels whose centre the
        crown's half-spaces keep."""
        total = 0.0
        for i in range(len(self)):
            p = self.pads[self.pad_of[i]]
            kept = self._kept(i) if self.planes.shape[1] else True
            total += float(np.sum(np.where(kept, p, 0.0))) * self.size_m[i] ** 3
        return total

    def profile(self, i: int = 0) -> tuple[np.ndarray, np.ndarray]:
        """Crown ``i``'s vertical profile, uncut: (layer bottoms above the grid's lower corner,
        m; plant area of each layer, m²)."""
        p = self.pads[self.pad_of[i]]
        v = float(self.size_m[i])
        return np.arange(p.shape[2]) * v, p.sum(axis=(0, 1)) * v ** 3


@dataclass
class MediaSet:
    """Spheroid and voxel crowns in one scene (either may be None)."""

    crowns: TurbidCrowns | None = None
    voxels: VoxelCrowns | None = None

    def __len__(self) -> int:
        return sum(len(m) for m in (self.crowns, self.voxels) if m is not None)

    @property
    def materials(self) -> list[str]:
        names = [*(self.crowns.materials if self.crowns is not None else []),
                 *(self.voxels.materials if self.voxels is not None else [])]
        return list(dict.fromkeys(names))

    def leaf_area(self) -> float:
        """One-sided leaf area (m²) of all crowns."""
        return sum(m.leaf_area() for m in (self.crowns, self.voxels) if m is not None)


#: what a scene's ``media`` may hold
Media = TurbidCrowns | VoxelCrowns | MediaSet


def media_parts(media: Media | None) -> tuple[TurbidCrowns | None, VoxelCrowns | None]:
    """(spheroid crowns, voxel crowns) of ``media``, None for a part it lacks or is empty."""
    if isinstance(media, MediaSet):
        crowns, voxels = media.crowns, media.voxels
    elif isinstance(media, VoxelCrowns):
        crowns, voxels = None, media
    else:
        crowns, voxels = media, None
    return (crowns if crowns is not None and len(crowns) else None,
            voxels if voxels is not None and len(voxels) else None)
