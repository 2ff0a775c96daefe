"""Crowns from the crown's photograph (``[tree] photo``, :mod:`radtree.config.photo`): the
photo read once through :mod:`radtree.hemi`, its checks, its provenance, and the façade
photo's sky predicate that cuts the dome crowns.

Façade photo (``photo_direction = "facade"``): lens axis = façade normal n, taken at the dome
centre (the sensor circle's centre on the wall) looking out; photo angles are (angle from n,
angle around n clockwise from up as seen looking out, 90° = +u). A direction d = (u, n, z)
of the façade frame is sky where the photo shows sky there (:func:`facade_sky`).

Upward photo (``photo_direction = "upward"``): lens axis vertical; (zenith, compass azimuth)
(:mod:`radtree.trees.photo_fit` fits the free crowns to it).

Bad input gives one :class:`~radtree.errors.ConfigError` naming the field: a file that is not
an image or shows no fisheye circle, a ``mask`` that does not match the image circle the photo
shows (centre or radius off by more than :data:`MASK_TOLERANCE` of the radius), a lens that
does not reach 90° or is unknown, an upward photo where a façade photo is needed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from radtree.config import Tree
from radtree.config.photo import photo_of
from radtree.errors import ConfigError, RadtreeError
from radtree.fileio import file_sha256
from radtree.hemi import HemiConfig, HemiResult, get_lens
from radtree.hemi.lens import Projection, parse_polynomial
from radtree.hemi.mask import CircularMask, detect_circular_mask
from radtree.hemi.metrics import RingGrid

MASK_TOLERANCE = 0.05   # a given mask may differ from the detected image circle by 5 % of r
AXIS_OF = {"facade": "horizontal", "upward": "up"}


@dataclass(frozen=True)
class PhotoSource:
    """Where a crown's photo comes from: the file, lens, mask, direction and the field that
    named it (``tree.photo`` or ``tree.perforated.photo``)."""

    path: Path
    lens: str
    mask: tuple[float, float, float] | None
    direction: str
    field: str
    zenith_deg: float = 90.0

    @property
    def images(self) -> list[Path]:
        """The photo, or every JPEG/PNG/TIFF of the folder it names (sorted)."""
        if self.path.is_dir():
            from radtree.hemi.image import find_images

            found = find_images(self.path)
            if not found:
                raise photo_error(f"folder {self.path} holds no JPEG, PNG or TIFF photos",
                                  self.field)
            return found
        return [self.path]


def photo_source(tree: Tree) -> PhotoSource | None:
    """The crown's photo as configured (None without one)."""
    path, lens, mask, where = photo_of(tree)
    if path is None:
        return None
    direction = tree.photo_direction if where == "tree.photo" else "facade"
    return PhotoSource(path, lens, mask, direction, where, tree.photo_zenith_deg)


def lens_of(name: str, field: str = "tree.lens") -> Projection:
    """A lens by name (:func:`radtree.hemi.get_lens`) or ``poly:a1,a2,…`` (x = zenith/90°)."""
    try:
        text = str(name)
        lens = (parse_polynomial(text.split(":", 1)[1]) if text.lower().startswith("poly:")
                else get_lens(text))
    except ConfigError as exc:
        detail = str(exc).split("': ", 1)[-1]
        raise photo_error(f"{detail} (or poly:a1,a2,… with r/R = a1·x + a2·x² + …, "
                          "x = zenith/90°)", field) from None
    return lens


def _check_mask(image: Any, mask: CircularMask, field: str,
                key: tuple[str, float] | None = None) -> None:
    """The given mask against the image circle the photo shows (when one is detected; the
    circle found is remembered by ``key``, the file and its modification time)."""
    if key is not None and key in _CIRCLES:
        found = _CIRCLES[key]
    else:
        try:
            found = detect_circular_mask(image.brightness())
        except RadtreeError:
            found = None
        if key is not None:
            _CIRCLES[key] = found
    if found is None:
        return   # no detectable circle (dark canopy at the rim): trust the mask given
    off = math.hypot(found.cx - mask.cx, found.cy - mask.cy)
    if off > MASK_TOLERANCE * found.radius or abs(found.radius - mask.radius) > (
            MASK_TOLERANCE * found.radius):
        raise photo_error(
            f"mask [{mask.cx:g}, {mask.cy:g}, {mask.radius:g}] px does not match the image "
            f"circle of {image.name} (centre {found.cx:.0f}, {found.cy:.0f}, radius "
            f"{found.radius:.0f} px): give that circle, or leave mask out to detect it",
            field.rsplit(".", 1)[0] + ".mask")


#: the image circle detected in a photo (None: none detectable), by file and modification time
_CIRCLES: dict[tuple[str, float], CircularMask | None] = {}


@lru_cache(maxsize=16)
def _analysed(path: str, mtime: float, lens: str, mask: tuple[float, float, float] | None,
              axis: str, zenith_deg: float, field: str) -> HemiResult:
    from radtree.hemi.analyse import analyse_loaded
    from radtree.hemi.image import load_image

    p = Path(path)
    projection = lens_of(lens, field.rsplit(".", 1)[0] + ".lens")
    circle = CircularMask(*mask) if mask is not None else None
    try:
        image = load_image(p)
        if circle is not None:
            _check_mask(image, circle, field, (path, mtime))
        config = HemiConfig(lens=projection, mask=circle, axis=axis, outlines=False,
                            channel="luma" if image.is_gray else "blue",
                            grid=RingGrid(9, 8, 0.0, float(zenith_deg)))
        return analyse_loaded(image, config)
    except ConfigError as exc:
        if getattr(exc, "detail", None):
            raise
        raise photo_error(f"{exc} (the crown's photo)", field) from None
    except RadtreeError as exc:
        raise photo_error(f"{exc} (the crown's photo)", field) from None
    except OSError as exc:
        raise photo_error(f"cannot read {p.name} as an image ({exc})", field) from None


def photo_error(message: str, field: str) -> ConfigError:
    """A ConfigError naming ``field`` that remembers its bare message (``detail``)."""
    exc = ConfigError(message, field=field)
    exc.detail = message  # type: ignore[attr-defined]
    return exc


def with_source(exc: ConfigError, source: str | None) -> ConfigError:
    """The same error naming the project file too."""
    if exc.source or not source:
        return exc
    return ConfigError(getattr(exc, "detail", str(exc)), source=source, field=exc.field)


def analyse_photo(path: Path, src: PhotoSource, axis: str | None = None) -> HemiResult:
    """The photo analysed by :mod:`radtree.hemi` (9 rings of the analysed zenith range × 8
    segments), cached per file, its modification time and the settings."""
    if not path.is_file():
        raise photo_error(f"photo {path} not found", src.field)
    return _analysed(str(path.resolve()), path.stat().st_mtime, src.lens, src.mask,
                     axis or AXIS_OF[src.direction], src.zenith_deg, src.field)


def require_direction(src: PhotoSource, wanted: str, what: str) -> None:
    """One clear message when the photo's stated direction is not the one ``what`` needs."""
    if src.direction != wanted:
        article = "an" if wanted == "upward" else "a"
        raise photo_error(
            f"{what}: {article} {wanted} photo is needed but tree.photo_direction = "
            f"{src.direction!r} ({src.path.name}): "
            + ("the dome crowns are cut from a photo taken at the sensors looking out (lens "
               "axis = façade normal); set photo_direction = 'facade' or use form = 'free'"
               if wanted == "facade" else
               "free louvers crowns are fitted to photos taken under the crown looking up; "
               "set photo_direction = 'upward' or use form = 'dome'"),
            "tree.photo_direction")


def facade_sky(result: HemiResult):  # noqa: ANN201 - a predicate on façade-frame vectors
    """``is_sky(d)`` for unit vectors d (N, 3) of the façade frame (u, n, z), from a façade
    photo: angle from n and angle around n clockwise from up, 90° = +u."""
    predicate = result.sky_predicate(outside=False)

    def is_sky(d: np.ndarray) -> np.ndarray:
        d = np.asarray(d, float)
        theta = np.degrees(np.arccos(np.clip(d[:, 1], -1.0, 1.0)))
        psi = np.mod(np.degrees(np.arctan2(d[:, 0], d[:, 2])), 360.0)
        return np.asarray(predicate(theta, psi), bool)

    return is_sky


def provenance(src: PhotoSource, results: list[HemiResult], fitted: dict[str, Any] | None = None
               ) -> dict[str, Any]:
    """What made a photo-derived crown: each photo's file, sha256, lens, mask (given or
    detected), direction and hemi's figures, plus the fitted values."""
    photos = []
    for r in results:
        path = Path(r.image.path) if r.image.path is not None else src.path
        g = r.geometry
        photos.append({
            "file": str(path), "sha256": file_sha256(path) if path.is_file() else None,
            "lens": g.lens.describe(), "lens_setting": src.lens,
            "mask_px": [g.mask.cx, g.mask.cy, g.mask.radius],
            "mask_given": src.mask is not None, "direction": src.direction,
            "axis": g.axis, "zenith_range_deg": [0.0, src.zenith_deg],
            "threshold": r.classification.threshold,
            "openness": r.metrics.openness, "lai_eff": r.metrics.lai_eff,
            "ellipsoid_x": r.metrics.ellipsoid_x,
            "mean_tilt_deg": r.metrics.mean_tilt_deg})
    out: dict[str, Any] = {"field": src.field, "photos": photos}
    if fitted:
        out["fitted"] = fitted
    return out
