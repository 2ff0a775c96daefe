"""Fitting slats of free-standing crowns to the trunk, the wall side and the neighbour crowns.

Shared by the layered louvers (:mod:`radtree.trees.louvers_free`) and the volume arrangement
(:mod:`radtree.trees.volume`). Local coordinates (u along the façade, n away from it, z up):
a crown's share of the row is the street side of the wall-side clip plane ``n = n_clip`` and
its strip ``lo ≤ u ≤ hi`` between the planes shared with its neighbours.
"""

from __future__ import annotations

import numpy as np

from radtree.trees.envelope import CrownRowSpec
from radtree.trees.geometry import clip_polygons

_U, _N, _Z = np.eye(3)


def trunk_clash(rho: np.ndarray, z_low: np.ndarray, spec: CrownRowSpec, s: float) -> np.ndarray:
    """Slats (plan distance ``rho`` of their centre from the trunk axis, lowest corner
    ``z_low``) that would cut the trunk: within trunk radius + 0.75·s of the axis and reaching
    below 5 cm above the trunk top."""
    return (rho < spec.trunk_radius + 0.75 * s) & (z_low < spec.trunk_top + 0.05)


def touches_share(corners: np.ndarray, spec: CrownRowSpec, lo: float, hi: float) -> np.ndarray:
    """Slats (k, m, 3) with at least one corner in a crown's share of the row: on the street
    side of the wall-side clip plane and within the crown's strip [lo, hi] of u."""
    return (np.any(corners[:, :, 1] >= spec.n_clip, axis=1)
            & np.any(corners[:, :, 0] >= lo, axis=1) & np.any(corners[:, :, 0] <= hi, axis=1))


def cut_to_share(corners: np.ndarray, spec: CrownRowSpec, lo: float, hi: float
                 ) -> tuple[list[np.ndarray], int]:
    """Slats (k, m, 3) touching a crown's share, cut at the wall-side clip plane and at the
    planes shared with neighbour crowns. Returns the polygons and how many were cut."""
    inside = (np.all(corners[:, :, 1] >= spec.n_clip, axis=1)
              & np.all(corners[:, :, 0] >= lo, axis=1) & np.all(corners[:, :, 0] <= hi, axis=1))
    polys: list[np.ndarray] = list(corners[inside])
    rest = corners[~inside]
    count = np.full(len(rest), rest.shape[1])
    rest, count = clip_polygons(rest, count, _N, spec.n_clip)
    if np.isfinite(lo):
        rest, count = clip_polygons(rest, count, _U, lo)
    if np.isfinite(hi):
        rest, count = clip_polygons(rest, count, -_U, -hi)
    kept = np.flatnonzero(count >= 3)
    polys.extend(rest[i, :count[i]] for i in kept)
    return polys, len(kept)
