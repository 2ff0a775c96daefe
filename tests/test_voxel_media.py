"""Voxel crowns (radtree.media_voxels) traced by radtree.engines.common.voxels: the exact
optical-depth walk against a brute-force integral, sampled free paths against Beer–Lambert,
superposition with spheroid crowns, and the NumPy engine through a grid."""

from __future__ import annotations

import math

import numpy as np
import pytest

from radtree.config import Louvers
from radtree.engines.common.media import SuperposedMedia, media_tracer
from radtree.engines.common.streams import GeneratorDraws
from radtree.engines.common.voxels import VoxelTracer
from radtree.errors import EngineError
from radtree.media import TurbidCrowns
from radtree.media_voxels import MediaSet, VoxelCrowns
from radtree.optics import Trans
from radtree.trees.turbid import leaf_kind

ORIGIN = np.array([-1.0, -0.75, 0.0])
SIZE = 0.5
KIND = leaf_kind(Louvers(inclination_distribution="ellipsoidal", ellipsoid_x=1.0), "leaf")
MATS = {"leaf": Trans("leaf", 1e-9, 0.0, 0.0)}


def _pad(seed: int = 1) -> np.ndarray:
    return np.random.default_rng(seed).random((4, 3, 5)) * 2.0


def _brute_area(pad: np.ndarray, o: np.ndarray, d: np.ndarray, length: float = 12.0,
                steps: int = 40_000, origin: np.ndarray = ORIGIN) -> float:
    """∫ u along o + t d, 0 ≤ t ≤ length, by the midpoint rule."""
    t = (np.arange(steps) + 0.5) / steps * length
    p = o + t[:, None] * d
    q = np.floor((p - origin) / SIZE).astype(int)
    ok = np.all((q >= 0) & (q < pad.shape), axis=1)
    return float(pad[q[ok, 0], q[ok, 1], q[ok, 2]].sum() * length / steps)


def _rays(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    o = rng.uniform(-3, 3, (n, 3))
    o[:, 2] = rng.uniform(-1, 4, n)
    tgt = rng.uniform(ORIGIN, ORIGIN + SIZE * np.array([4, 3, 5]), (n, 3))
    d = tgt - o
    return o, d / np.linalg.norm(d, axis=1)[:, None]


def test_transmittance_is_the_exact_piecewise_beer_lambert():
    pad = _pad()
    tr = VoxelTracer(VoxelCrowns.of(ORIGIN[None], size_m=SIZE, pads=[pad], kinds=[KIND]),
                     materials=MATS)
    o, d = _rays(60, 2)
    got = tr.transmittance(o, d)
    want = [math.exp(-_brute_area(pad, o[i], d[i]) * KIND.g(d[i, 2:3])[0]) for i in range(60)]
    assert np.max(np.abs(got - want)) < 5e-4      # the brute force's own step error
    assert got.min() < 0.3                        # the rays do cross the grid


def test_axis_parallel_rays_and_rays_starting_inside():
    pad = np.ones((2, 2, 2))
    tr = VoxelTracer(VoxelCrowns.of(np.zeros((1, 3)), size_m=1.0, pads=[pad], kinds=[KIND]),
                     materials=MATS)
    o = np.array([[0.5, 0.5, -1.0], [1.0, 1.0, 1.0], [0.5, -3.0, 1.5], [1.5, 1.5, 1.5]])
    d = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])
    g = KIND.g(d[:, 2])
    want = np.exp(-g * np.array([2.0, 1.0, 2.0, 0.5]))
    np.testing.assert_allclose(tr.transmittance(o, d), want, rtol=1e-12)


def test_half_spaces_cut_the_grid():
    pad = np.ones((2, 2, 2))
    planes = np.array([[[0.0, 0.0, 1.0, 0.5]]])   # keep z ≥ 0.5
    tr = VoxelTracer(VoxelCrowns.of(np.zeros((1, 3)), size_m=1.0, pads=[pad], kinds=[KIND],
                                    planes=planes), materials=MATS)
    got = tr.transmittance(np.array([[0.5, 0.5, -1.0]]), np.array([[0.0, 0.0, 1.0]]))
    assert got[0] == pytest.approx(math.exp(-KIND.g(np.array([1.0]))[0] * 1.5), rel=1e-12)


def test_sampled_free_paths_follow_the_optical_depth():
    """Uncollided share and the collision-distance CDF at three depths vs 1 − exp(−τ(t))."""
    pad = _pad(3)
    tr = VoxelTracer(VoxelCrowns.of(ORIGIN[None], size_m=SIZE, pads=[pad], kinds=[KIND]),
                     materials=MATS)
    n = 100_000
    d0 = np.array([0.2, 0.1, 1.0]) / np.linalg.norm([0.2, 0.1, 1.0])
    o = np.tile([0.1, 0.05, -2.0], (n, 1))
    d = np.tile(d0, (n, 1))
    met, dist = tr.collide(o, d, np.full(n, np.inf), GeneratorDraws(np.random.default_rng(4)))
    g = KIND.g(d0[2:3])[0]
    for t in (2.5, 3.0, 4.0, np.inf):
        tau = g * _brute_area(pad, o[0], d0, length=min(t, 12.0), steps=20_000)
        p = 1.0 - math.exp(-tau)
        got = float(np.mean((met >= 0) & (dist <= t)))
        assert abs(got - p) < 3.0 * math.sqrt(p * (1 - p) / n) + 1e-4, t
    assert set(np.unique(met)) == {-1, 0}


def test_superposed_media_compose():
    """A grid and a spheroid overlapping: transmittance the product, the uncollided share
    its mean, each medium's collisions numbered after the spheroids."""
    pad = _pad(5)
    vox = VoxelCrowns.of(ORIGIN[None], size_m=SIZE, pads=[pad], kinds=[KIND])
    sph = TurbidCrowns.of(np.array([[0.0, 0.0, 1.2]]), 0.8, 0.8, 1.5, 0, [KIND])
    both = media_tracer(MediaSet(sph, vox), materials=MATS)
    assert isinstance(both, SuperposedMedia)
    alone_s, alone_v = media_tracer(sph, materials=MATS), media_tracer(vox, materials=MATS)
    assert alone_s is not None and alone_v is not None
    o, d = np.array([[0.05, 0.0, -2.0]]), np.array([[0.0, 0.0, 1.0]])
    t_both = both.transmittance(o, d)[0]
    assert t_both == pytest.approx(alone_s.transmittance(o, d)[0]
                                   * alone_v.transmittance(o, d)[0], rel=1e-12)
    n = 60_000
    met, _ = both.collide(np.tile(o, (n, 1)), np.tile(d, (n, 1)), np.full(n, np.inf),
                          GeneratorDraws(np.random.default_rng(6)))
    assert float(np.mean(met < 0)) == pytest.approx(t_both, abs=3 * math.sqrt(t_both / n))
    assert {0, 1} <= set(np.unique(met))
    names = ["leaf", "other"]
    assert list(both.material_index(np.array([0, 1]), names)) == [0, 0]
    normal, coef = both.leaf_events(np.array([0, 1, 1]), np.tile(d, (3, 1)),
                                    GeneratorDraws(np.random.default_rng(7)))
    assert np.all(normal @ d[0] <= 0) and coef.shape == (4, 3)


def test_shared_density_arrays_and_validation():
    pad = _pad()
    vc = VoxelCrowns.of(np.array([[0.0, 0.0, 0.0], [10.0, 0.0, 0.0]]), size_m=SIZE, pads=[pad],
                        kinds=[KIND])
    assert vc.leaf_area() == pytest.approx(2 * pad.sum() * SIZE ** 3)
    z, area = vc.profile()
    assert z[1] == SIZE and area.sum() == pytest.approx(pad.sum() * SIZE ** 3)
    with pytest.raises(ValueError, match="finite and ≥ 0"):
        VoxelCrowns.of(np.zeros((1, 3)), size_m=1.0, pads=[-pad], kinds=[KIND])
    with pytest.raises(ValueError, match="3-D"):
        VoxelCrowns.of(np.zeros((1, 3)), size_m=1.0, pads=[pad[0]], kinds=[KIND])
    with pytest.raises(EngineError, match="trans"):
        VoxelTracer(vc, materials={})


def test_a_turned_grid_is_the_same_grid():
    """A grid turned 30° about z with the rays turned with it: the same transmittances."""
    pad = _pad(8)
    a = math.radians(30.0)
    rot = np.array([[math.cos(a), -math.sin(a), 0.0], [math.sin(a), math.cos(a), 0.0],
                    [0.0, 0.0, 1.0]])
    base = VoxelTracer(VoxelCrowns.of(ORIGIN[None], size_m=SIZE, pads=[pad], kinds=[KIND]),
                       materials=MATS)
    turned = VoxelTracer(VoxelCrowns.of((rot @ ORIGIN)[None], size_m=SIZE, pads=[pad],
                                        kinds=[KIND], axis_i=rot[:2, 0]), materials=MATS)
    o, d = _rays(40, 9)
    np.testing.assert_allclose(turned.transmittance(o @ rot.T, d @ rot.T),
                               base.transmittance(o, d), rtol=1e-9, atol=1e-12)


def test_verify_rows_pass():
    """Every voxel row of `radtree verify` passes (piecewise Beer–Lambert, sampled free
    paths, rasterised sphere vs spheroid, furnace, forward ledger), at reduced counts."""
    from radtree.verify.voxels import path_area, voxel_checks

    rows = voxel_checks(rays=2000, forward_photons=40_000)
    assert len(rows) == 9 and all(r.passed for r in rows), [str(r) for r in rows]
    # the independent optical depth: straight up a uniform column of 3 voxels of 0.5 m
    pad = np.full((1, 1, 3), 2.0)
    area = path_area(pad, np.zeros(3), 0.5, np.array([[0.2, 0.2, -1.0]]),
                     np.array([[0.0, 0.0, 1.0]]))
    assert area[0] == pytest.approx(3.0)


def test_overlapping_grids_compose_like_their_sum():
    """Two grids (different voxel sizes, one shifted) over the same space: the same
    transmittance and uncollided share as their densities added — min of the free paths."""
    fine = np.random.default_rng(12).random((4, 4, 4))
    coarse = np.random.default_rng(13).random((2, 2, 2))
    two = VoxelCrowns.of(np.zeros((2, 3)), size_m=np.array([0.5, 1.0]), pads=[fine, coarse],
                         pad_of=np.array([0, 1]), kinds=[KIND])
    summed = fine + np.repeat(np.repeat(np.repeat(coarse, 2, 0), 2, 1), 2, 2)
    one = VoxelCrowns.of(np.zeros((1, 3)), size_m=0.5, pads=[summed], kinds=[KIND])
    t_two, t_one = (VoxelTracer(m, materials=MATS) for m in (two, one))
    rng = np.random.default_rng(14)
    o = rng.uniform(-1, 3, (50, 3))
    tgt = rng.uniform(0, 2, (50, 3))
    d = (tgt - o) / np.linalg.norm(tgt - o, axis=1)[:, None]
    np.testing.assert_allclose(t_two.transmittance(o, d), t_one.transmittance(o, d),
                               rtol=1e-9)
    n = 80_000
    oo, dd = np.tile([0.3, 0.7, -1.0], (n, 1)), np.tile([0.0, 0.0, 1.0], (n, 1))
    met, _ = t_two.collide(oo, dd, np.full(n, np.inf), GeneratorDraws(np.random.default_rng(2)))
    want = t_one.transmittance(oo[:1], dd[:1])[0]
    assert float(np.mean(met < 0)) == pytest.approx(want, abs=3 * math.sqrt(want / n))
    assert set(np.unique(met)) == {-1, 0, 1}


def test_forward_direct_sun_sees_the_media():
    """The forward engine's direct sun at the sensor points (engine.forward_direct_sun)
    through a voxel grid and a spheroid crown: the exact piecewise Beer–Lambert, as the NumPy
    engine's shadow rays."""
    from radtree.engines.common.geometry import scene_geometry, scene_optics
    from radtree.engines.forward.direct import direct_sun
    from radtree.engines.numpy.scenes import sky_state
    from radtree.verify.voxels import grid_scene

    scene = grid_scene(Trans("black_leaf", 1e-9, 0.0, 0.0), spheroid=True)
    st = sky_state("none", altitude=60.0, dni=1000.0, ground_glow=False)
    geo = scene_geometry(scene, "auto", 1)
    sun = np.array([0.0, 0.5, math.sqrt(3) / 2])
    got = direct_sun(geo, scene_optics(scene, st, geo.material_names), scene.grids["facade"],
                     sun, 1000.0)
    assert geo.media is not None
    want = 1000.0 * sun[2] * geo.media.transmittance(scene.grids["facade"].points, sun[None])
    np.testing.assert_allclose(got, want, rtol=1e-6)
    assert got[0] < 0.5 * 1000.0 * sun[2]
