"""Analytic checks on rendered binary fisheye images whose true openness/SVF/LAI are known."""

from __future__ import annotations

import math

import numpy as np
import pytest

from radtree.hemi import (
    HemiConfig,
    RingGrid,
    analyse_array,
    get_lens,
    horizontal_to_world,
    poisson_canopy,
    render_fisheye,
)
from radtree.hemi.metrics import CanopyMetrics
from radtree.hemi.synthetic import default_mask, render_geometry, save_png

SIZE = 2000
LENSES = ["equidistant", "equisolid", "stereographic", "orthographic", "FC-E8", "FC-E9"]
REL = 0.005  # the 0.5 %


def analyse(image: np.ndarray, lens: str = "equidistant", grid: RingGrid | None = None,
            **kw: object) -> CanopyMetrics:
    config = HemiConfig(
        lens=get_lens(lens), mask=default_mask(image.shape[1::-1]), channel="luma", gamma=1.0,
        threshold=128, grid=grid or RingGrid(), outlines=False, **kw,  # type: ignore[arg-type]
    )
    return analyse_array(image, config).metrics


def complement(image: np.ndarray, lens: str = "equidistant") -> np.ndarray:
    """Swap sky and canopy inside the 90-degree circle."""
    g = render_geometry(image.shape[1::-1], lens)
    pf = g.pixel_field()
    out = image.copy()
    box = out[pf.rows, pf.cols]
    box[pf.valid] = 255 - box[pf.valid]
    return out


@pytest.mark.parametrize("lens", LENSES)
def test_fully_open_sky(lens: str) -> None:
    image = render_fisheye(lambda z, a: np.ones(z.shape, bool), 1000, lens)
    m = analyse(image, lens)
    assert m.openness == pytest.approx(1.0, abs=1e-12)
    assert m.svf == pytest.approx(1.0, abs=1e-12)
    assert m.difn == pytest.approx(100.0, abs=1e-9)
    assert m.gap_fraction == 1.0 and m.lai_eff == 0.0


@pytest.mark.parametrize("lens", LENSES)
def test_zenith_cap_and_its_complement(lens: str) -> None:
    theta0 = 37.3  # deliberately not on a ring edge of the default 10-degree rings
    t = math.radians(theta0)
    image = render_fisheye(lambda z, a: z < theta0, SIZE, lens)
    cap = analyse(image, lens)
    assert cap.svf == pytest.approx(math.sin(t) ** 2, rel=REL)
    assert cap.openness == pytest.approx(1 - math.cos(t), rel=REL)
    rest = analyse(complement(image, lens), lens)
    assert rest.svf == pytest.approx(math.cos(t) ** 2, rel=REL)
    assert rest.openness == pytest.approx(math.cos(t), rel=REL)
    # DIFN is the ring-quadrature version of the SVF: close, not identical, for a sharp edge
    assert cap.difn / 100 == pytest.approx(cap.svf, rel=0.05)
    assert cap.openness + rest.openness == pytest.approx(1.0, abs=1e-9)


def test_half_open_hemispheres() -> None:
    east = analyse(render_fisheye(lambda z, a: a < 180.0, SIZE, "FC-E8"), "FC-E8")
    assert east.openness == pytest.approx(0.5, rel=REL)
    assert east.svf == pytest.approx(0.5, rel=REL)
    # a split that cuts through the azimuth segments
    tilted = analyse(render_fisheye(lambda z, a: (a >= 100.7) & (a < 280.7), SIZE), "equidistant")
    assert tilted.openness == pytest.approx(0.5, rel=REL)
    assert tilted.svf == pytest.approx(0.5, rel=REL)


def test_normalisation_over_a_shorter_zenith_range() -> None:
    image = render_fisheye(lambda z, a: z < 30.0, SIZE)
    m = analyse(image, grid=RingGrid(6, 8, 0, 60))
    assert m.openness == pytest.approx((1 - math.cos(math.radians(30))) / 0.5, rel=REL)
    assert m.svf == pytest.approx(0.25 / 0.75, rel=REL)
    # a fully open sky is 1 over any range
    open_sky = analyse(complement(np.zeros_like(image)), grid=RingGrid(4, 8, 10, 50))
    assert (open_sky.openness, open_sky.svf) == (1.0, 1.0)


def test_poisson_canopy_miller_lai() -> None:
    lai = 2.0
    image = render_fisheye(poisson_canopy(lai, 1.0, seed=11), SIZE)
    m = analyse(image, grid=RingGrid(35, 8, 0, 70))
    assert m.lai_eff == pytest.approx(lai, rel=0.05)
    assert m.lai == pytest.approx(lai, rel=0.05)
    assert m.clumping_lx == pytest.approx(1.0, abs=0.01)
    assert m.ellipsoid_x == pytest.approx(1.0, rel=0.1)
    # expected openness of this canopy: ∫ exp(-0.5 LAI / cos) dΩ over the hemisphere
    z = np.radians(np.linspace(0, 90, 20001))
    f = np.exp(-0.5 * lai / np.maximum(np.cos(z), 1e-12)) * np.sin(z)
    expected = float(np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(z)))
    m90 = analyse(image, grid=RingGrid(18, 8))
    assert m90.openness == pytest.approx(expected, rel=0.01)


def test_ellipsoidal_canopy_leaf_angle() -> None:
    image = render_fisheye(poisson_canopy(2.0, 3.0, seed=5), SIZE, "FC-E8")
    m = analyse(image, "FC-E8", grid=RingGrid(15, 8, 0, 75))
    assert m.ellipsoid_x == pytest.approx(3.0, rel=0.1)
    assert m.ellipsoid_lai == pytest.approx(2.0, rel=0.05)
    assert m.mean_tilt_deg == pytest.approx(math.degrees(9.65 * 6.0**-1.65), abs=2.0)


def test_clumped_canopy_lang_xiang() -> None:
    dense, sparse = 4.0, 0.5
    dense_fn, sparse_fn = poisson_canopy(dense, seed=1), poisson_canopy(sparse, seed=2)

    def clumps(z: np.ndarray, a: np.ndarray) -> np.ndarray:
        odd = (np.floor(a / 45.0) % 2).astype(bool)  # alternate 45-degree sectors
        return np.where(odd, dense_fn(z, a), sparse_fn(z, a))

    m = analyse(render_fisheye(clumps, SIZE), grid=RingGrid(12, 8, 0, 60))
    assert m.lai == pytest.approx((dense + sparse) / 2, rel=0.05)
    assert m.lai_eff < 0.8 * m.lai
    assert m.clumping_lx < 0.8


def test_horizontal_axis_facade_photo() -> None:
    """Façade looking north, sky above a constant 20-degree horizon; analytic vertical SVF."""
    eps = math.radians(20.0)

    def sky(theta: np.ndarray, psi: np.ndarray) -> np.ndarray:
        v = horizontal_to_world(theta, psi, 0.0)
        return v[..., 2] > math.sin(eps)

    image = render_fisheye(sky, SIZE, axis="horizontal")
    m = analyse(image, axis="horizontal", grid=RingGrid(18, 12))
    assert m.openness == pytest.approx((1 - math.sin(eps)) / 2, rel=REL)
    assert m.svf == pytest.approx(0.5 - (eps + math.sin(eps) * math.cos(eps)) / math.pi, rel=REL)
    assert math.isnan(m.lai_eff)


def test_north_and_mirror_end_to_end(tmp_path) -> None:
    image = render_fisheye(lambda z, a: (a > 60) & (a < 120), 1000, north_deg=30.0)
    g = render_geometry(1000, north_deg=30.0)
    # east is 90 degrees counter-clockwise of north, which lies 30 degrees clockwise of up
    x, y = g.to_pixel(np.array([45.0]), np.array([90.0]))
    assert x[0] < 500 and y[0] < 500
    assert image[int(y[0]), int(x[0])] == 255
    config = HemiConfig(mask=default_mask(1000), channel="luma", gamma=1.0, threshold=128,
                        north_deg=30.0, grid=RingGrid(3, 4))
    r = analyse_array(image, config)
    # segments 0-90 and 90-180 each hold 30 degrees of the 60-120 sky sector, the rest none
    assert r.table.gap[:, :2] == pytest.approx(np.full((3, 2), 1 / 3), abs=2e-3)
    assert np.all(r.table.gap[:, 2:] == 0)
    is_sky = r.sky_predicate()
    assert is_sky(np.array([45.0, 45.0]), np.array([90.0, 270.0])).tolist() == [True, False]
    save_png(image, tmp_path / "east.png")
    assert (tmp_path / "east.png").stat().st_size > 0
