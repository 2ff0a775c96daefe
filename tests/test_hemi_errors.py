"""Bad inputs give one clear error naming the file; image formats and mask detection."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from PIL import Image

from radtree.cli import main
from radtree.errors import ConfigError, RadtreeError
from radtree.hemi import HemiConfig, analyse_image, detect_circular_mask, render_fisheye
from radtree.hemi.image import load_image
from radtree.hemi.mask import CircularMask
from radtree.hemi.synthetic import default_mask, save_png

MASK = "300,200,180"


def fisheye_rgb(width: int = 600, height: int = 400, seed: int = 0) -> np.ndarray:
    """A colour circular fisheye: bluish sky with dark blobs inside a black frame."""
    rng = np.random.default_rng(seed)
    sky = render_fisheye(
        lambda z, a: np.sin(np.radians(7 * a)) + np.cos(np.radians(5 * z)) > -0.3,
        (width, height),
    )
    inside = render_fisheye(lambda z, a: np.ones(z.shape, bool), (width, height)) > 0
    rgb = np.zeros((height, width, 3), np.uint8)
    rgb[inside] = (30, 45, 40)
    rgb[sky > 0] = (150, 190, 240)
    noise = rng.integers(0, 8, rgb.shape, dtype=np.uint8)
    return np.where(inside[..., None], rgb + noise, 0).astype(np.uint8)


def run_cli(*args: str):
    return CliRunner().invoke(main, ["hemi", *args])


def assert_one_line_error(res, *fragments: str) -> None:
    assert res.exit_code == 2, res.output  # bad input
    text = res.output.strip()
    assert text.startswith("error: ") and "\n" not in text, text
    for f in fragments:
        assert f in text, text


def test_corrupt_and_empty_files(tmp_path: Path) -> None:
    bad = tmp_path / "corrupt.jpg"
    bad.write_bytes(b"\xff\xd8\xff\xe0" + bytes(range(256)) * 4)
    with pytest.raises(RadtreeError, match="corrupt.jpg: cannot read the image"):
        load_image(bad)
    empty = tmp_path / "empty.png"
    empty.write_bytes(b"")
    with pytest.raises(RadtreeError, match="empty.png: the file is empty"):
        load_image(empty)
    assert_one_line_error(run_cli(str(bad), "--out", str(tmp_path / "o")), "corrupt.jpg")
    assert_one_line_error(run_cli(str(empty), "--out", str(tmp_path / "o")), "empty.png", "empty")
    assert not (tmp_path / "o" / "summary.csv").exists()


def test_truncated_jpeg(tmp_path: Path) -> None:
    good = tmp_path / "good.jpg"
    Image.fromarray(fisheye_rgb()).save(good, quality=90)
    cut = tmp_path / "cut.jpg"
    cut.write_bytes(good.read_bytes()[:2000])
    with pytest.raises(RadtreeError, match="cut.jpg"):
        analyse_image(cut, HemiConfig(mask=CircularMask(300, 200, 180)))


def test_grayscale_needs_luma(tmp_path: Path) -> None:
    gray = tmp_path / "gray.png"
    save_png(render_fisheye(lambda z, a: z < 40, 400), gray)
    assert load_image(gray).is_gray
    with pytest.raises(RadtreeError, match=r"gray.png: is a grayscale image.*--channel luma"):
        analyse_image(gray, HemiConfig(mask=default_mask(400)))
    assert_one_line_error(run_cli(str(gray), "--mask", "200,200,200", "--out", str(tmp_path)),
                          "gray.png", "--channel luma")
    res = run_cli(str(gray), "--mask", "200,200,200", "--channel", "luma", "--gamma", "1",
                  "--no-overlay", "--out", str(tmp_path / "ok"))
    assert res.exit_code == 0, res.output
    assert (tmp_path / "ok" / "summary.csv").exists()


def test_tiny_image(tmp_path: Path) -> None:
    tiny = tmp_path / "tiny.png"
    Image.fromarray(np.zeros((40, 50, 3), np.uint8)).save(tiny)
    with pytest.raises(RadtreeError, match=r"tiny.png: the image is only 50×40 px"):
        load_image(tiny)
    assert_one_line_error(run_cli(str(tiny), "--out", str(tmp_path)), "tiny.png", "64 px")


def test_non_fisheye_image_is_rejected(tmp_path: Path) -> None:
    rng = np.random.default_rng(1)
    yy, xx = np.mgrid[0:300, 0:400]
    photo = np.stack([xx % 256, yy % 256, (xx + yy) % 256], -1) + rng.integers(0, 20, (300, 400, 3))
    path = tmp_path / "street.jpg"
    Image.fromarray(photo.astype(np.uint8)).save(path)
    with pytest.raises(RadtreeError, match="street.jpg: no dark border"):
        analyse_image(path)
    assert_one_line_error(run_cli(str(path), "--out", str(tmp_path)), "street.jpg", "fisheye")


def test_mask_outside_the_image(tmp_path: Path) -> None:
    path = tmp_path / "fish.png"
    Image.fromarray(fisheye_rgb()).save(path)
    with pytest.raises(ConfigError, match="fish.png.*reaches outside the 600×400 px image"):
        analyse_image(path, HemiConfig(mask=CircularMask(300, 200, 250)))
    assert_one_line_error(run_cli(str(path), "--mask", "500,200,180", "--out", str(tmp_path)),
                          "fish.png", "reaches outside")
    assert_one_line_error(run_cli(str(path), "--preset", "coolpix4500-fce8", "--out",
                                  str(tmp_path)), "fish.png", "2272×1704")


def test_bad_options(tmp_path: Path) -> None:
    path = tmp_path / "fish.png"
    Image.fromarray(fisheye_rgb()).save(path)
    base = [str(path), "--mask", MASK, "--out", str(tmp_path / "o")]
    assert_one_line_error(run_cli(*base, "--threshold", "bright"), "threshold")
    assert_one_line_error(run_cli(*base, "--threshold", "300"), "0 to 255")
    assert_one_line_error(run_cli(*base, "--zenith", "80,10"), "zenith range")
    assert_one_line_error(run_cli(*base, "--zenith", "ten"), "--zenith")
    assert_one_line_error(run_cli(*base, "--polynomial", "1,0,-2"), "not strictly increasing")
    assert_one_line_error(run_cli(*base, "--lens", "fisheye9000"), "unknown lens")
    assert_one_line_error(run_cli(*base, "--mask", "1,2"), "CX,CY,R")
    assert_one_line_error(run_cli(*base, "--gamma", "0"), "gamma")
    assert run_cli(*base, "--channel", "red").exit_code == 2  # click's own usage error


def test_uniform_image_needs_a_manual_threshold(tmp_path: Path) -> None:
    path = tmp_path / "white.png"
    save_png(render_fisheye(lambda z, a: np.ones(z.shape, bool), 400), path)
    cfg = dict(mask=default_mask(400), channel="luma")
    with pytest.raises(RadtreeError, match="white.png: every pixel inside the mask"):
        analyse_image(path, HemiConfig(**cfg))  # type: ignore[arg-type]
    r = analyse_image(path, HemiConfig(threshold=128, **cfg))  # type: ignore[arg-type]
    assert r.metrics.openness == 1.0


def test_empty_folder(tmp_path: Path) -> None:
    assert_one_line_error(run_cli(str(tmp_path), "--out", str(tmp_path / "o")), "no images found")


def test_mask_detection_and_formats(tmp_path: Path) -> None:
    rgb = fisheye_rgb(640, 480, seed=3)
    detected = detect_circular_mask(rgb.max(axis=2))
    assert detected.cx == pytest.approx(320, abs=1.5)
    assert detected.cy == pytest.approx(240, abs=1.5)
    assert detected.radius == pytest.approx(240, abs=1.5)
    # the same picture as 8-bit TIFF and 16-bit RGB TIFF (read through tifffile)
    import tifffile

    Image.fromarray(rgb).save(tmp_path / "fish8.tif")
    tifffile.imwrite(tmp_path / "fish16.tif", rgb.astype(np.uint16) * 257)
    a = analyse_image(tmp_path / "fish8.tif")
    b = analyse_image(tmp_path / "fish16.tif")
    assert a.geometry.mask == b.geometry.mask
    assert a.metrics.openness == pytest.approx(b.metrics.openness, abs=1e-6)
    assert 0.1 < a.metrics.openness < 0.9


def test_config_validation() -> None:
    with pytest.raises(ConfigError, match="channel"):
        HemiConfig(channel="infrared")
    with pytest.raises(ConfigError, match="axis"):
        HemiConfig(axis="down")
    with pytest.raises(ConfigError, match="preset"):
        HemiConfig(preset="coolpix9999")
    with pytest.raises(ConfigError, match="gap floor"):
        HemiConfig(gap_floor=1.5)
