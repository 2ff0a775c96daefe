"""Pixel <-> direction geometry of a fisheye photo (angles in degrees, pixels as in ``mask``).

Angle conventions
-----------------
*Upward photos* (``axis="up"``, the default): a direction is (zenith, azimuth), azimuth in degrees
clockwise from true north (compass). ``north_deg`` is where true north lies in the image, in
degrees clockwise from image-up as displayed (0 = north at the top). Looking up at the sky
swaps east and west relative to a map: with north at the top, east is on the *left*. That
mirror is on by default for upward photos (``mirror=True``); turn it off only for images that
were already flipped.

*Horizontal-axis photos* (``axis="horizontal"``: taken from a façade looking out, lens axis
horizontal, as in the reference study): "zenith" is the angle from the lens axis (0–90°) and
"azimuth" is the angle around the axis, clockwise from world-up as seen looking out along the
axis (0 = up, 90 = the viewer's right, 180 = down, 270 = left). ``north_deg`` is then where
world-up lies in the image (clockwise from image-up), and no mirror is applied by default
(the photo shows the scene as the viewer sees it). :func:`radtree.hemi.directions.horizontal_to_world`
turns these angles into world vectors given the façade azimuth.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import lru_cache
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from radtree.errors import ConfigError

from .lens import Projection
from .mask import CircularMask

AXES = ("up", "horizontal")


@dataclass(frozen=True)
class PixelField:
    """Per-pixel directions over the bounding box of the valid pixels.

    ``rows``/``cols`` locate the box in the image. ``zenith``/``azimuth`` are degrees (NaN
    outside ``valid``), ``weight`` the solid angle of each pixel in steradians (0 outside).
    """

    rows: slice
    cols: slice
    valid: NDArray[np.bool_]
    zenith: NDArray[np.float32]
    azimuth: NDArray[np.float32]
    weight: NDArray[np.float64]

    @property
    def shape(self) -> tuple[int, int]:
        return self.valid.shape  # type: ignore[return-value]

    def crop(self, image: NDArray) -> NDArray:
        """The part of a full image (H × W [× C]) covered by this field."""
        return image[self.rows, self.cols]


@dataclass(frozen=True)
class FisheyeGeometry:
    """Where each direction falls in a ``width`` × ``height`` px fisheye image.

    ``full_frame=True`` lets the 90° circle extend past the frame (full-frame fisheyes or
    cropped circles): only pixels inside both the frame and the circle are used. Otherwise the
    circle must lie inside the image.
    """

    width: int
    height: int
    mask: CircularMask
    lens: Projection = Projection()
    axis: str = "up"
    north_deg: float = 0.0
    mirror: bool = True
    full_frame: bool = False

    def __post_init__(self) -> None:
        if int(self.width) < 1 or int(self.height) < 1:
            raise ConfigError(f"image size must be positive, got {self.width}×{self.height}")
        object.__setattr__(self, "width", int(self.width))
        object.__setattr__(self, "height", int(self.height))
        if self.axis not in AXES:
            raise ConfigError(f"axis must be 'up' or 'horizontal', got '{self.axis}'", field="axis")
        if not math.isfinite(float(self.north_deg)):
            raise ConfigError(f"north must be a finite angle, got {self.north_deg}", field="north")
        object.__setattr__(self, "north_deg", float(self.north_deg) % 360.0)
        if self.full_frame:
            if not (0 <= self.mask.cx <= self.width and 0 <= self.mask.cy <= self.height):
                raise ConfigError(
                    f"mask centre ({self.mask.cx:g}, {self.mask.cy:g}) lies outside the "
                    f"{self.width}×{self.height} px image",
                    field="mask",
                )
        else:
            self.mask.check_inside(self.width, self.height)

    # -- single directions ------------------------------------------------------------------
    def to_direction(
        self, x: ArrayLike, y: ArrayLike
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(zenith, azimuth) in degrees of image points (x, y) in pixels; NaN beyond the lens."""
        dx = np.asarray(x, dtype=np.float64) - self.mask.cx
        dy = np.asarray(y, dtype=np.float64) - self.mask.cy
        rho = np.hypot(dx, dy) / self.mask.radius
        zenith = self.lens.zenith(rho)
        alpha = np.degrees(np.arctan2(dx, -dy))  # clockwise from image-up
        beta = alpha - self.north_deg
        azimuth = np.mod(-beta if self.mirror else beta, 360.0)
        return zenith, np.where(np.isnan(zenith), np.nan, azimuth)

    def to_pixel(
        self, zenith: ArrayLike, azimuth: ArrayLike
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Image point (x, y) in pixels of directions (zenith, azimuth) in degrees."""
        z = np.asarray(zenith, dtype=np.float64)
        a = np.asarray(azimuth, dtype=np.float64)
        r = self.lens.radius(z) * self.mask.radius
        beta = -a if self.mirror else a
        alpha = np.radians(beta + self.north_deg)
        return self.mask.cx + r * np.sin(alpha), self.mask.cy - r * np.cos(alpha)

    # -- the whole image --------------------------------------------------------------------
    def bounds(self) -> tuple[slice, slice]:
        """Row and column slices of the pixels that can be valid (circle ∩ frame)."""
        m = self.mask
        r0 = max(0, int(math.floor(m.cy - m.radius)))
        r1 = min(self.height, int(math.ceil(m.cy + m.radius)))
        c0 = max(0, int(math.floor(m.cx - m.radius)))
        c1 = min(self.width, int(math.ceil(m.cx + m.radius)))
        return slice(r0, r1), slice(c0, c1)

    def pixel_field(self, max_zenith: float = 90.0) -> PixelField:
        """Directions and solid angles of all pixel centres within ``max_zenith`` degrees.

        Cached for the last few geometries (a batch of photos from one camera shares it, and
        one photo's upward and horizontal analyses share the lens's part: the lens axis does
        not enter these camera-frame angles, and north and mirror only turn the azimuths);
        the arrays are read-only.
        """
        return _pixel_field(replace(self, axis="up"), float(max_zenith))

    def _compute_pixel_field(self, max_zenith: float) -> PixelField:
        radial = _radial_field(replace(self, axis="up", north_deg=0.0, mirror=False),
                               max_zenith)
        rows, cols, valid, zenith, weight, alpha = radial
        beta = alpha - self.north_deg
        azimuth = np.full(valid.shape, np.nan, dtype=np.float32)
        azimuth[valid] = np.mod(-beta if self.mirror else beta, 360.0)
        azimuth.setflags(write=False)
        return PixelField(rows, cols, valid, zenith, azimuth, weight)

    def _compute_radial_field(self, max_zenith: float) -> tuple[Any, ...]:
        """What the lens and mask alone give: the box, valid pixels, zenith (degrees),
        solid angle (sr) and, on the valid pixels, the angle clockwise from image-up
        (degrees, before north and mirror)."""
        rows, cols = self.bounds()
        y = np.arange(rows.start, rows.stop, dtype=np.float64) + 0.5
        x = np.arange(cols.start, cols.stop, dtype=np.float64) + 0.5
        dx = x[None, :] - self.mask.cx
        dy = y[:, None] - self.mask.cy
        rho = np.hypot(dx, dy) / self.mask.radius
        rho_max = float(self.lens.radius(np.array([min(max_zenith, self.lens.max_zenith_deg)]))[0])
        valid = rho <= rho_max
        # the trigonometry only for pixels inside the circle
        r_in = rho[valid]
        z_in = self.lens.zenith(r_in)
        ok = np.isfinite(z_in)
        if not ok.all():
            valid[valid] = ok
            r_in, z_in = r_in[ok], z_in[ok]
        dxb = np.broadcast_to(dx, rho.shape)[valid]
        dyb = np.broadcast_to(dy, rho.shape)[valid]
        alpha = np.degrees(np.arctan2(dxb, -dyb))
        zenith = np.full(rho.shape, np.nan, dtype=np.float32)
        weight = np.zeros(rho.shape)
        zenith[valid] = z_in
        weight[valid] = self.pixel_solid_angle(z_in, r_in)
        for a in (valid, zenith, weight, alpha):
            a.setflags(write=False)
        return rows, cols, valid, zenith, weight, alpha

    def pixel_solid_angle(
        self, zenith: NDArray[np.float64], rho: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        """Solid angle (sr) of a 1 × 1 px pixel at (zenith, rho): sinθ / (R² · rho · drho/dθ)."""
        z = np.asarray(zenith, dtype=np.float64)
        d = self.lens.derivative(z)
        with np.errstate(divide="ignore", invalid="ignore"):
            w = np.sin(np.radians(z)) / (np.maximum(rho, 1e-12) * d)
        d0 = float(self.lens.derivative(np.zeros(1))[0])
        w = np.where(rho < 1e-9, 1.0 / d0**2, w)  # limit at the image centre
        return w / self.mask.radius**2

    def describe(self) -> dict[str, object]:
        return {
            "lens": self.lens.describe(),
            "mask_cx": self.mask.cx,
            "mask_cy": self.mask.cy,
            "mask_radius": self.mask.radius,
            "axis": self.axis,
            "north_deg": self.north_deg,
            "mirror": self.mirror,
            "full_frame": self.full_frame,
        }


@lru_cache(maxsize=2)
def _pixel_field(geometry: FisheyeGeometry, max_zenith: float) -> PixelField:
    return geometry._compute_pixel_field(max_zenith)


@lru_cache(maxsize=2)
def _radial_field(geometry: FisheyeGeometry, max_zenith: float) -> tuple[Any, ...]:
    return geometry._compute_radial_field(max_zenith)


def clear_pixel_field_cache() -> None:
    """Forget cached pixel fields (frees memory; benchmarks use it to time a cold start)."""
    _pixel_field.cache_clear()
    _radial_field.cache_clear()
