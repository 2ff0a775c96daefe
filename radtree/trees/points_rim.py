"""The rim re-inversion along tilted beams (airborne ``[tree] points`` with scan-angle beams).

The vertical-column path of :mod:`radtree.trees.points_hull` redoes each voxel's inversion on
the beams through the voxel's part inside the returns' hull only, solving for the density u
of that part with every beam's own path in it. Along beams rebuilt from the scan angle
(:mod:`radtree.lidar.scan_angle`) the voxel inversion (:mod:`radtree.lidar.beams`) clips the
beams to the envelope (the hull pushed out by one point spacing) and gives one mean-path
density for the voxel's whole part inside it; spreading that area over the hull cells keeps
the rim's Jensen bias (−ln of a mean transmittance < the mean of −ln: beams that graze the
hull part's corner, or cross only the empty margin, dilute the gap; Soma et al. 2018, Remote
Sens. 10:1580). Measured (``benchmarks/lidar_facade.py``, 2026-12-07): the near-nadir crown's
wall-side rim 6 % too transparent at 13:30 along the beams (1.062) against 1.003 with the
vertical re-inversion.

Here the re-inversion along the tilted beams: every beam b (origin → return; an intercepted
beam on to the exit of its return's voxel, the chord it was exposed to, as
:mod:`radtree.lidar.beams` counts it) is walked on the hull's cells (side w = v / sub,
Amanatides & Woo 1987 via :func:`radtree.lidar.beams.traverse`); ℓ_b is its length in the
voxel's inside cells. Of the beams with ℓ_b > 0 (weight w_b: the return's share of its pulse,
:func:`radtree.lidar.voxels.echo_weights`), N enter and I are intercepted in the voxel (weighted;
n = N²/Σ w_b² the effective number of beams, :mod:`radtree.lidar.beams`); the density u of the
inside cells is

    u = −ln( (n·(1 − I/N) + ½) / (n + ½) ) / l̄_G,   l̄_G = Σ_b w_b·G(μ_b)·ℓ_b / N

(the voxel inversion's own estimator, :mod:`radtree.lidar.beams`, on the beams through the
hull part only, ``estimator = "mean_path"``, the default), or u solving
Σ_b w_b exp(−u·G(μ_b)·ℓ_b) / Σ_b w_b = (n·(1 − I/N) + ½) / (n + ½) (``"sum_exp"``, the vertical
columns' rule of :mod:`radtree.trees.points_hull`, which takes each beam's own path in the
hull part into account). Only rim voxels (the hull crosses them) are re-inverted: a voxel
wholly inside the hull keeps the inversion's estimate. A voxel that fewer than ``pulse_min``
(effective) beams entered through its hull part keeps the inversion's leaf area spread over its inside
cells (the undersampled voxels' rule of :mod:`radtree.lidar.voxels`).

Measured (2026-12-07, ``benchmarks/lidar_facade.py --seeds 8 --turbid-seeds 16``, turbid
expectations vox/turb; load 5–7) at the 10:30 sensors / 13:30 sensors / 13:30 map: spread
(before) 1.001 / 1.062 ± 0.015 / 1.018; mean-path (default) 1.001 / 1.037 ± 0.018 / 1.015;
sum-exp 1.000 / 1.025 ± 0.019 / 1.011 (all voxels or rim voxels only: the same). Street leaf
area (``benchmarks/lidar_als_user.py --seeds 0-5``): see that benchmark's docstring — the
sum-exp rule raises the rim's leaf area: 51 of 55 tree scans within 10 % at seeds 0–2 (rim
voxels only; 57 of 60 before). Units: metres, heights above ground.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from radtree.lidar.beams import BeamCounts, Beams, chord_beyond, traverse
from radtree.lidar.voxels import PULSE_MIN, VoxelGrid, echo_weights
from radtree.trees.points_hull import solve_mean_gap


def tilted_beams(path: str | Path, origins: np.ndarray | None = None) -> Beams:
    """The beams of the tree in ``path`` in the grid's frame (heights above ground), as
    :func:`radtree.lidar.voxels.tree_voxels` follows them: from the scan-angle origins
    (:func:`radtree.lidar.scan_angle.scan_angle_origins`, or ``origins`` (n, 3)) to each
    return; buildings and noise left out."""
    from radtree.lidar.ground import NOT_TREES, heights_above_ground
    from radtree.lidar.scan_angle import HEIGHT_RANGE_M, scan_angle_origins
    from radtree.lidar.tile import read_tile
    tile = read_tile(path)
    if origins is None:
        o = scan_angle_origins(tile)
        origins = tile.xyz + [0.0, 0.0, HEIGHT_RANGE_M[1]] if o is None else o
    heights, _ = heights_above_ground(tile, "class")
    keep = ~np.isin(tile.classification, NOT_TREES)
    xyz, h = tile.xyz[keep], heights[keep]
    end = np.column_stack([xyz[:, :2], h])
    start = np.asarray(origins, float)[keep] - np.column_stack(
        [np.zeros((len(h), 2)), xyz[:, 2] - h])
    return Beams(start, end, h >= 0.5, echo_weights(tile, "intensity")[keep])


def beam_footprint_density(grid: VoxelGrid, inside: np.ndarray, *, beams: Beams,
                           g_of_mu: Callable[[np.ndarray], np.ndarray],
                           pulse_min: float = PULSE_MIN, estimator: str = "mean_path"
                           ) -> tuple[np.ndarray, np.ndarray]:
    """(u m²/m³, counted) per voxel of ``grid``: the density of each voxel's inside cells
    (``inside``, the hull cells of :func:`radtree.trees.points_hull.hull_inside`) from the
    beams through them, ``estimator`` "mean_path" or "sum_exp" (module text); ``counted``: voxels at least ``pulse_min`` beams
    entered through their inside cells and that the hull crosses (rim voxels; a voxel wholly
    inside keeps the inversion's own estimate)."""
    nx, ny, nz = grid.pad.shape
    sub = inside.shape[0] // nx
    v = grid.size_m
    w = v / sub
    lo = np.array([grid.x0, grid.y0, 0.0])
    d = beams.end - beams.origin
    d /= np.maximum(np.linalg.norm(d, axis=1), 1e-12)[:, None]
    beyond = np.where(beams.hit, chord_beyond(beams.end, d=d, lo=lo, size=v), 0.0)
    end = beams.end + (beyond * (1.0 - 1e-9))[:, None] * d
    seg, cell, length = traverse(beams.origin, end=end, lo=lo, size=w, shape=inside.shape)
    keep = inside.ravel()[cell]
    seg, cell, length = seg[keep], cell[keep], length[keep]
    fi, fj, fk = np.unravel_index(cell, inside.shape)
    vox = np.ravel_multi_index((fi // sub, fj // sub, fk // sub), (nx, ny, nz))
    pair, inv = np.unique(seg * (nx * ny * nz) + vox, return_inverse=True)
    ell = np.bincount(inv, weights=length, minlength=len(pair))
    b, pv = pair // (nx * ny * nz), pair % (nx * ny * nz)
    k = np.floor((beams.end[b] - lo) / v).astype(np.int64)
    inb = np.all((k >= 0) & (k < np.array([nx, ny, nz])), axis=1)
    end_vox = np.where(inb, np.ravel_multi_index(np.clip(k, 0, [nx - 1, ny - 1, nz - 1]).T,
                                                 (nx, ny, nz)), -1)
    wb = beams.weight[b]
    hit = beams.hit[b] & (end_vox == pv)
    gb = np.asarray(g_of_mu(np.abs(d[b, 2])), float)
    n = nx * ny * nz
    counts = BeamCounts(np.bincount(pv, weights=wb, minlength=n),
                        np.bincount(pv, weights=wb * hit, minlength=n),
                        np.zeros(n), np.bincount(pv, weights=wb**2, minlength=n))
    entering, hits, n_eff = counts.entering, counts.hits, counts.effective()
    rim = (inside.reshape(nx, sub, ny, sub, nz, sub).sum(axis=(1, 3, 5)) < sub**3).ravel()
    counted = (n_eff >= pulse_min) & rim
    with np.errstate(divide="ignore", invalid="ignore"):   # the voxels' gap (beams.density)
        gap = (n_eff * np.maximum(entering - hits, 0.0) / entering + 0.5) / (n_eff + 0.5)
    if estimator == "mean_path":
        optical = np.bincount(pv, weights=wb * gb * ell, minlength=n)
        with np.errstate(divide="ignore", invalid="ignore"):
            u = np.where(counted & (optical > 0),
                         -np.log(np.minimum(gap, 1.0)) * entering / optical, 0.0)
    else:
        u = _solve_pairs(pv, weights=wb, optical=gb * ell, gap=np.where(counted, gap, 1.0),
                         n=n)
    return u.reshape(nx, ny, nz), counted.reshape(nx, ny, nz)


def _solve_pairs(pv: np.ndarray, *, weights: np.ndarray, optical: np.ndarray,
                 gap: np.ndarray, n: int) -> np.ndarray:
    """u per voxel with Σ w exp(−u·optical) / Σ w = gap over the voxel's (beam, voxel)
    pairs ``pv`` (``optical`` = G·ℓ m per pair), by bisection; 0 where gap ≥ 1."""
    wsum = np.maximum(np.bincount(pv, weights=weights, minlength=n), 1e-300)

    def mean_gap(u: np.ndarray) -> np.ndarray:
        return np.bincount(pv, weights=weights * np.exp(-u[pv] * optical), minlength=n) / wsum

    want = gap < 1.0 - 1e-12
    return np.where(want, solve_mean_gap(mean_gap, gap, want), 0.0)
