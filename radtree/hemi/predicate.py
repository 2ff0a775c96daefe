"""Is a direction sky? A vectorised predicate that samples a classified fisheye photo.

The perforated crown model calls it with arrays of (zenith, azimuth) in degrees (for
horizontal-axis photos: angle from the lens axis, angle around it) and gets booleans: True
where the nearest pixel of the photo is sky. Directions the photo does not cover (beyond 90°,
outside the frame of a full-frame image, NaN) get ``outside`` (default False: opaque).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .directions import world_to_horizontal, world_to_up
from .geometry import FisheyeGeometry


@dataclass(frozen=True)
class SkyPredicate:
    """Callable ``(zenith_deg, azimuth_deg) -> bool array``: True where the photo shows sky.

    ``sky`` is the classified sky over the pixel box ``rows`` × ``cols`` of the image.
    """

    sky: NDArray[np.bool_]
    rows: slice
    cols: slice
    geometry: FisheyeGeometry
    outside: bool = False

    def __call__(self, zenith: ArrayLike, azimuth: ArrayLike) -> NDArray[np.bool_]:
        z = np.asarray(zenith, dtype=np.float64)
        a = np.asarray(azimuth, dtype=np.float64)
        z, a = np.broadcast_arrays(z, a)
        x, y = self.geometry.to_pixel(z, a)
        ok = np.isfinite(x) & np.isfinite(y) & (z >= 0) & (z <= 90.0)
        col = np.floor(np.where(ok, x, 0.0)).astype(np.intp) - self.cols.start
        row = np.floor(np.where(ok, y, 0.0)).astype(np.intp) - self.rows.start
        h, w = self.sky.shape
        ok &= (row >= 0) & (row < h) & (col >= 0) & (col < w)
        result = np.full(z.shape, self.outside, dtype=bool)
        result[ok] = self.sky[row[ok], col[ok]]
        return result

    def world(self, vectors: ArrayLike, facade_azimuth: float | None = None) -> NDArray[np.bool_]:
        """The same test for world unit vectors (..., 3) (x east, y north, z up).

        Horizontal-axis photos need ``facade_azimuth``, the compass direction of the lens axis.
        """
        if self.geometry.axis == "up":
            z, a = world_to_up(vectors)
        else:
            if facade_azimuth is None:
                raise ValueError("a horizontal-axis photo needs the façade azimuth")
            z, a = world_to_horizontal(vectors, facade_azimuth)
        return self(z, a)

    def sky_fraction(self, zenith: ArrayLike, azimuth: ArrayLike) -> float:
        """Share of the given directions that are sky."""
        return float(np.mean(self(zenith, azimuth)))
