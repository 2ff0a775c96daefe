"""The forward engine's unscattered sky at the sensor points (radtree.engines.forward.skypoint):
the estimator against closed forms and a quadrature, the split (sky photons tallied only once
scattered) against the whole photon tally, and the point against the NumPy engine's point.
Seeds fixed; every comparison within 3 standard errors with the error itself bounded."""

from __future__ import annotations

import math

import numpy as np
import pytest

from radtree.engines.common.geometry import Environment, scene_geometry, scene_optics
from radtree.engines.forward import ForwardSettings, trace_forward
from radtree.engines.forward.skypoint import direct_sky
from radtree.engines.forward.sources import EnvironmentSource, Sphere
from radtree.engines.numpy.scenes import sky_state, slat_layer
from radtree.engines.registry import get_engine
from radtree.optics import Plastic, Trans
from radtree.scene import Scene, SensorGrid, quad

UP = np.array([0.0, 0.0, 1.0])
L0 = 1000.0


def _point_sky(scene: Scene, st, grid: SensorGrid, rays: int = 64, batches: int = 32,
               seed: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """Mean and standard error (batches) of the point estimator per sensor (lux)."""
    geo = scene_geometry(scene, "auto", 1)
    optics = scene_optics(scene, st, geo.material_names)
    env = EnvironmentSource(Environment(st), Sphere(np.zeros(3), 60.0))
    rows = direct_sky(geo, optics, grid, env, rays, batches, np.random.default_rng(seed))
    return rows.mean(axis=0), rows.std(axis=0, ddof=1) / math.sqrt(batches)


def _strip(material) -> Scene:
    """A 0.3 m wide strip, 200 m long along y, 1 m above the sensor at the origin."""
    strip = quad("strip", "strip", np.array([[-0.15, -100, 1], [0.15, -100, 1],
                                             [0.15, 100, 1], [-0.15, 100, 1]], float))
    return Scene([strip], {"strip": material},
                 {"facade": SensorGrid("facade", [[0, 0, 0.0]], [UP])})


def test_uniform_sky_open_and_under_a_specular_strip():
    """Uniform sky L: πL on an open upward sensor, and under a black infinite strip of width
    w at height h the view factor (sin φ₂ − sin φ₁)/2 of the strip (differential element to
    an infinitely long strip) removed; under a Trans strip (T_s 0.4) 60 % of it."""
    st = sky_state("uniform", zenith_luminance=L0, ground_glow=False)
    g = SensorGrid("g", [[0, 0, 0.0], [3.0, 0, 0.0]], [UP, UP])
    def view(x0: float, x1: float) -> float:   # (sin φ₂ − sin φ₁)/2, sin φ = x / √(x² + h²)
        return 0.5 * (x1 / math.hypot(x1, 1.0) - x0 / math.hypot(x0, 1.0))

    f_strip = np.array([view(-0.15, 0.15), view(-3.15, -2.85)])
    for material, blocked in ((Plastic("strip", 0.0), 1.0), (Trans("strip", 0.0, 0.0, 0.4), 0.6)):
        m, se = _point_sky(_strip(material), st, g)
        expect = math.pi * L0 * (1.0 - blocked * f_strip)
        assert np.all(se < 0.01 * expect)
        assert np.all(np.abs(m - expect) <= 3 * se), (m, se, expect)


def test_clear_sky_on_a_vertical_sensor_against_quadrature():
    """A CIE-overcast sky and the ground glow on an open south-facing vertical sensor: the
    estimator against a 1 000 × 2 000 midpoint quadrature of ∫ L cos⁺ dω."""
    st = sky_state("cie_overcast", zenith_luminance=L0, ground_glow=True,
                   ground_reflectance=0.3)
    south = np.array([0.0, -1.0, 0.0])
    m, se = _point_sky(Scene([], {}, {}), st, SensorGrid("g", [[0, 0, 1.0]], [south]))
    nz, nphi = 1000, 2000
    z = -1.0 + (np.arange(nz) + 0.5) * 2.0 / nz
    phi = (np.arange(nphi) + 0.5) * 2.0 * math.pi / nphi
    Z, P = np.meshgrid(z, phi, indexing="ij")
    s = np.sqrt(1.0 - Z * Z)
    d = np.column_stack([(s * np.cos(P)).ravel(), (s * np.sin(P)).ravel(), Z.ravel()])
    lum = np.asarray(Environment(st)(d), float)
    exact = float((lum * np.maximum(d @ south, 0.0)).sum() * 4.0 * math.pi / (nz * nphi))
    assert se[0] < 0.005 * exact
    assert abs(m[0] - exact) <= 3 * se[0], (m, se, exact)


def test_split_counts_every_sky_lumen_once():
    """A diffusing Trans roof (R 0.1, T_d 0.3, T_s 0.4) under a uniform sky: the total with the
    unscattered sky at the point (the rest from scattered photons) against the whole photon
    tally on the patch (the roof is uniform: point and patch agree), and the infinite-slab
    value π L (T_s + T_d) = 0.7 π L within a 20 m roof's edge loss (< 1 %)."""
    st = sky_state("uniform", zenith_luminance=L0, ground_glow=False)
    roof = quad("roof", "roof", np.array([[-20, -20, 1], [20, -20, 1], [20, 20, 1],
                                          [-20, 20, 1]], float))
    sc = Scene([roof], {"roof": Trans("roof", 0.1, 0.3, 0.4)},
               {"facade": SensorGrid("facade", [[0, 0, 0.0]], [UP])})
    base = ForwardSettings(photons=200_000, focus_m=0.5, guide=0.8, guide_radius_m=None)
    split = trace_forward(sc, st, ForwardSettings(**{**base.__dict__, "direct_sky": True}))
    whole = trace_forward(sc, st, base)
    (a, sa), (b, sb) = split.grid_mean("facade"), whole.grid_mean("facade")
    print(f"roof: split {a:.0f} ± {sa:.0f}, whole {b:.0f} ± {sb:.0f}, "
          f"0.7πL {0.7 * math.pi * L0:.0f}")
    assert sa < 0.02 * a and sb < 0.03 * b
    assert abs(a - b) <= 3 * math.hypot(sa, sb)
    assert abs(a - 0.7 * math.pi * L0) <= 3 * sa + 0.01 * a
    assert sa < sb   # the unscattered part no longer comes from the photons


def test_slats_unscattered_sky_at_the_point_against_numpy():
    """Black Poisson slats (LAI 1.5, 0.3 m) over an upward sensor under a CIE-overcast sky and
    the ground glow: nothing scatters, so the forward engine's whole value is the point
    estimate, against the NumPy engine's paths from the same point (ab 1: escaping rays)."""
    st = sky_state("cie_overcast", zenith_luminance=L0, ground_glow=True)
    slats = slat_layer("slats", "leaf", lai=1.5, extent=12.0, z_bottom=0.5, z_top=2.5,
                       size=0.3, inclination_deg=45.0, rng=np.random.default_rng(5))
    pts = [[0, 0, 0.0], [1.0, 0.5, 0.0]]
    sc = Scene([slats], {"leaf": Plastic("leaf", 0.0)},
               {"facade": SensorGrid("facade", pts, [UP, UP])})
    fw = trace_forward(sc, st, ForwardSettings(photons=20_000, direct_sky=True,
                                               sky_rays=4096, focus_m=0.5))
    got, se = fw.grids["facade"].lux, fw.grids["facade"].stderr
    from radtree.config import EngineParams

    p = EngineParams().changed(rays=40_000, seed=2, max_bounces=1, ab=1)
    bw = get_engine("numpy").trace_once(sc, st, p, 1)["facade"]
    comb = np.hypot(se, bw.stderr)
    print(f"slats: forward {got} ± {se}, numpy {bw.lux} ± {bw.stderr}")
    assert np.all(comb < 0.02 * bw.lux)
    assert np.all(np.abs(got - bw.lux) <= 3 * comb)
    assert fw.ledger.balance == pytest.approx(0.0, abs=1e-6 * fw.ledger.launched)
