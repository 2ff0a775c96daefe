"""Heights above ground: z minus a terrain model interpolated from the ground points.

Three ways to know the ground (``ground``):

* ``"class"`` (default): the points classified 2 (ground, ASPRS LAS 1.4 R15 Table 17). The
  terrain at every point is the linear interpolation (Delaunay triangles of the ground points,
  scipy ``LinearNDInterpolator``), the nearest ground point outside their hull.
* ``"filter"``: a simple stated ground filter for tiles without classes — the lowest point of
  each ``cell_m`` cell, then a grey-scale morphological opening of that minimum raster with a
  square window of ``window_m`` (larger than the widest crown, so no crown survives it; the
  single-window filter of Kilian, Haala & Englich 1996, IAPRS 31(B3)); points within
  ``tolerance_m`` of the opened surface are ground. It fails on steep slopes and buildings
  wider than the window: classify with PDAL's ``filters.smrf`` or ``filters.csf`` instead.
* ``"heights"``: z already holds heights above ground (a normalised tile).

Units: metres. Heights below zero (ground noise) are kept as they are.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from radtree.errors import ConfigError
from radtree.lidar.tile import GROUND_CLASS, Tile

GROUND_MODES = ("class", "filter", "heights")


@dataclass(frozen=True)
class GroundFilter:
    """The stated simple filter (module text): cell, window and tolerance in metres."""

    cell_m: float = 1.0
    window_m: float = 20.0
    tolerance_m: float = 0.5

    def __post_init__(self) -> None:
        if not (0 < self.cell_m < self.window_m) or self.tolerance_m <= 0:
            raise ConfigError(f"ground filter cell {self.cell_m:g} m, window "
                              f"{self.window_m:g} m, tolerance {self.tolerance_m:g} m: expected "
                              "0 < cell < window and tolerance > 0")

    def ground_mask(self, xyz: np.ndarray) -> np.ndarray:
        from scipy import ndimage

        ij = np.floor((xyz[:, :2] - xyz[:, :2].min(axis=0)) / self.cell_m).astype(np.int64)
        shape = tuple(ij.max(axis=0) + 1)
        zmin = np.full(shape, np.inf)
        np.minimum.at(zmin, (ij[:, 0], ij[:, 1]), xyz[:, 2])
        empty = ~np.isfinite(zmin)
        if empty.any():   # empty cells take their nearest cell's minimum
            idx = ndimage.distance_transform_edt(empty, return_distances=False,
                                                 return_indices=True)
            zmin = zmin[tuple(idx)]
        k = max(3, int(round(self.window_m / self.cell_m)) | 1)
        opened = ndimage.grey_opening(zmin, size=(k, k))
        return np.asarray(xyz[:, 2] - opened[ij[:, 0], ij[:, 1]] <= self.tolerance_m)


def ground_points(tile: Tile, ground: str, flt: GroundFilter | None = None) -> np.ndarray:
    """Mask of the tile's ground points by ``ground`` (module text)."""
    if ground == "class":
        mask = tile.classification == GROUND_CLASS
        if mask.sum() < 3:
            raise ConfigError(
                f"the tile has {int(mask.sum())} ground points (classification 2) and its "
                "heights are not normalised: classify the ground first (PDAL filters.smrf), "
                "use the stated simple filter (--ground filter), or say z already holds "
                "heights above ground (--ground heights)", source=tile.source, field="ground")
        return np.asarray(mask)
    if ground == "filter":
        return (flt or GroundFilter()).ground_mask(tile.xyz)
    raise ConfigError(f"ground = {ground!r}, expected one of {', '.join(GROUND_MODES)}",
                      source=tile.source, field="ground")


def terrain_at(ground_xyz: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """Terrain height at ``xy`` (k, 2): linear on the ground points' triangles, nearest
    ground point outside them."""
    from scipy.interpolate import LinearNDInterpolator, NearestNDInterpolator

    # one ground point per 0.5 m cell (the lowest) keeps the triangulation small
    key = np.floor(ground_xyz[:, :2] / 0.5).astype(np.int64)
    order = np.lexsort((ground_xyz[:, 2], key[:, 1], key[:, 0]))
    k = key[order]
    first = np.ones(len(k), bool)
    first[1:] = np.any(k[1:] != k[:-1], axis=1)
    g = ground_xyz[order][first]
    near = NearestNDInterpolator(g[:, :2], g[:, 2])(xy)
    if len(g) < 3 or np.ptp(g[:, 0]) == 0 or np.ptp(g[:, 1]) == 0:
        return np.asarray(near)
    try:
        lin = LinearNDInterpolator(g[:, :2], g[:, 2])(xy)
    except Exception:   # degenerate (collinear) ground points: Qhull refuses; nearest only
        return np.asarray(near)
    return np.where(np.isfinite(lin), lin, near)


def heights_above_ground(tile: Tile, ground: str = "class",
                         flt: GroundFilter | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(heights above ground of every point in m, ground mask) — see the module text."""
    if ground not in GROUND_MODES:
        raise ConfigError(f"ground = {ground!r}, expected one of {', '.join(GROUND_MODES)}",
                          source=tile.source, field="ground")
    if ground == "heights":
        return tile.xyz[:, 2].copy(), tile.classification == GROUND_CLASS
    mask = ground_points(tile, ground, flt)
    return tile.xyz[:, 2] - terrain_at(tile.xyz[mask], tile.xyz[:, :2]), mask
