"""Hemispherical (fisheye) photo analysis: sky/canopy classification, gap fraction, openness,
sky view factor, DIFN, LAI, leaf angle, and the sky-gap outlines used by the perforated crown.

Conventions: angles in degrees; azimuth clockwise from north (compass); image pixels x right,
y down from the top-left corner (pixel centres at +0.5); the mask radius is the 90° circle;
upward photos have image north up by default and are east–west mirrored (east appears to the
left of north). Horizontal-axis photos (taken from a façade looking out) use (angle from the
lens axis, angle around the axis clockwise from up) instead of (zenith, azimuth); see
:mod:`radtree.hemi.geometry` and :mod:`radtree.hemi.directions`.

Main entry points::

    result = analyse_image("photo.jpg", HemiConfig(preset="coolpix4500-fce8"))
    result.metrics.openness, result.metrics.svf, result.metrics.lai_eff
    is_sky = result.sky_predicate()             # is_sky(zenith_deg, azimuth_deg) -> bool array
    rings = result.gap_polygons()               # [(n, 2) arrays of (zenith_deg, azimuth_deg)]
    is_sky = gap_mask_function("photo.jpg", HemiConfig(...))
    image = render_fisheye(lambda z, a: z < 30, 2000, "equidistant")   # synthetic test image
"""

from __future__ import annotations

import os

import numpy as np
from numpy.typing import NDArray

from .analyse import HemiConfig, HemiResult, analyse_array, analyse_image
from .batch import run_batch
from .classify import Classification, ThresholdSpec, classify
from .directions import horizontal_to_world, photo_to_world, up_to_world, world_to_horizontal
from .geometry import FisheyeGeometry, PixelField
from .image import channel_values, load_image
from .lens import LENS_PRESETS, Projection, get_lens, polynomial_lens
from .mask import CAMERA_PRESETS, CircularMask, detect_circular_mask, get_preset
from .metrics import CanopyMetrics, GapTable, RingGrid, canopy_metrics, gap_table
from .outlines import GapOutline, gap_polygons, outlines_geojson, trace_gaps
from .predicate import SkyPredicate
from .synthetic import poisson_canopy, render_fisheye, render_geometry, save_png


def gap_mask_function(
    source: str | os.PathLike | HemiResult, config: HemiConfig | None = None, *,
    outside: bool = False,
) -> SkyPredicate:
    """A sky predicate ``f(zenith_deg, azimuth_deg) -> bool array`` for a photo or a result.

    ``source`` is an image path (analysed with ``config``) or an existing :class:`HemiResult`.
    Directions the photo does not cover return ``outside``.
    """
    result = source if isinstance(source, HemiResult) else analyse_image(
        source, config or HemiConfig()
    )
    return result.sky_predicate(outside=outside)


def gap_outlines(
    source: str | os.PathLike | HemiResult, config: HemiConfig | None = None, *,
    include_holes: bool = False,
) -> list[NDArray[np.float64]]:
    """The sky-gap outlines of a photo as closed (n, 2) arrays of (zenith_deg, azimuth_deg)."""
    result = source if isinstance(source, HemiResult) else analyse_image(
        source, config or HemiConfig()
    )
    return result.gap_polygons(include_holes=include_holes)


__all__ = [
    "CAMERA_PRESETS", "LENS_PRESETS", "CanopyMetrics", "CircularMask", "Classification",
    "FisheyeGeometry", "GapOutline", "GapTable", "HemiConfig", "HemiResult", "PixelField",
    "Projection", "RingGrid", "SkyPredicate", "ThresholdSpec", "analyse_array", "analyse_image",
    "canopy_metrics", "channel_values", "classify", "detect_circular_mask", "gap_mask_function",
    "gap_outlines", "gap_polygons", "gap_table", "get_lens", "get_preset", "horizontal_to_world",
    "load_image", "outlines_geojson", "photo_to_world", "poisson_canopy", "polynomial_lens",
    "render_fisheye", "render_geometry", "run_batch", "save_png", "trace_gaps", "up_to_world",
    "world_to_horizontal",
]
