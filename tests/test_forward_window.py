"""The forward engine's weight window (radtree.engines.forward.window): its bound and copies,
the level from the first round's patch crossings, an unchanged expectation (the analytic floor
reflection, every lumen accounted for) and calibrated errors over seeded repeats with it on."""

from __future__ import annotations

import math

import numpy as np
import pytest

from radtree.config import EngineParams
from radtree.engines.forward import ForwardSettings, trace_forward
from radtree.engines.forward.window import MAX_SPLIT, WeightWindow, window_level
from radtree.engines.numpy.scenes import hemisphere_shell, sky_state
from radtree.errors import ConfigError
from radtree.optics import Trans
from radtree.scene import Scene, SensorGrid
from tests.test_forward_strata import DNI, SIDE, _floor_scene

UP = np.array([0.0, 0.0, 1.0])


def test_bound_grows_with_the_squared_distance():
    w = WeightWindow(np.zeros(3), radius=0.5, level=2.0)
    pts = np.array([[0.25, 0, 0], [1.0, 0, 0], [0, 5.0, 0]])
    assert w.bound(pts) == pytest.approx([2.0, 8.0, 200.0])
    # ⌈flux / bound⌉: 7 lm is 4 copies among the patches, 1 at 1 m, the cap far above
    assert list(w.copies(pts, np.array([7.0, 7.0, 1e9]))) == [4, 1, MAX_SPLIT]


def test_photons_aimed_at_the_sphere_are_held_to_the_level():
    w = WeightWindow(np.zeros(3), radius=0.5, level=2.0)
    o = np.array([[5.0, 0, 0], [5.0, 0, 0], [5.0, 0.6, 0], [5.0, 0.4, 0]])
    d = np.array([[-1.0, 0, 0], [1.0, 0, 0], [-1.0, 0, 0], [-1.0, 0, 0]])
    # towards the centre; away from it; passing 0.6 m from it; passing 0.4 m from it
    assert list(w.aimed(o, d)) == [True, False, False, True]
    assert list(w.aimed_copies(o, d, np.full(4, 7.0))) == [4, 1, 1, 4]


def test_level_from_the_mean_crossing():
    assert window_level(2.0, 10.0, 5) == pytest.approx(4.0)
    assert window_level(2.0, 0.0, 0) is None and window_level(0.0, 10.0, 5) is None


def test_project_default_and_bad_factor():
    assert ForwardSettings.from_params(EngineParams()).window == 2.0
    assert ForwardSettings().window == 0.0
    with pytest.raises(ConfigError, match="engine.forward_window"):
        ForwardSettings(window=-1.0)


def test_window_keeps_the_floor_reflection():
    """The floor reflection (tests/test_forward_strata.py, analytic) with the focused launch,
    guided scattering and a tight window (factor 1), rounds of 5 000 photons to 1.5 %: the
    window opens after the first round and splits, the analytic value within 3 standard
    errors, every lumen accounted for."""
    scene, expected = _floor_scene()
    st = sky_state("none", altitude=60, azimuth=30, dni=DNI, ground_glow=False)
    r = trace_forward(scene, st, ForwardSettings(photons=5_000, max_bounces=1, patch_m=SIDE,
                                                 focus_m=0.5, guide=0.8, guide_radius_m=1.0,
                                                 target_rel_se=0.015, window=1.0, seed=4))
    got, se = r.grid_mean("facade")
    print(f"floor reflection, window: expected {expected:.0f}, got {got:.0f} ± {se:.0f}, "
          f"level {r.window_level:.3g} lm, {r.window_splits} copies")
    assert r.window_level is not None and r.window_splits > 0
    assert se <= 0.015 * got and abs(got - expected) <= 3 * se
    assert abs(r.ledger.balance) < 1e-9 * r.ledger.launched


def _shell_floor_scene() -> Scene:
    """A translucent shell (R 0.1, T_d 0.3, T_s 0.2) of 1 m over two overlapping upward
    patches: sunlight reaches them through it; the heavy tail comes from the rings outside
    the shell, whose photons carry more flux each."""
    shell = hemisphere_shell("shell", "shell", radius=1.0, centre=np.zeros(3), axis=UP,
                             n_theta=8, n_phi=16)
    return Scene([shell], {"shell": Trans("shell", 0.10, 0.30, 0.20)},
                 {"facade": SensorGrid("facade", [[0, 0, 0.01], [0.1, 0, 0.01]], [UP, UP])})


def test_errors_calibrated_with_the_window():
    """The shell over two patches, focused launch, guide 0.8, window factor 2, rounds of 4 000
    photons to 5 %: over 60 seeds the z of each run against the mean of the others has s.d.
    0.8–1.25 and no |z| > 3, and the mean lies within 3 of its standard errors of the mean of
    60 runs without the window."""
    st = sky_state("none", altitude=55, azimuth=30, dni=DNI, ground_glow=False)
    sc = _shell_floor_scene()
    out = {}
    for ww in (0.0, 2.0):
        runs = [trace_forward(sc, st, ForwardSettings(
            photons=4_000, batches=32, max_bounces=4, focus_m=0.5, guide=0.8,
            target_rel_se=0.05, max_photons=100_000, window=ww, seed=s)) for s in range(1, 61)]
        m = np.array([r.grid_mean("facade")[0] for r in runs])
        se = np.array([r.grid_mean("facade")[1] for r in runs])
        out[ww] = (m, se, sum(r.window_splits for r in runs))
    m, se, splits = out[2.0]
    others = (m.sum() - m) / (len(m) - 1)
    z = (m - others) / np.sqrt(se ** 2 + np.mean(se ** 2) / (len(m) - 1))
    m0, se0, _ = out[0.0]
    d = m.mean() - m0.mean()
    c = math.hypot(m.std(ddof=1), m0.std(ddof=1)) / math.sqrt(len(m))
    print(f"window: z s.d. {z.std(ddof=1):.3f}, max |z| {np.abs(z).max():.2f}, mean "
          f"{m.mean():.1f} vs {m0.mean():.1f} without ({d / c:+.2f} s.e.), {splits} copies")
    assert splits > 0
    assert 0.8 <= z.std(ddof=1) <= 1.25 and np.all(np.abs(z) <= 3.0)
    assert abs(d) <= 3 * c
