"""The pipeline for one photo: photo -> channel -> sky/canopy -> ring × segment gap
fractions -> metrics, gap outlines (:func:`analyse_image`, :class:`HemiResult`).

The batch over a folder and its output files are :mod:`radtree.hemi.batch`.
"""

from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from radtree.errors import ConfigError, RadtreeError

from .classify import Classification, ThresholdSpec, classify
from .geometry import AXES, FisheyeGeometry, PixelField
from .image import LoadedImage, channel_values, check_channel, check_gamma, load_image
from .lens import Projection
from .mask import CircularMask, detect_circular_mask, full_frame_mask, get_preset
from .metrics import DEFAULT_GAP_FLOOR, CanopyMetrics, GapTable, RingGrid, canopy_metrics, gap_table
from .outlines import (
    GapOutline,
    gap_polygons,
    outlines_geojson,
    trace_gaps,
)
from .predicate import SkyPredicate


@dataclass(frozen=True)
class HemiConfig:
    """Everything that controls the analysis of a photo (validated on creation).

    ``lens``/``mask`` left as None come from ``preset`` if one is named; otherwise the lens is
    equidistant and the mask is detected (circular images) or centred with the 90° circle at
    half the frame diagonal (``full_frame``). ``mirror`` None means: mirrored for upward photos,
    not for horizontal ones. ``north_deg``: where north (horizontal photos: world-up) lies in
    the image, degrees clockwise from image-up.
    """

    lens: Projection | None = None
    mask: CircularMask | None = None
    preset: str | None = None
    full_frame: bool = False
    channel: str = "blue"
    gamma: float = 2.2
    threshold: ThresholdSpec | str | float = ThresholdSpec()
    grid: RingGrid = RingGrid()
    axis: str = "up"
    north_deg: float = 0.0
    mirror: bool | None = None
    gap_floor: float = DEFAULT_GAP_FLOOR
    outlines: bool = True
    outline_tolerance_px: float = 1.0
    outline_min_area_px: float = 4.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "channel", check_channel(self.channel))
        object.__setattr__(self, "gamma", check_gamma(self.gamma))
        object.__setattr__(self, "threshold", ThresholdSpec.parse(self.threshold))
        if self.axis not in AXES:
            raise ConfigError(f"axis must be 'up' or 'horizontal', got '{self.axis}'", field="axis")
        if self.preset is not None:
            get_preset(self.preset)
        if not math.isfinite(float(self.north_deg)):
            raise ConfigError(f"north must be a finite angle, got {self.north_deg}", field="north")
        if not 0.0 < float(self.gap_floor) < 1.0:
            raise ConfigError(
                f"gap floor must be between 0 and 1 (exclusive), got {self.gap_floor}",
                field="gap_floor",
            )
        if not float(self.outline_tolerance_px) >= 0.0:
            raise ConfigError("outline tolerance must be >= 0 px", field="outline_tolerance")
        if not float(self.outline_min_area_px) >= 0.0:
            raise ConfigError("minimum gap area must be >= 0 px", field="min_gap_area")

    @property
    def resolved_lens(self) -> Projection:
        if self.lens is not None:
            return self.lens
        if self.preset is not None:
            return get_preset(self.preset).lens
        return Projection("equidistant")

    @property
    def resolved_mirror(self) -> bool:
        return (self.axis == "up") if self.mirror is None else bool(self.mirror)

    def geometry_for(self, image: LoadedImage) -> FisheyeGeometry:
        """Lens, mask and angle conventions for one image (detects the mask if needed)."""
        w, h = image.width, image.height
        mask = self.mask
        if mask is None and self.preset is not None:
            preset = get_preset(self.preset)
            preset.check_size(w, h, source=image.name)
            mask = preset.mask
        if mask is None:
            mask = full_frame_mask(w, h) if self.full_frame else detect_circular_mask(
                image.brightness(), source=image.name
            )
        if not self.full_frame:
            mask.check_inside(w, h, source=image.name)
        return FisheyeGeometry(
            w, h, mask, self.resolved_lens, axis=self.axis, north_deg=self.north_deg,
            mirror=self.resolved_mirror, full_frame=self.full_frame,
        )


@dataclass
class HemiResult:
    """The analysis of one photo. ``pixel_field``, ``values`` and ``classification.sky`` cover
    the bounding box ``pixel_field.rows`` × ``pixel_field.cols`` of the valid pixels."""

    name: str
    image: LoadedImage
    config: HemiConfig
    geometry: FisheyeGeometry
    pixel_field: PixelField
    values: NDArray[np.float32]
    classification: Classification
    table: GapTable
    metrics: CanopyMetrics
    outlines: list[GapOutline]
    timings: dict[str, float] = field(default_factory=dict)

    @property
    def stem(self) -> str:
        return Path(self.name).stem

    def sky_predicate(self, *, outside: bool = False) -> SkyPredicate:
        """Callable (zenith_deg, azimuth_deg) -> bool: is this direction sky in the photo?"""
        return SkyPredicate(
            self.classification.sky, self.pixel_field.rows, self.pixel_field.cols, self.geometry, outside
        )

    def gap_polygons(self, *, include_holes: bool = False) -> list[NDArray[np.float64]]:
        """Gap outlines as closed (n, 2) arrays of (zenith_deg, azimuth_deg)."""
        return gap_polygons(self.outlines, include_holes=include_holes)

    def geojson(self) -> dict[str, Any]:
        return outlines_geojson(
            self.outlines,
            self.geometry,
            image=self.name,
            properties={"threshold": self.classification.threshold, "channel": self.config.channel},
        )

    def summary_row(self) -> dict[str, Any]:
        g = self.geometry
        grid = self.config.grid
        return {
            "image": self.name,
            "threshold": self.classification.threshold,
            **self.metrics.as_dict(),
            "threshold_method": self.classification.method,
            "channel": self.config.channel,
            "gamma": self.config.gamma,
            "lens": g.lens.describe(),
            "mask_cx": g.mask.cx,
            "mask_cy": g.mask.cy,
            "mask_radius": g.mask.radius,
            "full_frame": g.full_frame,
            "axis": g.axis,
            "north_deg": g.north_deg,
            "mirror": g.mirror,
            "zenith_from": grid.zenith_start,
            "zenith_to": grid.zenith_end,
            "rings": grid.rings,
            "segments": grid.segments,
            "gap_floor": self.config.gap_floor,
            "pixels": int(self.table.pixels.sum()),
            "sky_pixels": int(self.table.sky_pixels.sum()),
            "gaps": len(self.outlines),
        }

    def ring_rows(self) -> list[dict[str, Any]]:
        grid = self.table.grid
        ze, ae = grid.ring_edges, grid.segment_edges
        omega = grid.cell_solid_angle()
        cosw = grid.cell_cosine_weight()
        has = ~np.isnan(self.table.gap)
        w_open = np.where(has, omega, 0.0) / omega[has].sum() if has.any() else omega * np.nan
        w_svf = np.where(has, cosw, 0.0) / cosw[has].sum() if has.any() else cosw * np.nan
        rt = self.classification.ring_thresholds
        rows = []
        for i in range(grid.rings):
            for j in range(grid.segments):
                rows.append(
                    {
                        "image": self.name,
                        "ring": i + 1,
                        "zenith_from": ze[i],
                        "zenith_to": ze[i + 1],
                        "segment": j + 1,
                        "azimuth_from": ae[j],
                        "azimuth_to": ae[j + 1],
                        "gap_fraction": self.table.gap[i, j],
                        "gap_fraction_cos": self.table.gap_cos[i, j],
                        "pixels": int(self.table.pixels[i, j]),
                        "sky_pixels": int(self.table.sky_pixels[i, j]),
                        "solid_angle_sr": omega[i, j],
                        "weight_openness": w_open[i, j],
                        "weight_svf": w_svf[i, j],
                        "threshold": rt[i] if rt is not None else self.classification.threshold,
                    }
                )
        return rows


def analyse_image(path: str | os.PathLike, config: HemiConfig | None = None) -> HemiResult:
    """Load and analyse one photo."""
    return analyse_loaded(load_image(path), config or HemiConfig())


def analyse_array(
    pixels: NDArray, config: HemiConfig | None = None, *, name: str = "array"
) -> HemiResult:
    """Analyse an in-memory image (H × W or H × W × 3; uint8, uint16, bool or float 0–1)."""
    from .image import from_array

    return analyse_loaded(from_array(pixels, name=name), config or HemiConfig())


def analyse_loaded(image: LoadedImage, config: HemiConfig) -> HemiResult:
    """Run the pipeline on a loaded image; errors name the image."""
    try:
        return _analyse(image, config)
    except RadtreeError as exc:
        if image.name in str(exc):
            raise
        raise RadtreeError(f"{image.name}: {exc}") from exc


def _analyse(image: LoadedImage, config: HemiConfig) -> HemiResult:
    t0 = time.perf_counter()
    geometry = config.geometry_for(image)
    pf = geometry.pixel_field()
    if int(pf.valid.sum()) < 1000:
        raise RadtreeError("fewer than 1000 pixels inside the mask; check --mask")
    t1 = time.perf_counter()
    values = channel_values(image, config.channel, config.gamma, rows=pf.rows, cols=pf.cols)
    cls = classify(
        values, pf.valid, config.threshold, zenith=pf.zenith, ring_edges=config.grid.ring_edges
    )
    t2 = time.perf_counter()
    table = gap_table(cls.sky, pf.valid, pf.zenith, pf.azimuth, pf.weight, config.grid)
    if int(table.pixels.sum()) == 0:
        raise RadtreeError("no pixels in the analysed zenith range; check --mask and --zenith")
    metrics = canopy_metrics(table, gap_floor=config.gap_floor, upward=config.axis == "up")
    t3 = time.perf_counter()
    outlines: list[GapOutline] = []
    if config.outlines:
        outlines = trace_gaps(
            cls.sky, field_=pf, geometry=geometry, tolerance_px=config.outline_tolerance_px,
            min_area_px=config.outline_min_area_px,
        )
    t4 = time.perf_counter()
    timings = {"geometry": t1 - t0, "classify": t2 - t1, "metrics": t3 - t2, "outlines": t4 - t3}
    return HemiResult(
        image.name, image, config, geometry, pf, values, cls, table, metrics, outlines, timings
    )
