"""Randomised QMC first directions (radtree.engines.numpy.qmc) and the -ab ladder from one trace."""

from __future__ import annotations

import numpy as np
import pytest

from radtree.config import EngineParams
from radtree.engines.numpy import trace_hour
from radtree.engines.numpy.qmc import FirstDirections, replicate_stderr, replicates, sobol_net
from radtree.engines.numpy.scenes import sky_state, slat_layer
from radtree.engines.numpy.tracing import trace_bounce_ladder
from radtree.optics import Plastic, Trans
from radtree.scene import Scene, SensorGrid, quad


def test_each_replicate_is_a_shifted_net_with_one_point_per_elementary_cell():
    """256 paths → 16 replicates of 16 points; a digitally shifted 2-D Sobol' net keeps its
    (0, 4, 2)-net property: one point in each of the 4 × 4, 2 × 8, 8 × 2, 1 × 16 and 16 × 1
    boxes of area 1/16."""
    fd = FirstDirections(3, 256, np.random.default_rng(1))
    assert fd.r == 16 and sobol_net(16).shape == (16, 2)
    pid = np.arange(3 * 256)
    u, rep = fd.uniforms(pid), fd.replicate(pid)
    assert u.min() >= 0.0 and u.max() < 1.0
    for sensor in range(3):
        for r in range(16):
            uu = u[(pid // 256 == sensor) & (rep == r)]
            for a in (1, 2, 4, 8, 16):
                cell = np.floor(uu[:, 0] * a) * (16 // a) + np.floor(uu[:, 1] * (16 // a))
                assert sorted(cell.astype(int)) == list(range(16))
    # the shifts differ between replicates and sensors
    assert len({tuple(s) for s in fd.shift.reshape(-1, 2)}) == 48


def test_replicate_standard_error():
    sums = np.array([[1.0, 2.0, 3.0, 6.0]])        # 4 replicates of 2 paths: means .5 1 1.5 3
    counts = np.full((1, 4), 2.0)
    means = sums[0] / 2
    np.testing.assert_allclose(replicate_stderr(sums, counts),
                               [means.std(ddof=1) / 2])
    assert replicate_stderr(np.ones((2, 1)), np.ones((2, 1))).tolist() == [0.0, 0.0]
    assert replicates(4096) == 16 and replicates(8) == 4 and replicates(1) == 1
    assert replicates(2) == replicates(3) == 2      # a standard error from two paths on


def _slat_scene() -> tuple[Scene, object]:
    layer = slat_layer("leaves", "leafy", lai=1.5, extent=8, z_bottom=1, z_top=2.5, size=0.3,
                       inclination_deg=30, rng=np.random.default_rng(3))
    ground = Plastic("ground", 0.2)
    street = quad("street", "ground", np.array([[-20, -20, -0.01], [20, -20, -0.01],
                                                [20, 20, -0.01], [-20, 20, -0.01]]))
    g = SensorGrid("a", np.array([[0.0, 0, 0], [1, 1, 0], [0, 0, 0.5]]),   # the last looks down
                   np.array([[0.0, 0, 1], [0, 0, 1], [0, 0, -1]]))
    sc = Scene([layer, street], {"ground": ground, "leafy": Trans("leafy", 0.11, 0.3, 0.1)},
               {"a": g})
    return sc, sky_state("cosine", zenith_luminance=1000.0, altitude=50, azimuth=200,
                         dni=60000)


@pytest.mark.parametrize("sampling", ["sobol", "random"])
def test_the_ab_ladder_from_one_trace_matches_separate_traces(sampling):
    """-ab k read from the bounce orders of one trace to -ab 5 agrees with a trace at
    max_bounces = k (within 4 σ); its top step *is* that trace (same paths), and -ab 0 is the
    direct sun alone."""
    sc, st = _slat_scene()
    p = EngineParams(rays=2000, max_bounces=5, seed=4, sampling=sampling)
    ladder = trace_bounce_ladder(sc, st, p, [0, 1, 2, 3, 5])
    top = trace_hour(sc, st, p)["a"]
    np.testing.assert_allclose(ladder[5]["a"].lux, top.lux, rtol=1e-12)
    np.testing.assert_allclose(ladder[5]["a"].stderr, top.stderr, rtol=1e-9)
    direct = trace_hour(sc, st, EngineParams(rays=8, max_bounces=0))["a"].lux
    np.testing.assert_allclose(ladder[0]["a"].lux, direct)
    previous = direct
    for k in (1, 2, 3):
        one = trace_hour(sc, st, EngineParams(rays=2000, max_bounces=k, seed=11,
                                              sampling=sampling))["a"]
        lad = ladder[k]["a"]
        assert np.all(np.abs(lad.lux - one.lux) < 4 * np.hypot(lad.stderr, one.stderr)), k
        assert np.all(lad.lux >= previous)           # every order adds light
        previous = lad.lux
    assert np.all(ladder[1]["a"].lux < ladder[5]["a"].lux)


def test_hours_traced_in_one_batch_match_hour_by_hour_traces():
    """trace_states: three hours (sun on, another sun, sun off; ground reflectance 0.1 / 0.2 /
    0.4 by hour) in one batch agree with separate traces within 4 σ; the sun-off hour has no
    direct sun and the brighter ground shows."""
    from dataclasses import replace as dc_replace

    from radtree.engines.numpy.tracing import trace_states

    sc, st = _slat_scene()
    states = [dc_replace(st, ground_reflectance=0.1),
              dc_replace(sky_state("cosine", zenith_luminance=800.0, altitude=30, azimuth=120,
                                   dni=40000), ground_reflectance=0.2),
              dc_replace(sky_state("cosine", zenith_luminance=800.0, altitude=30, azimuth=120,
                                   dni=0), ground_reflectance=0.4)]
    p = EngineParams(rays=3000, max_bounces=4, seed=2)
    batch = trace_states(sc, states, p)
    assert len(batch) == 3
    for state, got in zip(states, batch, strict=True):
        one = trace_hour(sc, state, dc_replace(p, seed=9))["a"]
        b = got["a"]
        assert np.all(np.abs(b.lux - one.lux) < 4 * np.hypot(b.stderr, one.stderr))
    assert np.all(batch[2]["a"].lux[:2] < batch[1]["a"].lux[:2])   # no sun at the third hour
    # the downward sensor sees each hour's own ground: 0.4 at the third hour, not the first's 0.1
    dark = trace_hour(sc, dc_replace(states[2], ground_reflectance=0.1), p)["a"]
    assert batch[2]["a"].lux[2] > 2 * dark.lux[2]
