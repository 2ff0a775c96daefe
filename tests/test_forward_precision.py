"""The forward engine's precision target (radtree.engines.forward.precision): batch-means
standard errors, the photons a leg adds, the cap's warning, and the whole loop on analytic
scenes — the error reached, the mean within 3 standard errors of the exact value, and the
error's calibration over seeded repeats."""

from __future__ import annotations

import math

import numpy as np
import pytest

from radtree.config import EngineParams
from radtree.engines.forward import ForwardSettings, trace_forward
from radtree.engines.forward.precision import (
    Budget,
    PrecisionWarning,
    mean_and_se,
    relative_se,
    worst_relative_se,
)
from radtree.engines.numpy.scenes import hemisphere_shell, sky_state
from radtree.errors import ConfigError
from radtree.optics import Trans
from radtree.scene import Scene, SensorGrid

DNI = 80000.0
UP = np.array([0.0, 0.0, 1.0])


def test_batch_means_error():
    m, se = mean_and_se(np.array([1.0, 2.0, 3.0, 4.0]))
    assert m == 2.5 and se == pytest.approx(math.sqrt(5.0 / 3.0) / 2.0)
    with pytest.raises(ValueError, match="at least 2 batches"):
        mean_and_se(np.array([1.0]))


def test_relative_error_edge_cases():
    assert relative_se(200.0, 4.0) == 0.02 and relative_se(-200.0, 4.0) == 0.02
    assert relative_se(0.0, 0.0) == 0.0          # a dark grid: nothing to resolve
    assert relative_se(0.0, 1.0) == math.inf
    name, r = worst_relative_se({"a": np.array([10.0, 10.0]), "b": np.array([9.0, 11.0])})
    assert name == "b" and r == pytest.approx(0.1)


def test_leg_from_the_square_root_law():
    b = Budget(round_photons=1_000_000, target=0.02, cap=16_000_000)
    assert b.next_leg(1_000_000, 0.02) == 0                 # reached
    # twice the target after 1 M: 4 M in all × 1.1 → 3.4 M more → 4 whole rounds
    assert b.next_leg(1_000_000, 0.04) == 4_000_000
    assert b.next_leg(1_000_000, 0.30) == 15_000_000        # up to the cap, no further
    assert b.next_leg(16_000_000, 0.30) == 0
    assert b.next_leg(1_000_000, math.inf) == 1_000_000      # nothing seen yet: double
    assert Budget(1000, None, 1000).next_leg(1000, 0.5) == 0  # no target: one round


def test_sizing_round_predicts_the_counted_photons():
    """A first round of 1 M at 4 % sizes the run: 4 M × 1.1 → 5 rounds traced afresh (within
    the 16 M cap less the sizing round); further legs count the sizing round towards the cap."""
    b = Budget(round_photons=1_000_000, target=0.02, cap=16_000_000)
    assert b.sized_leg(1_000_000, 0.04) == 5_000_000
    assert b.sized_leg(1_000_000, 0.30) == 15_000_000       # the cap less the sizing round
    assert b.sized_leg(1_000_000, 0.02) == 0 and b.sized_leg(1_000_000, math.inf) == 0
    assert b.next_leg(5_000_000, 0.03, spent=1_000_000) == 8_000_000   # 12.4 M: 7.4 M more
    assert b.next_leg(15_000_000, 0.03, spent=1_000_000) == 0          # cap reached


def test_cap_warns_with_the_error_reached():
    b = Budget(1000, 0.02, 2000)
    with pytest.warns(PrecisionWarning, match=r"cap 2,000 reached .* grid 'facade' 10\.0%"):
        text = b.warn_if_short(2000, {"facade": np.array([90.0, 110.0]),
                                      "dark": np.zeros(2)})
    assert text is not None and "dark" not in text
    assert b.warn_if_short(2000, {"facade": np.array([99.9, 100.1])}) is None


@pytest.mark.parametrize("kwargs, field", [
    ({"target_rel_se": 0.0}, "target_rel_se"), ({"target_rel_se": 1.0}, "target_rel_se"),
    ({"target_rel_se": 0.02, "photons": 1000, "max_photons": 999}, "max_photons")])
def test_bad_precision_settings(kwargs, field):
    with pytest.raises(ConfigError, match=f"engine.{field}"):
        ForwardSettings(**kwargs)


def test_project_defaults_set_a_target():
    s = ForwardSettings.from_params(EngineParams())
    assert (s.target_rel_se, s.max_photons, s.batches, s.stages) == (0.02, 16_000_000, 32, 4)
    assert "to a 2.0% standard error of each grid mean" in s.describe()


def test_target_reached_on_an_open_patch():
    """E = E_dn cos θz on an upward patch in an empty scene: rounds are added until 1 %."""
    st = sky_state("none", altitude=50, azimuth=30, dni=DNI, ground_glow=False)
    g = SensorGrid("facade", [[0, 0, 0.01]], [UP])
    r = trace_forward(Scene([], {}, {"facade": g}), st,
                      ForwardSettings(photons=2_000, batches=16, target_rel_se=0.01,
                                      max_photons=400_000, seed=3))
    mean, se = r.grid_mean("facade")
    expected = DNI * math.cos(math.radians(40))
    assert r.rounds > 1 and r.photons == r.rounds * 2_000 and r.warning is None
    assert se <= 0.01 * mean and abs(mean - expected) <= 3 * se
    assert r.batches["facade"].shape == (16 * r.rounds, 1)


def _shell_scene() -> tuple[Scene, object]:
    st = sky_state("none", altitude=55, azimuth=30, dni=DNI, ground_glow=False)
    shell = hemisphere_shell("shell", "shell", radius=1.0, centre=np.zeros(3), axis=UP,
                             n_theta=8, n_phi=16)
    sc = Scene([shell], {"shell": Trans("shell", 0.10, 0.30, 0.20)},
               {"facade": SensorGrid("facade", [[0, 0, 0.01], [0.1, 0, 0.01]], [UP, UP])})
    return sc, st


def test_errors_are_calibrated_over_seeded_repeats():
    """A translucent shell over two overlapping patches, the target loop on (5 %, rounds of
    8 000 photons in 32 batches): over 60 seeds the z of each run against the mean of the others
    has s.d. 0.8–1.25 and no |z| > 3 (the batch-means error of the grid mean, overlapping
    patches included). With 16 batches of 250 photons the same loop gave s.d. 1.29 and
    max |z| 4.3 over 60 seeds: the tail that more batches handle."""
    sc, st = _shell_scene()
    runs = [trace_forward(sc, st, ForwardSettings(photons=8_000, batches=32, max_bounces=4,
                                                  target_rel_se=0.05, max_photons=200_000,
                                                  seed=s)).grid_mean("facade")
            for s in range(1, 61)]
    m = np.array([r[0] for r in runs])
    se = np.array([r[1] for r in runs])
    others = (m.sum() - m) / (len(m) - 1)
    z = (m - others) / np.sqrt(se ** 2 + np.mean(se ** 2) / (len(m) - 1))
    print(f"z s.d. {z.std(ddof=1):.3f}, max |z| {np.abs(z).max():.2f}, "
          f"relative error {np.mean(se / m):.3%}")
    assert np.all(se <= 0.05 * m)
    assert 0.8 <= z.std(ddof=1) <= 1.25 and np.all(np.abs(z) <= 3.0)


# ------------------------------------------------------------------ the direct sun at the points


def _strip_scene(material) -> tuple[Scene, object]:
    """A 0.3 m wide strip (along y) 1 m above an upward sensor at the origin, sun at the
    zenith: the sensor point in the strip's shadow, its 0.5 m patch 60 % in it."""
    from radtree.scene import quad

    st = sky_state("none", altitude=90.0, azimuth=0.0, dni=DNI, ground_glow=False)
    strip = quad("strip", "strip", np.array([[-0.15, -5, 1], [0.15, -5, 1], [0.15, 5, 1],
                                             [-0.15, 5, 1]], float))
    return Scene([strip], {"strip": material},
                 {"facade": SensorGrid("facade", [[0, 0, 0.0]], [UP])}), st


def test_direct_sun_at_a_point_through_a_specular_layer():
    """E = E_dn · T_s under a Trans strip (T_s 0.3), E_dn outside its shadow, exactly."""
    from radtree.engines.common.geometry import scene_geometry, scene_optics
    from radtree.engines.forward.direct import direct_sun

    sc, st = _strip_scene(Trans("strip", 0.1, 0.2, 0.3))
    geo = scene_geometry(sc, "auto", 1)
    optics = scene_optics(sc, st, geo.material_names)
    grid = SensorGrid("g", [[0, 0, 0.0], [1.0, 0, 0.0], [0, 0, 2.0]], [UP, UP, UP])
    got = direct_sun(geo, optics, grid, np.asarray(st.sun.vector), DNI)
    assert got == pytest.approx([0.3 * DNI, DNI, DNI], rel=1e-9)


def test_direct_sun_counted_at_the_point_not_over_the_patch():
    """A black strip shading the sensor point: 0 lx at the point (nothing scatters), where
    the 0.5 m patch tally of the sun's photons reads the lit 40 % of the square."""
    from radtree.optics import Plastic

    sc, st = _strip_scene(Plastic("strip", 0.0))
    at_point = trace_forward(sc, st, ForwardSettings(photons=100_000, direct_sun=True,
                                                       focus_m=0.5))
    on_patch = trace_forward(sc, st, ForwardSettings(photons=100_000, focus_m=0.5))
    assert at_point.grids["facade"].lux[0] == 0.0
    lux, se = on_patch.grids["facade"].lux[0], on_patch.grids["facade"].stderr[0]
    assert abs(lux - 0.4 * DNI) <= 3 * se and se < 0.02 * DNI
