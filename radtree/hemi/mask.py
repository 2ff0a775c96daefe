"""The circular image mask (centre and 90° radius, pixels), its automatic detection, camera presets.

Pixel coordinates: x to the right, y down, in pixels from the top-left corner of the image;
pixel (row i, column j) covers [j, j+1) × [i, i+1), so its centre is (j + 0.5, i + 0.5) and the
exact centre of a W × H image is (W/2, H/2). The mask radius is the radius of the 90° circle
(the horizon of an upward photo).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from radtree.errors import ConfigError, RadtreeError

from .lens import Projection, get_lens

MIN_RADIUS_PX = 32


@dataclass(frozen=True)
class CircularMask:
    """Circle of the 90° zenith angle: centre (cx, cy) and radius, all in pixels."""

    cx: float
    cy: float
    radius: float

    def __post_init__(self) -> None:
        for name in ("cx", "cy", "radius"):
            value = getattr(self, name)
            if not isinstance(value, (int, float, np.floating, np.integer)) or not math.isfinite(
                float(value)
            ):
                raise ConfigError(f"mask {name} must be a finite number, got {value!r}", field="mask")
            object.__setattr__(self, name, float(value))
        if self.radius < MIN_RADIUS_PX:
            raise ConfigError(
                f"mask radius {self.radius:g} px is too small (need at least {MIN_RADIUS_PX} px)",
                field="mask",
            )

    def check_inside(self, width: int, height: int, *, source: str = "", tolerance: float = 1.0) -> None:
        """Raise if the circle does not lie inside a ``width`` × ``height`` image."""
        left, right = self.cx - self.radius, self.cx + self.radius
        top, bottom = self.cy - self.radius, self.cy + self.radius
        if left < -tolerance or top < -tolerance or right > width + tolerance or bottom > height + tolerance:
            raise ConfigError(
                f"mask centre ({self.cx:g}, {self.cy:g}) radius {self.radius:g} px reaches outside "
                f"the {width}×{height} px image (x {left:g}..{right:g}, y {top:g}..{bottom:g}); "
                "check --mask, or use --full-frame if the image circle is cropped by the frame",
                source=source or None,
                field="mask",
            )

    def as_text(self) -> str:
        return f"{self.cx:g},{self.cy:g},{self.radius:g}"


def parse_mask(text: str) -> CircularMask:
    """Parse ``"CX,CY,R"`` (pixels) into a :class:`CircularMask`."""
    parts = [p.strip() for p in str(text).split(",")]
    try:
        values = [float(p) for p in parts]
    except ValueError:
        values = []
    if len(values) != 3:
        raise ConfigError(
            f"cannot read mask '{text}': expected CX,CY,R in pixels, e.g. 1136,852,754",
            field="mask",
        )
    return CircularMask(*values)


def full_frame_mask(width: int, height: int, radius: float | None = None) -> CircularMask:
    """Mask of a full-frame fisheye: centre of the frame, 90° circle at half the diagonal."""
    r = float(radius) if radius is not None else 0.5 * math.hypot(width, height)
    return CircularMask(width / 2.0, height / 2.0, r)


@dataclass(frozen=True)
class CameraPreset:
    """A camera + converter combination: lens projection, mask and expected image size."""

    name: str
    lens: Projection
    mask: CircularMask
    width: int
    height: int
    note: str = ""

    def check_size(self, width: int, height: int, *, source: str = "") -> None:
        if (width, height) != (self.width, self.height):
            raise ConfigError(
                f"preset '{self.name}' is for {self.width}×{self.height} px images, this image is "
                f"{width}×{height} px; give --lens and --mask instead",
                source=source or None,
                field="preset",
            )


CAMERA_PRESETS: dict[str, CameraPreset] = {
    "coolpix4500-fce8": CameraPreset(
        "coolpix4500-fce8",
        get_lens("FC-E8"),
        CircularMask(1136.0, 852.0, 754.0),
        2272,
        1704,
        "Nikon Coolpix 4500 + FC-E8 (mask as published with hemispheR's camera list)",
    ),
}


def get_preset(name: str) -> CameraPreset:
    key = str(name).strip().lower().replace("_", "-").replace("+", "-")
    if key not in CAMERA_PRESETS:
        raise ConfigError(
            f"unknown camera preset '{name}'; known presets: {', '.join(CAMERA_PRESETS)}",
            field="preset",
        )
    return CAMERA_PRESETS[key]


def detect_circular_mask(brightness: NDArray, *, source: str = "") -> CircularMask:
    """Find the image circle of a circular fisheye photo.

    ``brightness`` is a 2-D array on the 0–255 scale (e.g. the maximum of R, G, B). Pixels
    brighter than a small level count as "inside"; the outermost inside pixel of every row and
    column is an edge point, and a circle is fitted to the edge points with RANSAC
    (skimage.measure). The detected radius is the visible image circle, taken to be the 90°
    circle (true for 180° lenses; give the mask explicitly for wider lenses or when dark canopy
    at the horizon hides the circle's edge).
    """
    where = f"{source}: " if source else ""
    v = np.asarray(brightness, dtype=np.float32)
    h, w = v.shape
    corner = max(4, min(h, w) // 20)
    corners = np.concatenate(
        [v[:corner, :corner].ravel(), v[:corner, -corner:].ravel(), v[-corner:, :corner].ravel(),
         v[-corner:, -corner:].ravel()]
    )
    dark_level = max(12.0, float(np.percentile(corners, 95)) + 8.0)
    if np.mean(corners > dark_level) > 0.05 or float(np.median(corners)) > 40:
        raise RadtreeError(
            f"{where}no dark border around the image: this does not look like a circular "
            "fisheye photo; give --mask CX,CY,R, a --preset, or --full-frame"
        )
    inside = _drop_specks(v > dark_level, min_pixels=64)
    rows = np.flatnonzero(inside.any(axis=1))
    cols = np.flatnonzero(inside.any(axis=0))
    if rows.size < 16 or cols.size < 16:
        raise RadtreeError(f"{where}the image is dark everywhere: no image circle found")
    left = inside[rows].argmax(axis=1)
    right = w - 1 - inside[rows, ::-1].argmax(axis=1)
    top = inside[:, cols].argmax(axis=0)
    bottom = h - 1 - inside[::-1, cols].argmax(axis=0)
    pts = np.concatenate(
        [
            np.c_[left + 0.0, rows + 0.5],
            np.c_[right + 1.0, rows + 0.5],
            np.c_[cols + 0.5, top + 0.0],
            np.c_[cols + 0.5, bottom + 1.0],
        ]
    ).astype(np.float64)
    from skimage.measure import CircleModel, ransac  # here: ~0.4 s to import

    model, inliers = ransac(
        pts, CircleModel, min_samples=3, residual_threshold=2.5, max_trials=500, rng=0
    )
    if model is None or inliers is None:
        raise RadtreeError(f"{where}could not fit a circle to the image edge; give --mask CX,CY,R")
    share = float(np.mean(inliers))
    cx, cy, radius = _circle_params(model)
    if share < 0.5 or radius < max(MIN_RADIUS_PX, 0.2 * min(h, w)):
        raise RadtreeError(
            f"{where}could not detect the image circle reliably (only {share:.0%} of edge points "
            f"lie on one circle, r = {radius:.0f} px); its edge may be hidden by dark canopy: "
            "give --mask CX,CY,R or a --preset"
        )
    if cx - radius < -0.02 * radius or cy - radius < -0.02 * radius or cx + radius > w * 1.02 or (
        cy + radius > h * 1.02
    ):
        raise RadtreeError(
            f"{where}the detected image circle (centre {cx:.0f},{cy:.0f}, r {radius:.0f} px) is "
            "cropped by the frame; use --full-frame with --mask CX,CY,R"
        )
    return CircularMask(cx, cy, radius)


def _drop_specks(binary: NDArray[np.bool_], *, min_pixels: int) -> NDArray[np.bool_]:
    """Remove connected specks (noise, hot pixels) smaller than ``min_pixels``."""
    from skimage.measure import label

    labels = label(binary, connectivity=2)
    sizes = np.bincount(labels.ravel())
    keep = sizes >= min_pixels
    keep[0] = False
    return keep[labels]


def _circle_params(model: Any) -> tuple[float, float, float]:
    """(cx, cy, r) of a fitted ``skimage.measure.CircleModel``."""
    center = getattr(model, "center", None)
    if center is not None:  # scikit-image >= 0.26
        return float(center[0]), float(center[1]), float(model.radius)
    xc, yc, r = model.params  # older scikit-image
    return float(xc), float(yc), float(r)
