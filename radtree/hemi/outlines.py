"""Sky-gap outlines: classified sky -> polygons in angular coordinates -> GeoJSON.

The sky pixels (4-connected regions) are traced with ``skimage.measure.find_contours`` at the
0.5 level between sky (1) and canopy/outside (0), simplified in pixel space with
``skimage.measure.approximate_polygon`` (tolerance in pixels; rings of up to 48 traced vertices,
gaps about 10 px across, are kept as traced), and every vertex is converted
to (zenith, azimuth) in degrees with the photo's lens, mask, north and mirror settings.
Each gap is one polygon: its outer ring plus the rings of canopy islands inside it (holes).
Gaps and holes smaller than ``min_area_px`` pixels are dropped (holes are then filled).

Python API (for the perforated crown model): :func:`trace_gaps` returns :class:`GapOutline`
objects; ``GapOutline.exterior``/``holes`` are closed (n, 2) arrays of (zenith_deg,
azimuth_deg) with azimuth in [0, 360); ``GapOutline.vectors()`` gives unit world vectors.
For horizontal-axis photos the pair is (angle from the lens axis, angle around the axis).

GeoJSON (:func:`outlines_geojson`): a FeatureCollection of Polygon features with coordinates
``[azimuth_deg, zenith_deg]``. Azimuths are unwrapped along each ring (consecutive vertices
never jump by 360°, so values can leave [0, 360)); a ring that winds around the zenith (the
image centre) is closed along the zenith line (zenith = 0) so that it is a proper polygon in
the (azimuth, zenith) plane. Exterior rings are counter-clockwise and holes clockwise in that
plane (RFC 7946). Properties: image, gap (id), solid_angle_sr, pixels, holes, contains_zenith.
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from radtree.fileio import write_text

from .directions import photo_to_world
from .geometry import FisheyeGeometry, PixelField

SIMPLIFY_MIN_VERTICES = 48  # shorter rings (gaps up to ~10 px across) are kept as traced


@dataclass(frozen=True)
class GapOutline:
    """One sky gap: outer ring and holes as closed (n, 2) arrays of (zenith, azimuth) degrees."""

    exterior: NDArray[np.float64]
    holes: tuple[NDArray[np.float64], ...] = ()
    solid_angle_sr: float = 0.0
    pixels: int = 0
    contains_zenith: bool = False
    axis: str = "up"
    exterior_px: NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 2)), repr=False)
    holes_px: tuple[NDArray[np.float64], ...] = field(default=(), repr=False)

    def rings(self) -> list[NDArray[np.float64]]:
        """Exterior followed by the holes."""
        return [self.exterior, *self.holes]

    def vectors(self, facade_azimuth: float | None = None) -> list[NDArray[np.float64]]:
        """World unit vectors (n, 3) of each ring (x east, y north, z up).

        Horizontal-axis photos need ``facade_azimuth`` (compass direction of the lens axis).
        """
        return [
            photo_to_world(r[:, 0], r[:, 1], axis=self.axis, facade_azimuth=facade_azimuth)
            for r in self.rings()
        ]


def _winds_around(xy: NDArray[np.float64], cx: float, cy: float) -> bool:
    """Whether the closed ring ``xy`` (pixels) encloses the point (cx, cy)."""
    lo, hi = xy.min(axis=0), xy.max(axis=0)
    if not (lo[0] <= cx <= hi[0] and lo[1] <= cy <= hi[1]):
        return False
    from skimage.measure import points_in_poly  # scikit-image: imported where used (0.7 s)

    return bool(points_in_poly(np.array([[cx, cy]]), xy)[0])


def _contains_centre(
    ext: NDArray[np.float64], holes: list[NDArray[np.float64]], cx: float, cy: float
) -> bool:
    return _winds_around(ext, cx, cy) and not any(_winds_around(h, cx, cy) for h in holes)


def _signed_area(xy: NDArray[np.float64]) -> float:
    """Shoelace area of a ring (closed or not); positive when counter-clockwise in x-y."""
    x, y = xy[:, 0], xy[:, 1]
    inner = float(np.dot(x[:-1], y[1:]) - np.dot(x[1:], y[:-1]))
    return 0.5 * (inner + float(x[-1] * y[0] - x[0] * y[-1]))


def _contour_label(c: NDArray[np.float64], padded: NDArray[np.bool_], labels: NDArray) -> int:
    """Label of the sky region a contour borders (contour vertices sit between two pixels)."""
    r, k = c[0]
    if abs(r - round(r)) < 1e-6:
        cand = [(int(round(r)), int(math.floor(k))), (int(round(r)), int(math.ceil(k)))]
    else:
        cand = [(int(math.floor(r)), int(round(k))), (int(math.ceil(r)), int(round(k)))]
    for i, j in cand:
        if padded[i, j]:
            return int(labels[i, j])
    return 0


def trace_gaps(
    sky: NDArray[np.bool_],
    *,
    field_: PixelField,
    geometry: FisheyeGeometry,
    tolerance_px: float = 1.0,
    min_area_px: float = 4.0,
) -> list[GapOutline]:
    """Vectorise the sky gaps of a classified photo, largest first.

    ``sky`` covers ``field_`` (the bounding box of the valid pixels). ``tolerance_px`` is the
    simplification tolerance (0 keeps every contour vertex).
    """
    regions = _sky_regions(sky, field_, min_area_px)
    if regions is None:
        return []
    sizes, solid, groups = regions
    gaps = _gap_rings(groups, field_, tolerance_px=tolerance_px, min_area_px=min_area_px)
    if not gaps:
        return []
    all_xy, angles = _ring_angles(gaps, geometry)
    out: list[GapOutline] = []
    k = 0
    for lab, ext_xy, holes_xy in gaps:
        rings_xy, rings_ang = [], []
        for r in (ext_xy, *holes_xy):
            rings_xy.append(all_xy[k : k + len(r)])
            rings_ang.append(angles[k : k + len(r)])
            k += len(r)
        out.append(
            GapOutline(
                exterior=rings_ang[0],
                holes=tuple(rings_ang[1:]),
                solid_angle_sr=float(solid[lab]),
                pixels=int(sizes[lab]),
                contains_zenith=_contains_centre(rings_xy[0], rings_xy[1:], geometry.mask.cx,
                                                 geometry.mask.cy),
                axis=geometry.axis,
                exterior_px=rings_xy[0],
                holes_px=tuple(rings_xy[1:]),
            )
        )
    out.sort(key=lambda g: -g.solid_angle_sr)
    return out


#: a sky region's contours: (|area| in px², contour in (row, col) index space)
_Rings = list[tuple[float, NDArray[np.float64]]]


def _sky_regions(sky: NDArray[np.bool_], field_: PixelField, min_area_px: float
                 ) -> tuple[NDArray, NDArray, dict[int, _Rings]] | None:
    """The 4-connected sky regions: pixels and solid angle (sr) per label, and the contours
    of every region of at least ``min_area_px`` pixels; None when there is no sky."""
    from skimage.measure import find_contours, label

    padded = np.pad(sky & field_.valid, 1)
    labels = label(padded, connectivity=1)
    n_labels = int(labels.max())
    if n_labels == 0:
        return None
    sizes = np.bincount(labels.ravel(), minlength=n_labels + 1)
    weights = np.pad(field_.weight, 1)
    solid = np.bincount(labels.ravel(), weights=weights.ravel(), minlength=n_labels + 1)
    groups: dict[int, _Rings] = {}
    for c in find_contours(padded.astype(np.float32), 0.5):
        if len(c) < 4:
            continue
        lab = _contour_label(c, padded, labels)
        if lab == 0 or sizes[lab] < min_area_px:
            continue
        groups.setdefault(lab, []).append((abs(_signed_area(c)), c))
    return sizes, solid, groups


def _gap_rings(groups: dict[int, _Rings], field_: PixelField, *, tolerance_px: float,
               min_area_px: float
               ) -> list[tuple[int, NDArray[np.float64], list[NDArray[np.float64]]]]:
    """Per region, its largest contour (the exterior) and its holes of at least
    ``min_area_px``, simplified and in image pixel coordinates (x, y)."""
    from skimage.measure import approximate_polygon

    # pixel coordinates (x, y) of contour vertices: index space has pixel centres at integers
    x0 = field_.cols.start - 1 + 0.5
    y0 = field_.rows.start - 1 + 0.5

    def to_xy(c: NDArray[np.float64]) -> NDArray[np.float64]:
        if tolerance_px > 0 and len(c) > SIMPLIFY_MIN_VERTICES:
            c = approximate_polygon(c, tolerance_px)
        return c[:, ::-1] + (x0, y0)  # (row, col) -> (x, y)

    gaps: list[tuple[int, NDArray[np.float64], list[NDArray[np.float64]]]] = []
    for lab, rings in groups.items():
        rings.sort(key=lambda t: -t[0])
        ext_xy = to_xy(rings[0][1])
        if len(ext_xy) < 4:
            continue
        holes_xy = [to_xy(c) for area, c in rings[1:] if area >= min_area_px]
        gaps.append((lab, ext_xy, [h for h in holes_xy if len(h) >= 4]))
    return gaps


def _ring_angles(gaps: list[tuple[int, NDArray[np.float64], list[NDArray[np.float64]]]],
                 geometry: FisheyeGeometry) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Every ring vertex, rings in order: pixel (x, y) pulled onto the image circle where
    outside it (the rim is 90°), and its (zenith, azimuth) in degrees, in one vectorised
    call of the lens model."""
    cx, cy, radius = geometry.mask.cx, geometry.mask.cy, geometry.mask.radius
    all_xy = np.concatenate([r for _, e, hs in gaps for r in (e, *hs)])
    d = all_xy - (cx, cy)
    dist = np.hypot(d[:, 0], d[:, 1])
    scale = np.where(dist > radius, radius / np.maximum(dist, 1e-12), 1.0)  # rim onto 90°
    all_xy = (cx, cy) + d * scale[:, None]
    zen, azi = geometry.to_direction(all_xy[:, 0], all_xy[:, 1])
    return all_xy, np.c_[zen, azi]


def gap_polygons(outlines: list[GapOutline], *, include_holes: bool = False) -> list[NDArray]:
    """The gap outlines as a list of closed (n, 2) arrays of (zenith_deg, azimuth_deg).

    Exteriors only by default; with ``include_holes`` the hole rings follow (read the list
    with the even–odd rule).
    """
    rings: list[NDArray] = []
    for g in outlines:
        rings.append(g.exterior)
        if include_holes:
            rings.extend(g.holes)
    return rings


# -- GeoJSON ---------------------------------------------------------------------------------
def _ring_coordinates(
    angles: NDArray[np.float64], px: NDArray[np.float64], centre: NDArray[np.float64], exterior: bool
) -> list[list[float]]:
    az = np.unwrap(angles[:, 1], period=360.0)
    az = az - 360.0 * math.floor(az[0] / 360.0)
    zen = angles[:, 0]
    winds = _winds_around(px, float(centre[0, 0]), float(centre[0, 1]))
    if winds:  # close along the zenith line: a proper polygon in the (azimuth, zenith) plane
        az = np.r_[az, az[-1], az[0]]
        zen = np.r_[zen, 0.0, 0.0]
    xy = np.c_[az, zen]
    if not np.allclose(xy[0], xy[-1]):
        xy = np.r_[xy, xy[:1]]
    ccw = _signed_area(xy[:-1]) > 0
    if ccw != exterior:
        xy = xy[::-1]
    return [[round(float(a), 4), round(float(z), 4)] for a, z in xy]


def outlines_geojson(
    outlines: list[GapOutline],
    geometry: FisheyeGeometry,
    *,
    image: str,
    properties: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """A GeoJSON FeatureCollection of the gaps (coordinates [azimuth_deg, zenith_deg])."""
    centre = np.array([[geometry.mask.cx, geometry.mask.cy]])
    features = []
    for i, g in enumerate(outlines):
        rings = [_ring_coordinates(g.exterior, g.exterior_px, centre, True)]
        rings += [_ring_coordinates(h, hp, centre, False) for h, hp in zip(g.holes, g.holes_px)]
        features.append(
            {
                "type": "Feature",
                "geometry": {"type": "Polygon", "coordinates": rings},
                "properties": {
                    "image": image,
                    "gap": i,
                    "solid_angle_sr": round(g.solid_angle_sr, 8),
                    "pixels": g.pixels,
                    "holes": len(g.holes),
                    "contains_zenith": g.contains_zenith,
                },
            }
        )
    meta = {
        "coordinates": (
            "[azimuth_deg, zenith_deg]; azimuth clockwise from north"
            if geometry.axis == "up"
            else "[angle around the lens axis (clockwise from up, looking out), angle from the axis]"
        ),
        **{k: v for k, v in geometry.describe().items()},
        **(properties or {}),
    }
    return {"type": "FeatureCollection", "radtree": meta, "features": features}


def merge_collections(collections: list[dict[str, Any]]) -> dict[str, Any]:
    """One FeatureCollection holding the features of several (each feature names its image)."""
    feats = [f for c in collections for f in c["features"]]
    meta = collections[0]["radtree"] if collections else {}
    return {"type": "FeatureCollection", "radtree": {"coordinates": meta.get("coordinates", "")},
            "features": feats}


def write_geojson(path: str | os.PathLike, collection: dict[str, Any]) -> Path:
    """Write a FeatureCollection atomically (compact JSON)."""
    return write_text(path, json.dumps(collection, separators=(",", ":")) + "\n")
