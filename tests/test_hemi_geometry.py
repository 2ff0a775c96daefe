"""Pixel <-> direction conventions: north, east-west mirror, horizontal axis, solid angles."""

from __future__ import annotations

import math

import numpy as np
import pytest

from radtree.errors import ConfigError
from radtree.hemi.directions import (
    horizontal_to_world,
    up_to_world,
    world_to_horizontal,
    world_to_up,
)
from radtree.hemi.geometry import FisheyeGeometry
from radtree.hemi.lens import get_lens
from radtree.hemi.mask import CircularMask, full_frame_mask, parse_mask

MASK = CircularMask(500.0, 400.0, 300.0)


def geom(**kw: object) -> FisheyeGeometry:
    return FisheyeGeometry(1000, 800, MASK, get_lens(kw.pop("lens", "equidistant")), **kw)  # type: ignore[arg-type]


def test_upward_photo_is_mirrored_east_left_of_north() -> None:
    g = geom()
    x, y = g.to_pixel(np.array([90.0, 90.0, 90.0, 90.0]), np.array([0.0, 90.0, 180.0, 270.0]))
    assert x == pytest.approx([500, 200, 500, 800])  # N top, E left, S bottom, W right
    assert y == pytest.approx([100, 400, 700, 400])
    z, a = g.to_direction(np.array([200.0]), np.array([400.0]))
    assert (z[0], a[0]) == pytest.approx((90.0, 90.0))


def test_no_mirror_and_north_rotation() -> None:
    g = geom(mirror=False)
    x, _ = g.to_pixel(np.array([90.0]), np.array([90.0]))
    assert x[0] == pytest.approx(800)  # east on the right without the mirror
    g = geom(north_deg=90.0)  # true north lies to the right of image-up
    x, y = g.to_pixel(np.array([90.0]), np.array([0.0]))
    assert (x[0], y[0]) == pytest.approx((800, 400))
    # mirrored, east is 90 deg counter-clockwise of north in the image: here image-up
    z, a = g.to_direction(np.array([500.0]), np.array([100.0]))
    assert (z[0], a[0]) == pytest.approx((90.0, 90.0))


def test_round_trip_pixels() -> None:
    rng = np.random.default_rng(3)
    for lens in ("equidistant", "FC-E8", "stereographic"):
        g = geom(lens=lens, north_deg=33.0)
        z = rng.uniform(0, 89.9, 500)
        a = rng.uniform(0, 360, 500)
        x, y = g.to_pixel(z, a)
        z2, a2 = g.to_direction(x, y)
        assert z2 == pytest.approx(z, abs=1e-7)
        assert np.angle(np.exp(1j * np.radians(a2 - a))) == pytest.approx(0.0, abs=1e-7)


@pytest.mark.parametrize("lens", ["equidistant", "equisolid", "stereographic", "FC-E8", "FC-E9"])
def test_pixel_solid_angles_sum_to_the_hemisphere(lens: str) -> None:
    g = FisheyeGeometry(1200, 1200, CircularMask(600, 600, 580), get_lens(lens))
    pf = g.pixel_field()
    assert pf.weight.sum() == pytest.approx(2 * math.pi, rel=2e-3)
    cap = pf.valid & (pf.zenith < 40)
    assert pf.weight[cap].sum() == pytest.approx(2 * math.pi * (1 - math.cos(math.radians(40))), rel=2e-3)


def test_pixel_field_is_shared_by_the_lens_axes() -> None:
    """The field's angles are in the camera frame: an upward and a horizontal analysis of one
    photo share one computation; a geometry with another north and mirror shares the lens's
    part, and each field equals its geometry's own pixel-by-pixel directions."""
    from radtree.hemi.geometry import clear_pixel_field_cache

    mask, lens = CircularMask(450, 350, 340), get_lens("FC-E8")
    up = FisheyeGeometry(900, 700, mask, lens)
    side = FisheyeGeometry(900, 700, mask, lens, axis="horizontal")
    turned = FisheyeGeometry(900, 700, mask, lens, axis="horizontal", north_deg=30.0,
                             mirror=False)
    clear_pixel_field_cache()
    assert side.pixel_field() is up.pixel_field()
    a, b = up.pixel_field(), turned.pixel_field()
    assert b.zenith is a.zenith and b.weight is a.weight and b.valid is a.valid
    for g, pf in ((up, a), (turned, b)):
        y, x = np.nonzero(pf.valid)
        zen, azi = g.to_direction(x + pf.cols.start + 0.5, y + pf.rows.start + 0.5)
        np.testing.assert_allclose(pf.zenith[pf.valid], zen, atol=1e-4)
        np.testing.assert_allclose(pf.azimuth[pf.valid], azi.astype(np.float32), atol=1e-3)
    assert not np.allclose(a.azimuth[a.valid], b.azimuth[b.valid], atol=1.0)


def test_full_frame_allows_the_circle_past_the_frame() -> None:
    mask = full_frame_mask(1200, 800)
    assert mask.radius == pytest.approx(0.5 * math.hypot(1200, 800))
    g = FisheyeGeometry(1200, 800, mask, full_frame=True)
    pf = g.pixel_field()
    assert pf.valid.shape == (800, 1200) and pf.valid.all()  # the whole frame is within 90 deg
    with pytest.raises(ConfigError, match="outside"):
        FisheyeGeometry(1200, 800, mask)


def test_mask_parsing_and_validation() -> None:
    assert parse_mask("1136,852,754") == CircularMask(1136, 852, 754)
    with pytest.raises(ConfigError, match="CX,CY,R"):
        parse_mask("1136,852")
    with pytest.raises(ConfigError, match="too small"):
        CircularMask(10, 10, 5)
    with pytest.raises(ConfigError, match="reaches outside"):
        CircularMask(100, 100, 150).check_inside(400, 400)


def test_upward_world_vectors() -> None:
    v = up_to_world(np.array([0.0, 90.0, 90.0]), np.array([0.0, 0.0, 90.0]))
    assert v == pytest.approx(np.array([[0, 0, 1], [0, 1, 0], [1, 0, 0]]), abs=1e-12)
    z, a = world_to_up(v[1:])
    assert z == pytest.approx([90, 90]) and a == pytest.approx([0, 90])


def test_horizontal_axis_to_world() -> None:
    # a facade looking north: the lens axis is north; psi clockwise from up, seen looking out
    v = horizontal_to_world(np.array([0, 90, 90, 90, 90]), np.array([0, 0, 90, 180, 270]), 0.0)
    expected = [[0, 1, 0], [0, 0, 1], [1, 0, 0], [0, 0, -1], [-1, 0, 0]]
    assert v == pytest.approx(np.array(expected, dtype=float), abs=1e-12)
    # a facade looking east: right-hand side is south
    v = horizontal_to_world(np.array([0.0, 90.0]), np.array([0.0, 90.0]), 90.0)
    assert v == pytest.approx(np.array([[1, 0, 0], [0, -1, 0]], dtype=float), abs=1e-12)
    # 45 degrees up from the axis of a south-west facing facade
    v = horizontal_to_world(np.array([45.0]), np.array([0.0]), 225.0)[0]
    assert v == pytest.approx([-0.5, -0.5, math.sqrt(0.5)])


def test_horizontal_round_trip() -> None:
    rng = np.random.default_rng(4)
    theta = rng.uniform(0.1, 179.9, 200)
    psi = rng.uniform(0, 360, 200)
    v = horizontal_to_world(theta, psi, 17.0)
    assert np.linalg.norm(v, axis=1) == pytest.approx(np.ones(200))
    t2, p2 = world_to_horizontal(v, 17.0)
    assert t2 == pytest.approx(theta, abs=1e-9)
    assert np.angle(np.exp(1j * np.radians(p2 - psi))) == pytest.approx(0.0, abs=1e-9)
