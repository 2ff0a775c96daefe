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
``ConvexHull``): the returns are where the beams met leaves, and no leaf stands outside the
smallest convex body that holds them all (a concave crown keeps its concavities at voxel
scale: only voxels the hull crosses change). The density in a voxel's inside cells:

* vertical-beam inversion (airborne scans, ``beams`` given): the column inversion of
  :mod:`radtree.lidar.voxels` again, on the beams through the voxel's hull part only. Of the
  beams of the voxel's cell columns c that the hull crosses (ℓ_c > 0: the column's inside
  cells in the voxel × w), N_c reach the voxel's top and N(z_bottom) = Σ its bottom; the
  density u of the inside cells solves Σ_c N_c exp(−u·G·ℓ_c) / Σ_c N_c = (N(z_bottom) + ½) /
  (Σ_c N_c + ½) (the same ½ correction). Counting every beam of the voxel, as the voxel
  inversion does, mixes beams that miss the crown with beams through it, and reads a rim
  voxel low — the sub-voxel heterogeneity that biases a voxel's Beer–Lambert estimate
  (Soma et al. 2018, Remote Sens. 10:1580; Pimont, Soma & Dupuy 2019, Remote Sens. 11:1580,
  "sub-grid clumping"), taken out with the one thing known about it: where the crown is.
  (Solving instead for the voxel's own gap over its hull part amplifies the counts' noise
  where the hull covers a sliver of the voxel; benchmarks/lidar_facade.py.) A voxel no beam
  through its hull part reached (occluded, filled from its layer) keeps its leaf area,
  spread over its inside cells;
* airborne beams rebuilt from the scan angle (:mod:`radtree.lidar.scan_angle`): the same
  re-inversion along each tilted beam's own path through the voxel's inside cells
  (:mod:`radtree.trees.points_rim`);
* beams along their own paths from terrestrial scans (:mod:`radtree.lidar.beams`): the
  voxel's plant area PAD·v³ spread over its inside cells (area-conserving).

A voxel with plant area but no inside cell (an occluded voxel filled from its layer, outside
the hull) keeps its density in all its cells. The grid is cropped horizontally to the cells
with plant area.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from radtree.lidar.voxels import VoxelGrid

#: hull cells per voxel side (1.25 m voxels → 0.31 m cells, about a slat's size; the rim
#: is kept to a cell; module text)
SUB = 4


def vertical_beams(path: str | Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(x, y (n, 2) m, heights above ground (n,) m, weights (n,)) of every return of the tree
    in ``path`` but buildings and noise — as :func:`radtree.lidar.voxels.tree_voxels` reads
    them (weights: :func:`radtree.lidar.voxels.echo_weights`, by intensity share)."""
    from radtree.lidar.ground import NOT_TREES, heights_above_ground
    from radtree.lidar.tile import read_tile
    from radtree.lidar.voxels import echo_weights

    tile = read_tile(path)
    heights, _ = heights_above_ground(tile, "class")
    keep = ~np.isin(tile.classification, NOT_TREES)
    return tile.xyz[keep, :2], heights[keep], echo_weights(tile, "intensity")[keep]


def crown_centre(grid: VoxelGrid) -> np.ndarray:
    """Where a crown from points stands on its trunk: the area centroid (x, y m) of the
    convex outline of its vegetation returns seen from above — the crown projection's centre,
    which the outermost returns fix (the plant-area centroid also carries the inversion's
    noise voxel by voxel: on the synthetic crowns of ``benchmarks/lidar_facade.py`` 0.03 m
    r.m.s. from the trunk against 0.11 m, 16 scans); the plant-area centroid where the
    returns span no area."""
    from scipy.spatial import ConvexHull, QhullError

    xy = grid.returns[:, :2]
    ref = xy.mean(axis=0) if len(xy) else np.zeros(2)   # map coordinates: keep the digits
    try:
        p = xy[ConvexHull(xy).vertices] - ref
    except (QhullError, ValueError):
        return grid.centroid_xy()
    x, y = p[:, 0], p[:, 1]
    x1, y1 = np.roll(x, -1), np.roll(y, -1)
    cross = x * y1 - x1 * y
    area = cross.sum() / 2.0
    if abs(area) < 1e-12:
        return grid.centroid_xy()
    return ref + np.array([((x + x1) * cross).sum(), ((y + y1) * cross).sum()]) / (6.0 * area)


def hull_inside(grid: VoxelGrid, sub: int, margin_m: float = 0.0) -> np.ndarray | None:
    """(nx·sub, ny·sub, nz·sub) whether each cell's centre lies inside the convex hull of the
    grid's vegetation returns, its faces moved ``margin_m`` outwards; None when they span no
    volume (all in a plane, < 4 points)."""
    from scipy.spatial import ConvexHull, QhullError

    r = grid.returns
    if len(r) < 4:
        return None
    ref = r.mean(axis=0)                      # map coordinates: keep the digits
    try:
        eq = ConvexHull(r - ref).equations    # n·(x − ref) + c ≤ 0 inside, |n| = 1
    except QhullError:
        return None
    eq[:, 3] -= eq[:, 2] * ref[2]             # heights: n·x − n_z·ref_z …
    w = grid.size_m / sub
    shape = tuple(int(n) * sub for n in grid.pad.shape)
    x, y = np.meshgrid(grid.x0 - ref[0] + (np.arange(shape[0]) + 0.5) * w,
                       grid.y0 - ref[1] + (np.arange(shape[1]) + 0.5) * w, indexing="ij")
    xy = np.column_stack([x.ravel(), y.ravel()]) @ eq[:, :2].T + eq[:, 3] - margin_m
    out = np.zeros(shape, bool)
    for k in range(shape[2]):       # a layer at a time: (nx·sub)·(ny·sub) × faces
        far = xy + ((k + 0.5) * w) * eq[:, 2]
        out[:, :, k] = (far.max(axis=1) <= 0.0).reshape(shape[0], shape[1])
    return out


def _solve_u(paths: np.ndarray, *, weights: np.ndarray, gap: np.ndarray, g: float
             ) -> tuple[np.ndarray, np.ndarray]:
    """(u m²/m³, solved) per voxel: the density with Σ_c w_c exp(−u·g·ℓ_c) / Σ_c w_c = gap
    (``paths`` ℓ (n, sub²) m, ``weights`` w the beams reaching each cell column) by
    bisection; solved False where even u → ∞ leaves more gap than ``gap``."""
    wsum = np.maximum(weights.sum(axis=1), 1e-300)

    def mean_gap(uu: np.ndarray) -> np.ndarray:
        return np.sum(weights * np.exp(-uu[:, None] * g * paths), axis=1) / wsum

    solved = np.sum(weights * (paths <= 0), axis=1) / wsum < gap - 1e-9
    return solve_mean_gap(mean_gap, gap, solved), solved


def solve_mean_gap(mean_gap: Callable[[np.ndarray], np.ndarray], gap: np.ndarray,
                   want: np.ndarray) -> np.ndarray:
    """The density u (m²/m³) per entry where ``mean_gap(u)`` (falling in u) equals ``gap``,
    for the entries ``want`` (bracket doubled from 1 until it holds the root, then 60
    bisections); the others are left at the bracket's middle."""
    lo = np.zeros(len(gap))
    hi = np.full(len(gap), 1.0)
    for _ in range(60):          # grow the bracket until it holds the root
        short = want & (mean_gap(hi) > gap)
        if not short.any():
            break
        hi[short] *= 2.0
    for _ in range(60):          # bisection: the mean gap falls as u grows
        mid = 0.5 * (lo + hi)
        above = mean_gap(mid) > gap
        lo = np.where(above, mid, lo)
        hi = np.where(above, hi, mid)
    return 0.5 * (lo + hi)


def footprint_density(grid: VoxelGrid, inside: np.ndarray, *, xy: np.ndarray,
                      heights: np.ndarray, ground_m: float = 0.5,
                      weights: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(u m²/m³, counted) per voxel: the column inversion of :mod:`radtree.lidar.voxels` on
    the beams through the hull's part of each voxel only (module text). ``xy`` (n, 2) m and
    ``heights`` (n,) m above ground of every return of the tree, ground returns included (one
    vertical beam each, of weight ``weights``: 1 when None; the ½ added in effective beams,
    (Σ w)² / Σ w²); ``counted``: voxels some beam reached."""
    nx, ny, nz = grid.pad.shape
    sub = inside.shape[0] // nx
    w, g = grid.size_m / sub, grid.g
    fi = np.floor((xy[:, 0] - grid.x0) / w).astype(np.int64)
    fj = np.floor((xy[:, 1] - grid.y0) / w).astype(np.int64)
    ok = (fi >= 0) & (fi < nx * sub) & (fj >= 0) & (fj < ny * sub)
    k = np.where(heights >= ground_m, np.floor(heights / grid.size_m), -1).astype(np.int64)
    k = np.clip(k, -1, nz - 1)
    wt = np.ones(len(heights)) if weights is None else np.asarray(weights, float)
    counts = np.zeros((nx * sub, ny * sub, nz + 1))      # [..., 0] ground, [..., k + 1] layer k
    np.add.at(counts, (fi[ok], fj[ok], k[ok] + 1), wt[ok])
    squares = np.zeros((nx * sub, ny * sub, nz + 1))
    np.add.at(squares, (fi[ok], fj[ok], k[ok] + 1), wt[ok] ** 2)
    below = np.cumsum(counts, axis=2)
    top, bottom = below[..., 1:], below[..., :-1]        # N(z_top), N(z_bottom) per cell column
    top_sq = np.cumsum(squares, axis=2)[..., 1:]

    def per_voxel(a: np.ndarray) -> np.ndarray:           # (nx, ny, nz, sub²)
        return a.reshape(nx, sub, ny, sub, nz).transpose(0, 2, 4, 1, 3).reshape(
            nx, ny, nz, sub * sub)

    paths = per_voxel(inside.reshape(nx * sub, ny * sub, nz, sub).sum(axis=-1) * w)
    lit = paths > 0
    n_top = per_voxel(top) * lit
    n_top_sum = n_top.sum(axis=-1)
    n_bottom = (per_voxel(bottom) * lit).sum(axis=-1)
    counted = n_top_sum > 0
    sq = (per_voxel(top_sq) * lit).sum(axis=-1)[counted]
    n_eff = n_top_sum[counted] ** 2 / np.maximum(sq, 1e-300)     # effective beams
    gap = (n_eff * n_bottom[counted] / n_top_sum[counted] + 0.5) / (n_eff + 0.5)
    u = np.zeros((nx, ny, nz))
    us, _ = _solve_u(paths[counted], weights=n_top[counted], gap=np.minimum(gap, 1.0), g=g)
    u[counted] = np.where(gap < 1.0, us, 0.0)
    return u, counted


def sharpen(grid: VoxelGrid, *, sub: int = SUB,
            beams: tuple[np.ndarray, ...] | None = None, margin_m: float = 0.0,
            density: Callable[[VoxelGrid, np.ndarray], tuple[np.ndarray, np.ndarray]]
            | None = None) -> tuple[VoxelGrid, int]:
    """(the grid on cells of side size_m/``sub`` with its plant area inside the returns' hull
    (widened by ``margin_m``), voxels with plant area that no beam through their hull part
    reached — their leaf area kept, spread over their inside cells) (module text). ``beams``:
    (x, y, heights[, weights]) of :func:`vertical_beams` for the vertical-beam inversion; None spreads
    every voxel's leaf area over its inside cells. ``density``: (grid, inside) → (u, counted)
    instead, e.g. the re-inversion along tilted beams
    (:func:`radtree.trees.points_rim.beam_footprint_density`)."""
    inside = hull_inside(grid, sub, margin_m)
    nx, ny, nz = grid.pad.shape
    w = grid.size_m / sub
    if inside is None:
        inside = np.ones((nx * sub, ny * sub, nz * sub), bool)
    blocks = inside.reshape(nx, sub, ny, sub, nz, sub).transpose(0, 2, 4, 1, 3, 5)
    count = blocks.sum(axis=(3, 4, 5))                       # inside cells per voxel
    dense = (grid.pad > 0) & (count > 0)
    u = np.where(dense, grid.pad * sub**3 / np.maximum(count, 1), grid.pad)  # area-conserving
    unreached = 0
    if beams is not None and density is None:
        def density(gr: VoxelGrid, ins: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            return footprint_density(gr, ins, xy=beams[0], heights=beams[1],
                                     weights=beams[2] if len(beams) > 2 else None)
    if density is not None and dense.any():
        uf, counted = density(grid, inside)
        u = np.where(dense & counted, uf, u)
        unreached = int((dense & ~counted).sum())
    keep = np.where(dense[..., None, None, None], blocks, True)
    fine = np.where(keep, u[..., None, None, None], 0.0).transpose(0, 3, 1, 4, 2, 5).reshape(
        nx * sub, ny * sub, nz * sub)
    cols = np.nonzero(fine.sum(axis=2))
    if len(cols[0]) == 0:
        return VoxelGrid(grid.x0, grid.y0, w, fine, grid.g, grid.spacing_m, grid.returns), 0
    i0, i1, j0, j1 = cols[0].min(), cols[0].max() + 1, cols[1].min(), cols[1].max() + 1
    return VoxelGrid(grid.x0 + i0 * w, grid.y0 + j0 * w, w, fine[i0:i1, j0:j1].copy(), grid.g,
                     grid.spacing_m, grid.returns), unreached
