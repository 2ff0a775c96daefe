"""A crown's plant area density kept inside its points' hull (the crowns of ``[tree] points``).

The inversion (:mod:`radtree.lidar.voxels`) gives one density per voxel of side v (≈ 1.25 m
for a 20 pulses/m² airborne scan). A voxel on the crown's rim is only partly inside the crown,
and spreading its leaves over the whole voxel blurs the envelope by up to a voxel: leaves
stand where the crown has none (light the original lets pass is cut), and the rim's
leaves are thinned (light the original's rim stops gets through). A crown 0.2 m from a façade,
whose sensors see a steep sun through its wall-side rim, is where this shows
(``benchmarks/lidar_facade.py``: rebuilt turbid crown against the original, direct sun at the
8 sensors 0.86 of the original's transmission at 10:30 — leaves outside the envelope — and
1.24 at 13:30 — the rim too thin).

So each voxel is cut into ``sub``³ cells of side w = v/``sub``, and only the cells whose centre
lies inside the convex hull of the crown's vegetation returns keep plant area (the hull by
Qhull, Barber, Dobkin & Huhdanpaa 1996, ACM Trans. Math. Softw. 22:469–483, through SciPy's
``Delaunay``): the returns are where the beams met leaves, and no leaf stands outside the
smallest convex body that holds them all (a concave crown keeps its concavities at voxel
scale: only voxels the hull crosses change). The density in a voxel's inside cells:

* vertical-beam inversion (airborne scans): the voxel's measured gap P = exp(−PAD·G·v) is the
  mean over its beams, and a beam through the hull part of the voxel crosses a path ℓ_c in it
  (its cell column's inside cells × w; 0 outside the hull's footprint), so the density u of
  the inside cells solves (1/sub²) Σ_c exp(−u·G·ℓ_c) = P — the sub-voxel heterogeneity that
  biases a voxel's Beer–Lambert estimate low (Soma et al. 2018, Remote Sens. 10:1580;
  Pimont, Soma & Dupuy 2019, Remote Sens. 11:1580, "sub-grid clumping"), taken out with
  the one thing known about it: where the crown is. u ≥ the area-conserving PAD·v³ /
  (inside cells × w³) (Jensen's inequality); where no u reaches P (the hull's footprint
  smaller than the voxel's interception: a hull short of the true rim), that area-conserving
  value is kept;
* beams along their own paths (terrestrial scans, :mod:`radtree.lidar.beams`): the voxel's
  plant area PAD·v³ spread over its inside cells (area-conserving).

A voxel with plant area but no inside cell (an occluded voxel filled from its layer, outside
the hull) keeps its density in all its cells. The grid is cropped horizontally to the cells
with plant area.
"""

from __future__ import annotations

import numpy as np

from radtree.lidar.voxels import VoxelGrid

#: hull cells per voxel side (1.25 m voxels → 0.31 m cells, about a slat's size; the rim
#: is kept to a cell; module text)
SUB = 4


def hull_inside(grid: VoxelGrid, sub: int) -> np.ndarray | None:
    """(nx·sub, ny·sub, nz·sub) whether each cell's centre lies inside the convex hull of the
    grid's vegetation returns; None when they span no volume (all in a plane, < 4 points)."""
    from scipy.spatial import Delaunay, QhullError

    r = grid.returns
    if len(r) < 4:
        return None
    try:
        tri = Delaunay(r)
    except QhullError:
        return None
    w = grid.size_m / sub
    shape = tuple(int(n) * sub for n in grid.pad.shape)
    x, y = np.meshgrid(grid.x0 + (np.arange(shape[0]) + 0.5) * w,
                       grid.y0 + (np.arange(shape[1]) + 0.5) * w, indexing="ij")
    out = np.zeros(shape, bool)
    for k in range(shape[2]):       # a layer at a time: (nx·sub)·(ny·sub) points
        pts = np.column_stack([x.ravel(), y.ravel(), np.full(x.size, (k + 0.5) * w)])
        out[:, :, k] = (tri.find_simplex(pts) >= 0).reshape(shape[0], shape[1])
    return out


def _solve_u(paths: np.ndarray, gap: np.ndarray, g: float) -> tuple[np.ndarray, np.ndarray]:
    """(u m²/m³, solved) per voxel: the density with mean_c exp(−u·g·paths[:, c]) = gap
    (paths (n, sub²) m); solved False where even u → ∞ leaves more gap than ``gap``."""
    empty = np.mean(paths <= 0, axis=1)
    solved = empty < gap - 1e-9
    lo = np.zeros(len(gap))
    hi = np.full(len(gap), 1.0)
    for _ in range(60):          # grow the bracket until it holds the root
        short = solved & (np.mean(np.exp(-hi[:, None] * g * paths), axis=1) > gap)
        if not short.any():
            break
        hi[short] *= 2.0
    for _ in range(60):          # bisection: the mean gap falls as u grows
        mid = 0.5 * (lo + hi)
        above = np.mean(np.exp(-mid[:, None] * g * paths), axis=1) > gap
        lo = np.where(above, mid, lo)
        hi = np.where(above, hi, mid)
    return 0.5 * (lo + hi), solved


def sharpen(grid: VoxelGrid, *, sub: int = SUB, vertical: bool = True) -> tuple[VoxelGrid, int]:
    """(the grid on cells of side size_m/``sub`` with its plant area inside the returns' hull,
    voxels whose gap the hull could not hold — kept area-conserving) (module text)."""
    inside = hull_inside(grid, sub)
    nx, ny, nz = grid.pad.shape
    v, w = grid.size_m, grid.size_m / sub
    if inside is None:
        inside = np.ones((nx * sub, ny * sub, nz * sub), bool)
    blocks = inside.reshape(nx, sub, ny, sub, nz, sub).transpose(0, 2, 4, 1, 3, 5)
    count = blocks.sum(axis=(3, 4, 5))                       # inside cells per voxel
    dense = (grid.pad > 0) & (count > 0)
    u = np.where(dense, grid.pad * sub**3 / np.maximum(count, 1), grid.pad)  # area-conserving
    unsolved = 0
    if vertical and dense.any():
        paths = blocks[dense].sum(axis=-1).reshape(-1, sub * sub) * w   # ℓ_c per cell column
        gap = np.exp(-grid.pad[dense] * grid.g * v)
        us, ok = _solve_u(paths, gap, grid.g)
        u[dense] = np.where(ok, np.maximum(us, u[dense]), u[dense])
        unsolved = int((~ok).sum())
    keep = np.where(dense[..., None, None, None], blocks, True)
    fine = np.where(keep, u[..., None, None, None], 0.0).transpose(0, 3, 1, 4, 2, 5).reshape(
        nx * sub, ny * sub, nz * sub)
    cols = np.nonzero(fine.sum(axis=2))
    if len(cols[0]) == 0:
        return VoxelGrid(grid.x0, grid.y0, w, fine, grid.g, grid.spacing_m, grid.returns), 0
    i0, i1, j0, j1 = cols[0].min(), cols[0].max() + 1, cols[1].min(), cols[1].max() + 1
    return VoxelGrid(grid.x0 + i0 * w, grid.y0 + j0 * w, w, fine[i0:i1, j0:j1].copy(), grid.g,
                     grid.spacing_m, grid.returns), unsolved
