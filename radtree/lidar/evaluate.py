"""Detected trees against reference trees: matching by top position and the detection table.

Reference tops: for every reference tree id (a per-point extra dimension such as lidR's
``treeID``; values ≥ 1e300 or NaN mean "no tree"), its highest point (x, y, height above
ground). Matching is one-to-one and minimises the summed top distance (the Hungarian
assignment, scipy ``linear_sum_assignment``) among pairs closer than ``max_distance_m``.

Figures (:class:`Detection`): *found* = matched reference trees taller than ``min_height_m`` /
reference trees taller than ``min_height_m``; *false* = detected trees taller than
``min_height_m`` matched to no reference tree (of any height) / detected trees taller than
``min_height_m``; the median and mean absolute height error of the matched pairs whose
reference is taller than ``min_height_m``; the median relative crown diameter error of those
pairs, a reference crown's diameter being the equal-area circle of the CHM cells its points
above the segmentation's ``min_height_m`` fall in.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from radtree.errors import ConfigError
from radtree.lidar.segment import Segmentation
from radtree.lidar.tile import NO_ID


def reference_tops(seg: Segmentation, field: str = "treeID") -> np.ndarray:
    """(k, 5) id, x, y, height and crown diameter (m) of every reference tree (module text)."""
    tile = seg.tile
    if field not in tile.extra:
        raise ConfigError(f"the tile has no {field!r} dimension (its extra dimensions: "
                          f"{', '.join(tile.extra) or 'none'})", source=tile.source,
                          field=field)
    ids = np.asarray(tile.extra[field], float)
    ok = np.isfinite(ids) & (ids < NO_ID)
    rows = []
    for tid in np.unique(ids[ok]):
        sel = np.nonzero(ids == tid)[0]
        k = sel[np.argmax(seg.heights[sel])]
        up = sel[seg.heights[sel] >= seg.config.min_height_m]
        cells = len(np.unique(np.floor(tile.xyz[up, :2] / seg.chm.cell), axis=0))
        diameter = 2.0 * np.sqrt(cells * seg.chm.cell**2 / np.pi)
        rows.append((tid, tile.xyz[k, 0], tile.xyz[k, 1], seg.heights[k], diameter))
    return np.array(rows, float).reshape(-1, 5)


def match_tops(detected: np.ndarray, reference: np.ndarray, max_distance_m: float
               ) -> list[tuple[int, int, float]]:
    """One-to-one pairs (detected index, reference index, distance m) within the distance."""
    from scipy.optimize import linear_sum_assignment
    from scipy.spatial.distance import cdist

    if len(detected) == 0 or len(reference) == 0:
        return []
    d = cdist(detected[:, :2], reference[:, :2])
    big = 1e6
    rows, cols = linear_sum_assignment(np.where(d <= max_distance_m, d, big))
    return [(int(r), int(c), float(d[r, c])) for r, c in zip(rows, cols)
            if d[r, c] <= max_distance_m]


@dataclass(frozen=True)
class Detection:
    """The detection figures (module text)."""

    reference: int         # reference trees taller than min_height_m
    detected: int          # detected trees taller than min_height_m
    found: int
    false: int
    median_height_error_m: float
    mean_height_error_m: float
    median_distance_m: float
    median_diameter_error: float   # relative, |d − d_ref| / d_ref
    min_height_m: float
    max_distance_m: float

    @property
    def found_fraction(self) -> float:
        return self.found / self.reference if self.reference else float("nan")

    @property
    def false_fraction(self) -> float:
        return self.false / self.detected if self.detected else float("nan")

    def table(self) -> str:
        return "\n".join([
            f"reference trees > {self.min_height_m:g} m       {self.reference}",
            f"detected trees > {self.min_height_m:g} m        {self.detected}",
            f"found (top within {self.max_distance_m:g} m)     {self.found}  "
            f"({100 * self.found_fraction:.1f} %)",
            f"false trees                  {self.false}  ({100 * self.false_fraction:.1f} %)",
            f"median |height error|        {self.median_height_error_m:.2f} m",
            f"mean |height error|          {self.mean_height_error_m:.2f} m",
            f"median top distance          {self.median_distance_m:.2f} m",
            f"median |crown diameter error| {100 * self.median_diameter_error:.1f} %"])


def detection(seg: Segmentation, field: str = "treeID", min_height_m: float = 5.0,
              max_distance_m: float = 2.0) -> Detection:
    """Match ``seg``'s trees to the tile's reference trees (module text)."""
    ref = reference_tops(seg, field)
    det = np.array([[t.top_x, t.top_y, t.height_m, t.crown_diameter_m] for t in seg.trees],
                   float).reshape(-1, 4)
    pairs = match_tops(det, ref[:, 1:3], max_distance_m)
    ref_tall = ref[:, 3] > min_height_m
    det_tall = det[:, 2] > min_height_m
    matched_det = {r for r, _, _ in pairs}
    tall_pairs = [(r, c, d) for r, c, d in pairs if ref_tall[c]]
    err = np.array([abs(det[r, 2] - ref[c, 3]) for r, c, _ in tall_pairs])
    dist = np.array([d for _, _, d in tall_pairs])
    dd = np.array([abs(det[r, 3] - ref[c, 4]) / ref[c, 4] for r, c, _ in tall_pairs])
    false = sum(1 for i in np.nonzero(det_tall)[0] if i not in matched_det)
    return Detection(int(ref_tall.sum()), int(det_tall.sum()), len(tall_pairs), int(false),
                     float(np.median(err)) if len(err) else float("nan"),
                     float(np.mean(err)) if len(err) else float("nan"),
                     float(np.median(dist)) if len(dist) else float("nan"),
                     float(np.median(dd)) if len(dd) else float("nan"),
                     min_height_m, max_distance_m)
