"""Synthetic binary fisheye images from a sky predicate, for checks with known answers.

``render_fisheye(predicate, size, projection)`` evaluates ``predicate(zenith_deg, azimuth_deg)``
(NumPy arrays in, booleans out; True = sky) at every pixel centre inside the 90° circle and
returns a uint8 image: 255 for sky, 0 for canopy and for everything outside the circle. The
default mask is centred in the frame with radius min(width, height) / 2 (see
:func:`default_mask`); the same geometry (lens, north, mirror, axis) is what the analysis
uses, so an analysis of the rendered image measures the predicate's sky.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from PIL import Image

from radtree.errors import ConfigError
from radtree.fileio import atomic_path

from .geometry import FisheyeGeometry
from .lens import Projection, get_lens
from .mask import CircularMask

SkyFunction = Callable[[NDArray[np.float64], NDArray[np.float64]], NDArray[np.bool_]]


def _size(size: int | tuple[int, int]) -> tuple[int, int]:
    if isinstance(size, (int, np.integer)):
        return int(size), int(size)
    w, h = size
    return int(w), int(h)


def default_mask(size: int | tuple[int, int]) -> CircularMask:
    """Mask used by :func:`render_fisheye` by default: frame centre, radius min(W, H) / 2."""
    w, h = _size(size)
    return CircularMask(w / 2.0, h / 2.0, min(w, h) / 2.0)


def render_geometry(
    size: int | tuple[int, int],
    projection: str | Projection = "equidistant",
    *,
    mask: CircularMask | None = None,
    axis: str = "up",
    north_deg: float = 0.0,
    mirror: bool | None = None,
    full_frame: bool = False,
) -> FisheyeGeometry:
    """The geometry :func:`render_fisheye` uses (and an analysis of its output should use)."""
    w, h = _size(size)
    lens = projection if isinstance(projection, Projection) else get_lens(projection)
    return FisheyeGeometry(
        w,
        h,
        mask or default_mask((w, h)),
        lens,
        axis=axis,
        north_deg=north_deg,
        mirror=(axis == "up") if mirror is None else mirror,
        full_frame=full_frame,
    )


def render_fisheye(
    predicate: SkyFunction,
    size: int | tuple[int, int] = 2000,
    projection: str | Projection = "equidistant",
    **geometry_options: object,
) -> NDArray[np.uint8]:
    """Render a binary fisheye image (H × W uint8: 255 sky, 0 canopy/outside) of ``predicate``.

    ``size`` is the side (square) or (width, height) in pixels; ``geometry_options`` go to
    :func:`render_geometry` (mask, axis, north_deg, mirror, full_frame).
    """
    geometry = render_geometry(size, projection, **geometry_options)  # type: ignore[arg-type]
    field = geometry.pixel_field()
    z = field.zenith[field.valid].astype(np.float64)
    a = field.azimuth[field.valid].astype(np.float64)
    sky = np.asarray(predicate(z, a), dtype=bool)
    if sky.shape != z.shape:
        raise ConfigError(
            f"the sky predicate returned shape {sky.shape} for {z.shape} directions; it must "
            "return one boolean per direction"
        )
    image = np.zeros((geometry.height, geometry.width), dtype=np.uint8)
    box = image[field.rows, field.cols]
    box[field.valid] = np.where(sky, 255, 0).astype(np.uint8)
    return image


def save_png(image: NDArray[np.uint8], path: str | os.PathLike) -> Path:
    """Save a rendered image as an 8-bit PNG, atomically."""
    with atomic_path(path) as tmp:
        Image.fromarray(np.asarray(image, dtype=np.uint8)).save(tmp, format="PNG")
    return Path(path)


def poisson_canopy(
    lai: float, x: float = 1.0, *, seed: int = 0
) -> SkyFunction:
    """A random canopy with Poisson gaps: P(sky | θ) = exp(−G(θ, x)·LAI / cosθ), per pixel.

    G is Campbell's ellipsoidal projection function (x = 1: spherical, G = 0.5). Each call
    draws independent Bernoulli pixels from ``seed``.
    """
    from .metrics import ellipsoid_g

    def predicate(zenith: NDArray[np.float64], azimuth: NDArray[np.float64]) -> NDArray[np.bool_]:
        rng = np.random.default_rng(seed)
        cos = np.cos(np.radians(zenith))
        with np.errstate(divide="ignore"):
            p = np.where(cos > 1e-9, np.exp(-ellipsoid_g(zenith, x) * lai / np.maximum(cos, 1e-9)), 0.0)
        return rng.random(np.shape(zenith)) < p

    return predicate
