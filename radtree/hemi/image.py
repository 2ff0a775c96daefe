"""Loading fisheye photos (JPEG/PNG/TIFF) and making the single channel that is classified.

Channels (computed after gamma back-correction, on the 0–255 scale; sky is bright in all):

* ``blue`` (default): the blue channel B.
* ``luma``: 0.299 R + 0.587 G + 0.114 B (Rec. 601 weights); the only choice for grayscale files.
* ``gla``: the Green Leaf Algorithm index GLA = (2G − R − B) / (2G + R + B) (Louhaichi et al.
  2001), inverted and rescaled to 255 · (1 − GLA) / 2 so that sky is bright and leaves dark.
* ``2bg``: 2B − G, clipped to 0–255.

Gamma back-correction: v_linear = 255 · (v / 255) ** gamma (default 2.2, i.e. undo the sRGB-like
encoding of camera JPEGs; gamma = 1 leaves values unchanged). The pixel array is used as stored
(EXIF orientation is ignored, so mask coordinates refer to the stored pixels).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from PIL import Image, UnidentifiedImageError

from radtree.errors import ConfigError, RadtreeError

CHANNELS = ("blue", "luma", "gla", "2bg")
IMAGE_SUFFIXES = (".jpg", ".jpeg", ".png", ".tif", ".tiff")
MIN_SIZE_PX = 64

Image.MAX_IMAGE_PIXELS = 400_000_000  # large stitched fisheyes are fine; guards only absurd files


@dataclass(frozen=True)
class LoadedImage:
    """A photo as stored: ``pixels`` is H × W × 3 (colour) or H × W (grayscale), on 0–255."""

    name: str
    pixels: NDArray[np.float32]
    path: Path | None = None

    @property
    def is_gray(self) -> bool:
        return self.pixels.ndim == 2

    @property
    def width(self) -> int:
        return int(self.pixels.shape[1])

    @property
    def height(self) -> int:
        return int(self.pixels.shape[0])

    def brightness(self) -> NDArray[np.float32]:
        """Max over colour channels (0–255), used to find the image circle."""
        if self.is_gray:
            return self.pixels
        p = self.pixels   # channel by channel: 10 × faster than max(axis=2) over 3 values
        return np.maximum(np.maximum(p[:, :, 0], p[:, :, 1]), p[:, :, 2])

    def display_rgb(self) -> NDArray[np.uint8]:
        """An 8-bit RGB copy for overlays."""
        rgb = self.pixels if not self.is_gray else np.repeat(self.pixels[:, :, None], 3, axis=2)
        return np.clip(rgb + 0.5, 0, 255).astype(np.uint8)


def load_image(path: str | os.PathLike) -> LoadedImage:
    """Read a JPEG/PNG/TIFF file; raise :class:`RadtreeError` naming the file on any problem."""
    p = Path(path)
    if not p.exists():
        raise RadtreeError(f"{p}: no such file")
    if p.is_dir():
        raise RadtreeError(f"{p}: is a folder, not an image")
    if p.stat().st_size == 0:
        raise RadtreeError(f"{p}: the file is empty (0 bytes)")
    try:
        with Image.open(p) as im:
            im.load()
            pixels = _pil_to_array(im)
    except (UnidentifiedImageError, OSError, ValueError, SyntaxError) as exc:
        pixels = _tiff_fallback(p, exc)
    return from_array(pixels, name=p.name, path=p)


def from_array(array: NDArray, *, name: str = "array", path: Path | None = None) -> LoadedImage:
    """Wrap an in-memory image (H × W or H × W × 3/4; uint8, uint16, bool or float 0–1)."""
    a = np.asarray(array)
    if a.ndim == 3 and a.shape[2] == 4:
        a = a[:, :, :3]
    if a.ndim == 3 and a.shape[2] == 1:
        a = a[:, :, 0]
    if a.ndim not in (2, 3) or (a.ndim == 3 and a.shape[2] != 3):
        raise RadtreeError(f"{name}: unsupported image shape {a.shape}; expected H×W or H×W×3")
    if a.size == 0:
        raise RadtreeError(f"{name}: the image has no pixels")
    if a.dtype == np.bool_:
        scaled = a.astype(np.float32) * 255.0
    elif a.dtype == np.uint8:
        scaled = a.astype(np.float32)
    elif a.dtype == np.uint16:
        scaled = a.astype(np.float32) / 257.0
    elif np.issubdtype(a.dtype, np.integer):
        top = 255.0 if a.max(initial=0) <= 255 else 65535.0
        scaled = a.astype(np.float32) * (255.0 / top)
    elif np.issubdtype(a.dtype, np.floating):
        if not np.all(np.isfinite(a)):
            raise RadtreeError(f"{name}: the image contains NaN or infinite values")
        top = 1.0 if a.max(initial=0) <= 1.0 else 255.0
        scaled = np.clip(a.astype(np.float32) * (255.0 / top), 0, 255)
    else:
        raise RadtreeError(f"{name}: unsupported pixel type {a.dtype}")
    h, w = scaled.shape[:2]
    if min(h, w) < MIN_SIZE_PX:
        raise RadtreeError(
            f"{name}: the image is only {w}×{h} px; hemispherical analysis needs at least "
            f"{MIN_SIZE_PX} px on each side"
        )
    return LoadedImage(name, scaled, path)


def _pil_to_array(im: Image.Image) -> NDArray:
    mode = im.mode
    if mode in ("1", "L", "LA", "I;16", "I;16B", "I;16L", "I;16N"):
        if mode == "LA":
            im = im.convert("L")
        if mode == "1":
            return np.asarray(im.convert("L"))
        arr = np.asarray(im)
        return arr.astype(np.uint16) if mode.startswith("I;16") else arr
    if mode in ("I", "F"):
        return np.asarray(im)
    if mode != "RGB":
        im = im.convert("RGB")
    return np.asarray(im)


def _tiff_fallback(p: Path, exc: Exception) -> NDArray:
    """PIL cannot read 48-bit RGB TIFFs; tifffile (a scikit-image dependency) can."""
    if p.suffix.lower() in (".tif", ".tiff"):
        try:
            import tifffile

            return np.asarray(tifffile.imread(p))
        except Exception:  # noqa: BLE001 - report the original, clearer error
            pass
    raise RadtreeError(f"{p}: cannot read the image ({exc}); is it a valid JPEG, PNG or TIFF?") from exc


def _linearise(v: NDArray[np.float32], gamma: float) -> NDArray[np.float32]:
    if gamma == 1.0:
        return v
    return (255.0 * np.power(v / np.float32(255.0), np.float32(gamma))).astype(np.float32)


def check_channel(channel: str) -> str:
    c = str(channel).strip().lower().replace("-", "").replace("_", "")
    c = {"b": "blue", "2b-g": "2bg", "2bminusg": "2bg", "y": "luma"}.get(c, c)
    if c not in CHANNELS:
        raise ConfigError(
            f"unknown channel '{channel}'; expected one of {', '.join(CHANNELS)}", field="channel"
        )
    return c


def check_gamma(gamma: float) -> float:
    g = float(gamma)
    if not math.isfinite(g) or not 0.1 <= g <= 10.0:
        raise ConfigError(f"gamma must be between 0.1 and 10, got {gamma}", field="gamma")
    return g


def channel_values(
    image: LoadedImage, channel: str = "blue", gamma: float = 2.2, *, rows: slice | None = None,
    cols: slice | None = None,
) -> NDArray[np.float32]:
    """The processed channel (0–255, float32) over an optional crop of the image."""
    channel = check_channel(channel)
    gamma = check_gamma(gamma)
    px = image.pixels[rows or slice(None), cols or slice(None)]
    if image.is_gray:
        if channel != "luma":
            raise RadtreeError(
                f"{image.name}: is a grayscale image, so the '{channel}' channel does not exist; "
                "use --channel luma"
            )
        return _linearise(px, gamma)
    if channel == "blue":
        return _linearise(np.ascontiguousarray(px[:, :, 2]), gamma)
    if channel == "2bg":
        b, g = _linearise(px[:, :, 2], gamma), _linearise(px[:, :, 1], gamma)
        return np.clip(2.0 * b - g, 0.0, 255.0).astype(np.float32)
    lin = _linearise(px, gamma)
    r, g, b = lin[:, :, 0], lin[:, :, 1], lin[:, :, 2]
    if channel == "luma":
        return (0.299 * r + 0.587 * g + 0.114 * b).astype(np.float32)
    den = 2.0 * g + r + b
    with np.errstate(invalid="ignore", divide="ignore"):
        gla = np.where(den > 0, (2.0 * g - r - b) / den, 0.0)
    return (255.0 * (1.0 - gla) / 2.0).astype(np.float32)


def find_images(folder: str | os.PathLike) -> list[Path]:
    """JPEG/PNG/TIFF files directly inside ``folder``, sorted by name (hidden files skipped)."""
    d = Path(folder)
    files = sorted(
        p
        for p in d.iterdir()
        if p.is_file() and p.suffix.lower() in IMAGE_SUFFIXES and not p.name.startswith(".")
    )
    if not files:
        raise RadtreeError(
            f"{d}: no images found (looked for {', '.join(IMAGE_SUFFIXES)} files in the folder)"
        )
    return files
