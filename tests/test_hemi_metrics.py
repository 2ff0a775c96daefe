"""Metric definitions: hand-computed values and property tests (ranges, monotonicity)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from radtree.errors import ConfigError
from radtree.hemi.geometry import FisheyeGeometry
from radtree.hemi.mask import CircularMask
from radtree.hemi.metrics import (
    GapTable,
    RingGrid,
    canopy_metrics,
    difn,
    ellipsoid_g,
    fit_ellipsoid,
    gap_table,
    lai_lang_xiang,
    lai_miller,
    mean_tilt_deg,
    openness,
    sky_view_factor,
    x_from_mean_tilt,
)


def table_from(gap: np.ndarray, start: float = 0.0, end: float = 90.0) -> GapTable:
    rings, segments = gap.shape
    grid = RingGrid(rings, segments, start, end)
    n = np.where(np.isnan(gap), 0, 100)
    return GapTable(grid, gap, gap.copy(), n, np.rint(np.nan_to_num(gap) * n).astype(int),
                    grid.cell_solid_angle())


def test_openness_and_svf_by_hand() -> None:
    gap = np.array([[1.0, 0.0], [0.5, 0.5], [0.0, 0.0]])  # rings 0-30, 30-60, 60-90
    t = table_from(gap)
    c = np.cos(np.radians([0, 30, 60, 90]))
    s2 = np.sin(np.radians([0, 30, 60, 90])) ** 2
    omega = c[:-1] - c[1:]
    cosw = s2[1:] - s2[:-1]
    ring = np.array([0.5, 0.5, 0.0])
    assert openness(t) == pytest.approx((omega * ring).sum() / omega.sum())
    assert sky_view_factor(t) == pytest.approx((cosw * ring).sum() / cosw.sum())
    assert difn(t) == pytest.approx(100 * (cosw * ring).sum() / cosw.sum())


def test_empty_cells_are_left_out() -> None:
    gap = np.array([[1.0, np.nan], [0.0, 0.0]])
    t = table_from(gap, 0, 60)
    c = np.cos(np.radians([0, 30, 60]))
    omega = (c[:-1] - c[1:]) * math.pi  # one cell per ring half
    assert openness(t) == pytest.approx(omega[0] / (omega[0] + 2 * omega[1]))
    assert t.ring_gap == pytest.approx([1.0, 0.0])


def test_miller_and_lang_xiang() -> None:
    z = RingGrid(6, 4, 0, 60).ring_centres
    k = 0.8  # constant contact number: LAI = 2 K for any zenith range
    ring_t = np.exp(-k / np.cos(np.radians(z)))
    gap = np.repeat(ring_t[:, None], 4, axis=1)
    t = table_from(gap, 0, 60)
    assert lai_miller(t) == pytest.approx(2 * k, rel=1e-12)
    assert lai_lang_xiang(t) == pytest.approx(2 * k, rel=1e-12)
    # clumped: half the segments twice as dense -> Lang-Xiang sees the mean contact number
    gap2 = np.concatenate([np.repeat(ring_t[:, None] ** 2, 2, 1), np.repeat(ring_t[:, None] ** 0.5, 2, 1)], 1)
    t2 = table_from(gap2, 0, 60)
    assert lai_lang_xiang(t2) == pytest.approx(2 * k * 1.25, rel=1e-12)
    m = canopy_metrics(t2)
    assert m.lai_eff < m.lai and 0 < m.clumping_lx < 1


def test_gap_floor_for_rings_without_sky() -> None:
    gap = np.zeros((3, 2))
    t = table_from(gap, 0, 45)
    floor = 0.01
    z = t.grid.ring_centres
    w = t.grid.ring_solid_angle_weights()
    expected = 2 * (w * -math.log(floor) * np.cos(np.radians(z))).sum() / w.sum()
    assert lai_miller(t, floor) == pytest.approx(expected)
    assert math.isfinite(lai_lang_xiang(t, floor))
    with pytest.raises(ConfigError, match="gap floor"):
        canopy_metrics(t, gap_floor=0.0)


def test_ellipsoid_functions() -> None:
    z = np.linspace(0, 85, 18)
    assert ellipsoid_g(z, 1.0) == pytest.approx(np.full(18, 0.5), rel=2e-3)  # spherical
    assert ellipsoid_g(z, 0.0) == pytest.approx(2 / math.pi * np.sin(np.radians(z)), rel=3e-3)
    assert mean_tilt_deg(1.0) == pytest.approx(57.3, abs=1.5)  # spherical mean tilt
    assert x_from_mean_tilt(mean_tilt_deg(2.7)) == pytest.approx(2.7)


@pytest.mark.parametrize("x_true,lai_true", [(0.6, 1.5), (1.0, 2.0), (2.5, 3.0), (6.0, 4.0)])
def test_ellipsoid_fit_recovers_parameters(x_true: float, lai_true: float) -> None:
    z = RingGrid(8, 1, 0, 80).ring_centres
    x, lai = fit_ellipsoid(z, lai_true * ellipsoid_g(z, x_true))
    assert x == pytest.approx(x_true, rel=1e-3)
    assert lai == pytest.approx(lai_true, rel=1e-4)


def test_open_sky_structure_metrics() -> None:
    m = canopy_metrics(table_from(np.ones((5, 8)), 0, 75))
    assert (m.openness, m.svf, m.difn, m.lai_eff, m.lai) == (1.0, 1.0, 100.0, 0.0, 0.0)
    assert math.isnan(m.clumping_lx) and math.isnan(m.ellipsoid_x)
    h = canopy_metrics(table_from(np.ones((5, 8))), upward=False)
    assert h.svf == 1.0 and math.isnan(h.lai_eff)


def test_grid_validation() -> None:
    with pytest.raises(ConfigError, match="zenith range"):
        RingGrid(5, 8, 60, 30)
    with pytest.raises(ConfigError, match="zenith range"):
        RingGrid(5, 8, 0, 95)
    with pytest.raises(ConfigError, match="rings"):
        RingGrid(0, 8)
    g = RingGrid(9, 8)
    assert g.cell_solid_angle().sum() == pytest.approx(2 * math.pi)
    assert g.cell_cosine_weight().sum() == pytest.approx(math.pi)


# -- property tests --------------------------------------------------------------------------
gap_arrays = st.tuples(st.integers(1, 10), st.integers(1, 12)).flatmap(
    lambda s: arrays(np.float64, s, elements=st.floats(0.0, 1.0))
)
ranges = st.tuples(st.floats(0.0, 60.0), st.floats(5.0, 30.0)).map(
    lambda t: (t[0], min(90.0, t[0] + t[1]))
)


@settings(max_examples=150, deadline=None)
@given(gap_arrays, gap_arrays, ranges)
def test_metrics_bounded_and_monotone(gap: np.ndarray, extra: np.ndarray, zr: tuple) -> None:
    more = np.clip(gap + np.resize(extra, gap.shape), 0.0, 1.0)  # more sky everywhere
    a = canopy_metrics(table_from(gap, *zr))
    b = canopy_metrics(table_from(more, *zr))
    for m in (a, b):
        assert 0.0 <= m.openness <= 1.0 and 0.0 <= m.svf <= 1.0 and 0.0 <= m.difn <= 100.0
        assert m.lai_eff >= 0.0 and m.lai >= 0.0 and math.isfinite(m.lai)
    assert b.openness >= a.openness - 1e-12
    assert b.svf >= a.svf - 1e-12
    assert b.difn >= a.difn - 1e-10
    assert b.lai_eff <= a.lai_eff + 1e-12
    assert b.lai <= a.lai + 1e-12


SMALL = FisheyeGeometry(96, 96, CircularMask(48, 48, 46))
FIELD = SMALL.pixel_field()


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**32 - 1), st.floats(0.05, 0.95), st.floats(0.0, 0.5))
def test_pixel_masks_monotone(seed: int, p: float, p_add: float) -> None:
    rng = np.random.default_rng(seed)
    sky = rng.random(FIELD.valid.shape) < p
    more = sky | (rng.random(FIELD.valid.shape) < p_add)
    assume(more[FIELD.valid].sum() > sky[FIELD.valid].sum())
    grid = RingGrid(6, 4)
    ta = gap_table(sky & FIELD.valid, FIELD.valid, FIELD.zenith, FIELD.azimuth, FIELD.weight, grid)
    tb = gap_table(more & FIELD.valid, FIELD.valid, FIELD.zenith, FIELD.azimuth, FIELD.weight, grid)
    for t in (ta, tb):
        assert 0 <= openness(t) <= 1 and 0 <= sky_view_factor(t) <= 1
        assert np.all((t.gap >= 0) & (t.gap <= 1))
    assert openness(tb) >= openness(ta)
    assert sky_view_factor(tb) >= sky_view_factor(ta)
    assert tb.gap_fraction > ta.gap_fraction
    assert lai_miller(tb) <= lai_miller(ta) + 1e-12
