"""The forward light-tracing engine against analytic values, its own ledger and the NumPy engine.

Every check compares a number to its expectation within 3 standard errors (the engine's batch
standard error, combined with the NumPy engine's where both are compared) and asserts that the
standard error is small enough for the check to mean something. Seeds are fixed.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from radtree.config import EngineParams, load_project
from radtree.engines.forward import ForwardSettings, trace_forward
from radtree.engines.forward.precision import PrecisionWarning
from radtree.engines.numpy.scenes import hemisphere_shell, sky_state, slat_layer
from radtree.engines.registry import ENGINE_CHOICES, get_engine
from radtree.errors import ConfigError
from radtree.optics import Plastic, Trans
from radtree.scene import Scene, SensorGrid, quad
from radtree.verify.compare import backward_patch_mean, reduced_dome_project

DNI = 80000.0
UP = np.array([0.0, 0.0, 1.0])


def square(name: str, material: str, half: float, z: float = 0.0):
    return quad(name, material, np.array([[-half, -half, z], [half, -half, z],
                                          [half, half, z], [-half, half, z]], float))


def within(got: float, expected: float, se: float, k: float = 3.0) -> bool:
    return abs(got - expected) <= k * se


# ----------------------------------------------------------------- settings and registry


def test_registered_and_in_the_cli_choices():
    assert "forward" in ENGINE_CHOICES
    eng = get_engine("forward")
    assert eng.name == "forward" and "forward light tracing" in eng.describe()
    assert "photons" in eng.sampling(EngineParams())


@pytest.mark.parametrize("kwargs, field", [
    ({"threshold": 0.0}, "forward_threshold"), ({"threshold": 1.0}, "forward_threshold"),
    ({"threshold": -0.1}, "forward_threshold"), ({"photons": 0}, "photons"),
    ({"beam_diameter_m": 0.0}, "beam_diameter_m"), ({"patch_m": -1.0}, "patch_m"),
    ({"batches": 1}, "forward_batches")])
def test_bad_settings_one_clear_message(kwargs, field):
    with pytest.raises(ConfigError, match=f"engine.{field}"):
        ForwardSettings(**kwargs)


@pytest.mark.parametrize("key, value", [("forward_threshold", 0), ("forward_threshold", 1),
                                        ("photons", 0), ("beam_diameter_m", 0.0),
                                        ("patch_m", 0.0)])
def test_bad_project_settings_are_named(key, value):
    with pytest.raises(ConfigError, match=f"engine.{key}"):
        reduced_dome_project(scenario_overrides={f"engine.{key}": value})


def test_beam_that_misses_the_sensors_is_refused():
    st = sky_state("none", altitude=50, azimuth=30, dni=DNI, ground_glow=False)
    g = SensorGrid("facade", [[0, 0, 0], [1.0, 0, 0]], [UP, UP])
    with pytest.raises(ConfigError, match="misses its sensors.*diameter ≥"):
        trace_forward(Scene([], {}, {"facade": g}), st,
                      ForwardSettings(photons=1000, beam_diameter_m=0.5))


# ----------------------------------------------------------------- analytic values


@pytest.mark.parametrize("beam", [None, 1.0])
def test_open_ground_horizontal_patch(beam):
    """E = E_dn·cos θz on a horizontal patch over open ground (ground light leaves upwards and
    is not counted: the detector tallies its front side only)."""
    st = sky_state("none", altitude=50, azimuth=30, dni=DNI, ground_glow=False)
    g = SensorGrid("facade", [[0, 0, 0.01]], [UP])
    sc = Scene([square("ground", "ground", 1.0)], {"ground": Plastic("ground", 0.3)},
               {"facade": g})
    r = trace_forward(sc, st, ForwardSettings(photons=200_000, beam_diameter_m=beam))
    got, se = float(r.grids["facade"].lux[0]), float(r.grids["facade"].stderr[0])
    expected = DNI * math.cos(math.radians(40))
    print(f"horizontal patch (beam {beam}): expected {expected:.0f} got {got:.0f} ± {se:.0f}")
    assert se < 0.02 * expected
    assert within(got, expected, se)
    assert abs(r.ledger.balance) < 1e-9 * r.ledger.launched


def test_vertical_facade_patch_in_an_empty_scene():
    st = sky_state("none", altitude=35, azimuth=20, dni=DNI, ground_glow=False)
    n = np.array([0.0, 1.0, 0.0])
    g = SensorGrid("facade", [[0, 0, 5], [1.0, 0, 5]], [n, n])
    r = trace_forward(Scene([], {}, {"facade": g}), st, ForwardSettings(photons=200_000))
    expected = DNI * float(np.asarray(st.sun.vector) @ n)
    res = r.grids["facade"]
    print(f"vertical patch: expected {expected:.0f} got {res.lux} ± {res.stderr}")
    assert np.all(res.stderr < 0.02 * expected)
    assert np.all(np.abs(res.lux - expected) <= 3 * res.stderr)


def test_sky_photons_uniform_sky_on_a_horizontal_patch():
    """A uniform sky of luminance L over open ground: E = π L from above."""
    st = sky_state("uniform", zenith_luminance=1000.0, ground_glow=False)
    g = SensorGrid("facade", [[0, 0, 0.0]], [UP])
    r = trace_forward(Scene([], {}, {"facade": g}), st, ForwardSettings(photons=200_000))
    got, se = float(r.grids["facade"].lux[0]), float(r.grids["facade"].stderr[0])
    print(f"uniform sky: expected {math.pi * 1000:.1f} got {got:.1f} ± {se:.1f}")
    assert se < 0.02 * math.pi * 1000 and within(got, math.pi * 1000.0, se)


# ----------------------------------------------------------------- against the NumPy engine


def test_translucent_shell_against_numpy():
    """A Trans half sphere (R 0.10, T_d 0.30, T_s 0.20, radius 1 m) over an upward sensor,
    sun only: forward and NumPy patch means within 3 combined standard errors."""
    st = sky_state("none", altitude=55, azimuth=30, dni=DNI, ground_glow=False)
    shell = hemisphere_shell("shell", "shell", radius=1.0, centre=np.zeros(3), axis=UP,
                             n_theta=12, n_phi=24)
    sc = Scene([shell], {"shell": Trans("shell", 0.10, 0.30, 0.20)},
               {"facade": SensorGrid("facade", [[0, 0, 0.01]], [UP])})
    fw = trace_forward(sc, st, ForwardSettings(photons=300_000, max_bounces=6))
    got, se = float(fw.grids["facade"].lux[0]), float(fw.grids["facade"].stderr[0])
    bw = backward_patch_mean("numpy", sc, st, "facade", 0.5, ab=6, points=200, rays=64)
    comb = math.hypot(se, bw.stderr)
    print(f"shell: numpy {bw.lux:.0f} ± {bw.stderr:.0f}, forward {got:.0f} ± {se:.0f}")
    assert comb < 0.02 * bw.lux
    assert within(got, bw.lux, comb)


def test_mendoza_reduced_louvers_dome_against_numpy():
    """Scenario A of the reduced Mendoza dome (5 slat layers, 12:30, sun only, black ground):
    façade mean (mean over the 8 sensors' 0.5 m patches) within 2 % or 3 combined s.e."""
    from radtree.light.hours import hour_states
    from radtree.pipeline.assemble import make_scene

    proj = reduced_dome_project("12:30")
    sc = proj.scenario("A")
    built = make_scene(proj, sc, dense_grid=False)
    st = hour_states(proj, sc, ["12:30"])[0]
    fw = trace_forward(built.scene, st, ForwardSettings(photons=3_000_000, max_bounces=built.ab,
                                                        seed=7), ["facade"])
    got, se = fw.grid_mean("facade")
    bw = backward_patch_mean("numpy", built.scene, st, "facade", 0.5, ab=built.ab, points=48,
                             rays=48)
    comb = math.hypot(se, bw.stderr)
    print(f"reduced dome A 12:30: numpy {bw.lux:.0f} ± {bw.stderr:.0f}, "
          f"forward {got:.0f} ± {se:.0f} ({got / bw.lux - 1:+.1%})")
    assert comb < 0.05 * bw.lux
    assert abs(got / bw.lux - 1) <= 0.02 or within(got, bw.lux, comb)


# ----------------------------------------------------------------- energy conservation


def leaf_layer(material: str, seed: int = 3):
    return slat_layer("leaves", material, lai=2.0, extent=3.0, z_bottom=0.5, z_top=1.5,
                      size=0.15, inclination_deg=40.0, rng=np.random.default_rng(seed))


@pytest.mark.parametrize("splitting", [False, True])
def test_lossless_leaves_over_a_white_floor_send_everything_back(splitting):
    """Leaves with r + t = 1 over a white Lambertian floor: all launched flux leaves the scene
    upwards (≤ 0.5 % lost: bounce cap, threshold kills, leaks). A 2 m sun beam aimed at the
    layer's centre, so that every photon meets the scene."""
    st = sky_state("none", altitude=60, azimuth=0, dni=DNI, ground_glow=False)
    sc = Scene([leaf_layer("leaf"), square("floor", "floor", 500.0)],
               {"leaf": Trans("leaf", 0.45, 0.45, 0.10), "floor": Plastic("floor", 1.0)},
               {"facade": SensorGrid("facade", [[0, 0, 0.01]], [UP])})
    r = trace_forward(sc, st, ForwardSettings(photons=4_000 if splitting else 40_000,
                                              max_bounces=200, max_specular=200,
                                              splitting=splitting, threshold=0.001,
                                              beam_diameter_m=2.0))
    led = r.ledger
    back = led.escaped_up / led.launched
    print(f"white floor, splitting={splitting}: sent back {back:.5f}, "
          f"absorbed {led.absorbed.sum() / led.launched:.2e}, killed "
          f"{led.killed / led.launched:.2e}, capped {led.capped / led.launched:.2e}")
    assert abs(led.balance) < 1e-9 * led.launched
    assert float(led.absorbed.sum()) < 1e-9 * led.launched
    # ray splitting kills children below the threshold (TracePro): that flux is lost, counted
    assert back + led.killed / led.launched >= 0.995
    if not splitting:
        assert back >= 0.995


def test_black_floor_reflected_transmitted_absorbed_add_up():
    """Leaves R 0.10, T_d 0.15, T_s 0.30 over a black floor: reflected (escaped upwards) +
    transmitted (absorbed by the floor) + absorbed by leaves = launched; and the flux a floor
    detector grid tallies equals what the floor absorbed (two independent tallies). A 2 m sun
    beam aimed at the layer's centre (the ``facade`` grid)."""
    st = sky_state("none", altitude=70, azimuth=0, dni=DNI, ground_glow=False)
    xs = np.arange(-11.0, 12.0, 2.0)  # 2 m tiles covering the floor
    X, Y = np.meshgrid(xs, xs)
    tiles = SensorGrid("floor_tiles", np.column_stack([X.ravel(), Y.ravel(), np.full(X.size, 1e-3)]),
                       np.tile(UP, (X.size, 1)))
    sc = Scene([leaf_layer("leaf"), square("floor", "floor", 12.0)],
               {"leaf": Trans("leaf", 0.10, 0.15, 0.30), "floor": Plastic("floor", 0.0)},
               {"facade": SensorGrid("facade", [[0, 0, 0.01]], [UP]), "floor_tiles": tiles})
    r = trace_forward(sc, st, ForwardSettings(photons=100_000, max_bounces=50, threshold=0.001,
                                              beam_diameter_m=2.0, patch_m=2.0))
    led = r.ledger
    # transmitted: what left the layer downwards (onto the floor, or past its edge)
    refl, floor = led.escaped_up, led.absorbed_by("floor")
    trans, absd = floor + led.escaped_down, led.absorbed_by("leaf")
    total = refl + trans + absd + led.capped + led.killed - led.promoted
    tallied = float(r.grids["floor_tiles"].lux.sum()) * 4.0
    print(f"black floor: R {refl / led.launched:.4f} T {trans / led.launched:.4f} "
          f"A {absd / led.launched:.4f} sum {(refl + trans + absd) / led.launched:.5f}; "
          f"floor tally / floor absorption {tallied / floor:.5f}")
    assert abs(total / led.launched - 1) < 1e-9
    assert abs((refl + trans + absd) / led.launched - 1) <= 0.005
    assert abs(tallied / floor - 1) < 1e-4  # (a photon on a tile edge counts twice)


# ----------------------------------------------------------------- the pipeline


def test_simulate_with_the_forward_engine(tmp_path):
    """``radtree simulate --engine forward``: the same results table, engine column 'forward'."""
    from radtree.pipeline.options import RunOptions
    from radtree.pipeline.simulate import simulate_project
    from tests.conftest import copy_project

    root = copy_project(tmp_path / "p", hours=["13:30"])
    proj = load_project(root, overrides={"engine.photons": 20_000, "sensors.dense_grid": False,
                                         "street.length_m": 10.0, "engine.max_photons": 40_000})
    with pytest.warns(PrecisionWarning, match="photon cap 40,000 reached"):
        out = simulate_project(proj, options=RunOptions(engine="forward", scenarios=["A", "E"],
                                                        fresh=True))
    assert out is not None
    t = out.table
    assert set(t["engine"]) == {"forward"} and set(t["scenario"]) == {"A", "E"}
    assert len(t) == 16 and np.all(np.isfinite(t["lux"])) and np.all(t["lux_stderr"] >= 0)
    a = t[t["scenario"] == "A"]
    assert np.all(a["lux_reflected_calc"] > 0)  # the calculated ground term is added as usual
