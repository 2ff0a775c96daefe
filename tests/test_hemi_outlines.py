"""Gap outlines on shapes of known angular size, GeoJSON structure, and the sky predicate."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from radtree.hemi import HemiConfig, RingGrid, analyse_array, gap_mask_function, gap_outlines
from radtree.hemi.outlines import write_geojson
from radtree.hemi.synthetic import default_mask, render_fisheye

SIZE = 1000  # R = 500 px: one pixel is ~0.18 degrees at the image centre (equidistant)


def angular_distance(z1, a1, z2, a2):  # degrees
    z1, a1, z2, a2 = (np.radians(np.asarray(v, dtype=float)) for v in (z1, a1, z2, a2))
    c = np.cos(z1) * np.cos(z2) + np.sin(z1) * np.sin(z2) * np.cos(a1 - a2)
    return np.degrees(np.arccos(np.clip(c, -1, 1)))


def analyse(image, **kw):
    config = HemiConfig(mask=default_mask(SIZE), channel="luma", gamma=1.0, threshold=128,
                        grid=RingGrid(9, 8), **kw)
    return analyse_array(image, config, name="synthetic.png")


def test_off_zenith_disc() -> None:
    image = render_fisheye(lambda z, a: angular_distance(z, a, 50, 120) < 15, SIZE)
    r = analyse(image)
    assert len(r.outlines) == 1
    gap = r.outlines[0]
    d = angular_distance(gap.exterior[:, 0], gap.exterior[:, 1], 50, 120)
    assert d == pytest.approx(np.full(d.shape, 15.0), abs=0.5)
    assert gap.solid_angle_sr == pytest.approx(2 * math.pi * (1 - math.cos(math.radians(15))), rel=0.02)
    assert not gap.contains_zenith and gap.holes == ()
    assert np.allclose(gap.exterior[0], gap.exterior[-1])  # closed ring
    v = gap.vectors()[0]
    assert v[:, 2] == pytest.approx(np.cos(np.radians(gap.exterior[:, 0])))


def test_annulus_gives_a_polygon_with_a_hole(tmp_path) -> None:
    image = render_fisheye(lambda z, a: (z > 20) & (z < 40), SIZE)
    r = analyse(image)
    assert len(r.outlines) == 1
    gap = r.outlines[0]
    assert len(gap.holes) == 1 and not gap.contains_zenith
    assert gap.exterior[:, 0] == pytest.approx(np.full(len(gap.exterior), 40.0), abs=0.3)
    assert gap.holes[0][:, 0] == pytest.approx(np.full(len(gap.holes[0]), 20.0), abs=0.3)
    rings = gap_outlines(r, include_holes=True)
    assert len(rings) == 2 and len(gap_outlines(r)) == 1

    collection = r.geojson()
    write_geojson(tmp_path / "gaps.geojson", collection)
    data = json.loads((tmp_path / "gaps.geojson").read_text())
    assert data["type"] == "FeatureCollection" and len(data["features"]) == 1
    feature = data["features"][0]
    assert feature["geometry"]["type"] == "Polygon"
    assert feature["properties"]["holes"] == 1 and feature["properties"]["image"] == "synthetic.png"
    outer, hole = (np.array(c) for c in feature["geometry"]["coordinates"])
    for ring in (outer, hole):
        assert np.allclose(ring[0], ring[-1])
        assert ring[:, 0].max() - ring[:, 0].min() == pytest.approx(360.0, abs=2.0)  # winds round
        assert ring[:, 1].min() == 0.0  # closed along the zenith line

    def area(xy):
        return 0.5 * np.sum(xy[:-1, 0] * xy[1:, 1] - xy[1:, 0] * xy[:-1, 1])

    assert area(outer) > 0 > area(hole)  # RFC 7946 orientation in the (azimuth, zenith) plane
    assert area(outer) + area(hole) == pytest.approx(360 * 20, rel=0.01)  # the 20-40 band


def test_cap_contains_zenith_and_tiny_gaps_are_dropped() -> None:
    def sky(z, a):
        specks = np.random.default_rng(0).random(z.shape) < 0.02  # isolated pixels
        return (z < 20) | ((z > 60) & specks)

    r = analyse(render_fisheye(sky, SIZE), outline_min_area_px=4.0)
    big = [g for g in r.outlines if g.pixels > 100]
    assert len(big) == 1 and big[0].contains_zenith
    assert big[0].exterior[:, 0] == pytest.approx(np.full(len(big[0].exterior), 20.0), abs=0.3)
    assert all(g.pixels >= 4 for g in r.outlines)


def test_simplification_reduces_vertices() -> None:
    image = render_fisheye(lambda z, a: angular_distance(z, a, 40, 300) < 25, SIZE)
    raw = analyse(image, outline_tolerance_px=0.0).outlines[0]
    simple = analyse(image, outline_tolerance_px=1.0).outlines[0]
    assert len(simple.exterior) < len(raw.exterior) / 3


def test_sky_predicate_reproduces_the_rendered_sky() -> None:
    def truth(z, a):
        return (angular_distance(z, a, 30, 200) < 20) | ((z > 70) & (a > 45) & (a < 100))

    r = analyse(render_fisheye(truth, SIZE, north_deg=17.0), north_deg=17.0)
    is_sky = gap_mask_function(r)
    rng = np.random.default_rng(1)
    z = np.degrees(np.arccos(rng.random(20000)))  # uniform over the hemisphere
    a = rng.uniform(0, 360, 20000)
    d_edge = np.minimum.reduce([
        np.abs(angular_distance(z, a, 30, 200) - 20), np.abs(z - 70), np.abs(a - 45), np.abs(a - 100),
    ])
    far = d_edge > 1.0
    assert np.array_equal(is_sky(z[far], a[far]), truth(z[far], a[far]))
    assert is_sky(np.array([95.0, np.nan]), np.array([0.0, 0.0])).tolist() == [False, False]
    assert gap_mask_function(r, outside=True)(np.array([95.0]), np.array([0.0]))[0]
    v = np.array([[0.0, 0.0, 1.0]])
    assert is_sky.world(v)[0] == truth(np.array([0.0]), np.array([0.0]))[0]
