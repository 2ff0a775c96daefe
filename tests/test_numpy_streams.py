"""The NumPy engine's random numbers: one counter-based stream per path.

``radtree.engines.common.streams``: each path's uniforms are SplitMix64 outputs keyed by the
path's number and the draw's place in the program, so a result depends neither on how many
worker threads trace a batch nor on how the paths are batched.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from radtree.config import EngineParams
from radtree.engines.common.streams import GeneratorDraws, PathStreams, as_draws, uniforms
from radtree.engines.numpy import TraceOptions, trace
from radtree.engines.numpy.scenes import sky_state, slat_layer
from radtree.optics import Glass, Plastic, Trans
from radtree.scene import Scene, SensorGrid, quad

# SplitMix64 seeded with 0: its first outputs (Vigna's reference splitmix64.c; the state is
# advanced by the golden increment, then finalised): the stream at offset 0 from path 1 on
SPLITMIX64_SEED0 = [0xE220A8397B1DCDAF, 0x6E789E6AA1B965F4, 0x06C45D188009454F,
                    0xF88BB8A8724C81EC]


def test_uniforms_are_splitmix64_outputs():
    got = uniforms(np.arange(1, 5, dtype=np.uint64), 0)
    expect = np.array([(x >> 11) * 2.0 ** -53 for x in SPLITMIX64_SEED0])
    np.testing.assert_array_equal(got, expect)


def test_streams_are_uniform_and_uncorrelated_between_places():
    """10⁵ paths: each place's numbers pass a Kolmogorov–Smirnov test, two places of the same
    paths (and the two draws at one place) are uncorrelated, consecutive paths too."""
    s = PathStreams(12345, np.arange(100_000, dtype=np.uint64))
    a = s.rows(None, 1, 2)
    u1, u2 = a.random(100_000), a.random(100_000)
    v = s.rows(None, 1, 3).random(100_000)
    w = s.rows(None, 2, 1, 0).random(100_000)
    for x in (u1, u2, v, w):
        assert 0.0 <= x.min() and x.max() < 1.0
        assert stats.kstest(x, "uniform").pvalue > 1e-3
    for x, y in ((u1, u2), (u1, v), (v, w), (u1[:-1], u1[1:])):
        assert abs(np.corrcoef(x, y)[0, 1]) < 0.015  # 4.7 standard errors of 1/√10⁵


def test_a_path_draws_the_same_numbers_whatever_else_is_drawn():
    ids = np.arange(1000, 1100, dtype=np.uint64)
    s = PathStreams(7, ids)
    whole = s.rows(None, 3, 4)
    all1, all2 = whole.random(100), whole.random(100)
    some = np.array([5, 17, 18, 99])
    part = s.rows(some, 3, 4)
    np.testing.assert_array_equal(part.random(4), all1[some])
    np.testing.assert_array_equal(part.random(4), all2[some])
    # a part of the batch (the worker thread's view) sees the same streams
    np.testing.assert_array_equal(PathStreams(7, ids[50:]).rows(None, 3, 4).random(50),
                                  all1[50:])
    assert not np.array_equal(PathStreams(8, ids).rows(None, 3, 4).random(100), all1)
    with pytest.raises(ValueError, match="3 draws asked of 4 paths"):
        s.rows(some).random(3)


def test_a_generator_stays_the_plain_stream():
    g = as_draws(np.random.default_rng(3))
    assert isinstance(g, GeneratorDraws) and g.rows(np.arange(2), 1) is g
    np.testing.assert_array_equal(g.random(5), np.random.default_rng(3).random(5))


def _slat_scene() -> Scene:
    rng = np.random.default_rng(3)
    layer = slat_layer("leaves", "leafy", lai=4.0, extent=8, z_bottom=1, z_top=4, size=0.3,
                       inclination_deg=30, rng=rng)
    pane = quad("pane", "glass", np.array([[-1.0, -1, 0.6], [1, -1, 0.6], [1, 1, 0.6],
                                           [-1, 1, 0.6]]))
    street = quad("street", "ground", np.array([[-20.0, -20, -0.01], [20, -20, -0.01],
                                                [20, 20, -0.01], [-20, 20, -0.01]]))
    pts = np.array([[0.0, 0, 0], [1.5, 1.5, 0], [-1.5, 0.5, 0.2]])
    g = SensorGrid("g", pts, np.tile([0.0, 0.0, 1.0], (3, 1)))
    mats = {"ground": Plastic("ground", 0.2), "leafy": Trans("leafy", 0.11, 0.2, 0.35),
            "glass": Glass.from_transmittance("glass", 0.7)}
    return Scene([layer, pane, street], mats, {"g": g})


@pytest.mark.parametrize("sun_disc", [False, True])
def test_results_do_not_depend_on_the_number_of_worker_threads(sun_disc):
    """Slats with specular transmission (shadow rays through layers, their roulette), glass,
    diffuse bounces, sun and sky: 1, 2 and 3 workers give the same numbers to the bit."""
    sc = _slat_scene()
    st = sky_state("perez", altitude=55.0, azimuth=30.0, dni=70000, dhi=12000)
    opts = TraceOptions(min_part_paths=8, batch_paths=48, sun_disc=sun_disc)
    out = [trace(sc, st, EngineParams(rays=300, max_bounces=5, seed=4, workers=w),
                 options=opts)["g"] for w in (1, 2, 3)]
    for other in out[1:]:
        np.testing.assert_array_equal(other.lux, out[0].lux)
        np.testing.assert_array_equal(other.stderr, out[0].stderr)
    assert np.all(out[0].lux > 0)


@pytest.mark.parametrize("sun_disc", [False, True])
def test_results_do_not_depend_on_the_batch_size(sun_disc):
    """The same paths in batches of 48, 100 or all 900 at once: the same numbers (the per-sensor
    sums gathered batch by batch: equal to rounding)."""
    sc = _slat_scene()
    st = sky_state("perez", altitude=55.0, azimuth=30.0, dni=70000, dhi=12000)
    out = [trace(sc, st, EngineParams(rays=300, max_bounces=5, seed=4, workers=2),
                 options=TraceOptions(min_part_paths=8, batch_paths=b, sun_disc=sun_disc))["g"]
           for b in (48, 100, 900)]
    for other in out[1:]:
        np.testing.assert_allclose(other.lux, out[0].lux, rtol=1e-12)
        np.testing.assert_allclose(other.stderr, out[0].stderr, rtol=1e-9)
