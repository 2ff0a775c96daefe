"""Sky / canopy classification of the processed channel: a pixel is sky if its value > threshold.

Methods (thresholds on the 0–255 scale of the processed channel, i.e. after gamma):

* ``otsu`` (default): Otsu's between-class-variance threshold over all valid pixels
  (skimage.filters.threshold_otsu).
* ``isodata``: Ridler–Calvard iterative intermeans (skimage.filters.threshold_isodata).
* a number: a manual threshold.
* ``zonal``: one Otsu threshold per zenith ring of the analysis grid (pixels outside the
  analysed range use the nearest ring's threshold); the reported threshold is the
  pixel-weighted mean of the ring thresholds. Rings whose values do not vary fall back to the
  global Otsu threshold.

An image with only two distinct values inside the mask (an already binary image) is split
midway between them by every automatic method; an image with a single value cannot be
thresholded automatically (error: give a number).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from radtree.errors import ConfigError, RadtreeError

METHODS = ("otsu", "isodata", "zonal", "manual")


@dataclass(frozen=True)
class ThresholdSpec:
    """How to threshold: ``method`` in otsu/isodata/zonal/manual; ``value`` for manual (0–255)."""

    method: str = "otsu"
    value: float | None = None

    def __post_init__(self) -> None:
        if self.method not in METHODS:
            raise ConfigError(
                f"unknown threshold method '{self.method}'; expected otsu, isodata, zonal or a "
                "number 0–255",
                field="threshold",
            )
        if self.method == "manual":
            if self.value is None or not math.isfinite(self.value) or not 0 <= self.value <= 255:
                raise ConfigError(
                    f"a manual threshold must be a number from 0 to 255, got {self.value}",
                    field="threshold",
                )
        elif self.value is not None:
            raise ConfigError(f"threshold method '{self.method}' takes no value", field="threshold")

    @classmethod
    def parse(cls, text: str | float | ThresholdSpec) -> ThresholdSpec:
        """``"otsu"``, ``"isodata"``, ``"zonal"`` or a number (manual threshold, 0–255)."""
        if isinstance(text, ThresholdSpec):
            return text
        if isinstance(text, (int, float)):
            return cls("manual", float(text))
        t = str(text).strip().lower()
        if t in ("otsu", "isodata", "zonal"):
            return cls(t)
        try:
            value = float(t)
        except ValueError:
            raise ConfigError(
                f"unknown threshold '{text}'; expected otsu, isodata, zonal or a number 0–255",
                field="threshold",
            ) from None
        return cls("manual", value)

    def label(self) -> str:
        return f"manual {self.value:g}" if self.method == "manual" else self.method


@dataclass(frozen=True)
class Classification:
    """``sky`` (bool, same shape as the values; False outside the valid pixels) and thresholds."""

    sky: NDArray[np.bool_]
    threshold: float
    method: str
    ring_thresholds: NDArray[np.float64] | None = None


def _auto_threshold(values: NDArray[np.float32], method: str) -> float:
    lo, hi = float(values.min()), float(values.max())
    if lo == hi:
        raise RadtreeError(
            f"every pixel inside the mask has the same value ({lo:.1f}): an automatic threshold "
            "is undefined; give --threshold NUMBER"
        )
    if not np.any((values != lo) & (values != hi)):  # already binary
        return 0.5 * (lo + hi)
    from skimage.filters import threshold_isodata, threshold_otsu  # here: ~0.5 s to import

    if method == "isodata":
        return float(threshold_isodata(values))
    return float(threshold_otsu(values))


def classify(
    values: NDArray[np.float32],
    valid: NDArray[np.bool_],
    spec: ThresholdSpec | str | float = ThresholdSpec(),
    *,
    zenith: NDArray[np.floating] | None = None,
    ring_edges: NDArray[np.float64] | None = None,
) -> Classification:
    """Threshold ``values`` (0–255) over ``valid`` pixels; zonal needs ``zenith`` and ``ring_edges``."""
    spec = ThresholdSpec.parse(spec)
    inside = values[valid]
    if inside.size == 0:
        raise RadtreeError("no valid pixels inside the mask")
    if spec.method == "manual":
        assert spec.value is not None
        return Classification(valid & (values > spec.value), float(spec.value), spec.label())
    if spec.method in ("otsu", "isodata"):
        t = _auto_threshold(inside, spec.method)
        return Classification(valid & (values > t), t, spec.method)
    if zenith is None or ring_edges is None:
        raise ConfigError("zonal thresholding needs the zenith angles and ring edges")
    global_t = _auto_threshold(inside, "otsu")
    n = len(ring_edges) - 1
    z = np.where(valid, zenith, 0.0)
    ring = np.clip(np.searchsorted(ring_edges, z, side="right") - 1, 0, n - 1)
    thresholds = np.full(n, global_t)
    ring_v = ring[valid]
    order = np.argsort(ring_v, kind="stable")
    counts = np.bincount(ring_v, minlength=n)
    groups = np.split(inside[order], np.cumsum(counts)[:-1])
    for i, v in enumerate(groups):
        if v.size >= 16 and float(v.min()) < float(v.max()):
            thresholds[i] = _auto_threshold(v, "otsu")
    sky = valid & (values > thresholds[ring])
    mean_t = float(np.average(thresholds, weights=counts)) if counts.sum() > 0 else global_t
    return Classification(sky, mean_t, "zonal", thresholds)
