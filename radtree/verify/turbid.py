"""Checks of the turbid-medium crowns (:mod:`radtree.media`, traced by the NumPy engine's
:mod:`radtree.engines.common.turbid`), rows of ``radtree verify``.

One spherical crown of radius R = 2 m (centre 3 m up) of leaf area density u, no other
surface but a black floor far below; the sensor sits at the crown's centre, facing up, so that
every upward path crosses exactly R of medium:

* **Uncollided transmission, direct sun** (black leaves, sun zeniths 0°, 30°, 60°): the
  sensor's direct sun over DNI·cos θ against Beer–Lambert with the G-function,
  exp(−u·G(cos θ)·R), G of Campbell's ellipsoidal distribution x = 1 (spherical leaves, G = ½)
  and x = 3 (planophile) — within 1 % (the shadow rays carry the mean transmittance: no
  sampling error).
* **Uncollided transmission, sampled free paths** (black leaves, a uniform sky of luminance
  L, no sun, no ground): E = 2π L ∫₀¹ μ exp(−u R G(μ)) dμ (midpoint rule on 20 000 nodes)
  against the engine's mean over sensor paths — within 1 % or 3 standard errors. This one
  exercises the collision sampling (the free paths), not the shadow rays.
* **Energy conservation (white furnace)**: leaves that absorb nothing (R = T_d = 0.5), the same
  luminance L from every direction (uniform sky, ground glow of reflectance 1, the floor
  shrunk to 1 cm): the radiance
  field stays uniform, so the sensor must read E = π L whatever the density — within 1 % or 3
  standard errors, at up to 40 bounces. A leak or a gain of energy at the leaf events would
  show here.

* **Forward engine** (:func:`forward_checks`): the sun through the crown onto 36 detectors
  under it against Beer–Lambert integrated over them, and the photon ledger balanced.

References: Ross J. 1981, The Radiation Regime and Architecture of Plant Stands (Junk), ch. 2
(G-function, Beer–Lambert in canopies); Campbell G. S. 1990, Agric. For. Meteorol. 49,
173–176 (ellipsoidal leaf angles); the white-furnace test is the standard conservation check of
volume path tracers (e.g. Pharr, Jakob & Humphreys, Physically Based Rendering, 4th ed., §14).
"""

from __future__ import annotations

import logging
import math
from typing import Any

import numpy as np

from radtree.config import EngineParams, Louvers
from radtree.engines.base import GridResult
from radtree.engines.numpy.engine import ENGINE_NAME
from radtree.engines.numpy.scenes import sky_state
from radtree.engines.numpy.tracing import trace
from radtree.light.sky import SkyState
from radtree.media import TurbidCrowns
from radtree.media_voxels import Media
from radtree.optics import Plastic, Trans
from radtree.scene import Scene, SensorGrid, quad
from radtree.trees.turbid import leaf_kind
from radtree.verify.checks import Check, log_checks

log = logging.getLogger(__name__)

RADIUS = 2.0
CENTRE = (0.0, 0.0, 3.0)
DNI = 100000.0
LUMINANCE = 1000.0   # cd/m² of the uniform sky
ENGINE = ENGINE_NAME   # the NumPy engine's registered name
CASES = ((1.0, 1.0), (3.0, 0.8))   # (ellipsoid x, leaf area density m²/m³)
SENSORS = 16                        # sensors at the centre (the sky check's mean)


def _lv(x: float) -> Louvers:
    return Louvers(inclination_distribution="ellipsoidal", ellipsoid_x=x)


def furnace_scene(media: Media, leaf: Trans, *, sensor: np.ndarray, sensors: int = 1,
                  floor_m: float = 500.0) -> Scene:
    """``media`` over a black floor of half-width ``floor_m`` at z = −47 m (the furnace: a
    1 cm one, which the sensor sees in 4·10⁻⁸ sr: the engine needs one surface), ``sensors``
    sensors at ``sensor`` facing up."""
    h = floor_m
    floor = quad("floor", "black", np.array([[-h, -h, -47.0], [h, -h, -47.0], [h, h, -47.0],
                                             [-h, h, -47.0]]))
    grid = SensorGrid("facade", np.tile(sensor, (sensors, 1)), np.tile([0.0, 0.0, 1.0],
                                                                          (sensors, 1)))
    return Scene([floor], {"black": Plastic("black", 0.0), leaf.name: leaf}, {"facade": grid},
                 media=media)


def crown_scene(x: float, lad: float, leaf: Trans, sensors: int = 1, floor_m: float = 500.0
                ) -> Scene:
    """The one spherical crown over :func:`furnace_scene`'s floor (50 m below its centre),
    ``sensors`` sensors at its centre facing up."""
    kind = leaf_kind(_lv(x), leaf.name)
    media = TurbidCrowns.of(np.array([CENTRE]), RADIUS, RADIUS, lad, 0, [kind])
    return furnace_scene(media, leaf, sensor=np.asarray(CENTRE, float), sensors=sensors,
                         floor_m=floor_m)


def uncollided_patches(res: Any, scene: Scene, st: SkyState, *, seed: int
                       ) -> tuple[float, float, float]:
    """(expected, got, tolerance) of a forward run's ``facade`` patch mean against the NumPy
    engine's exact direct sun at 256 random points per square (``-ab 0``): within 1 % or 3
    combined standard errors."""
    from radtree.verify.compare import backward_patch_values

    got = res.grids["facade"]
    values = backward_patch_values(ENGINE, scene, st, "facade", 1.0, ab=0, points=256,
                                   rays=1, seed=seed)
    want = float(values.mean())
    se_b = float(values.mean(axis=0).std(ddof=1) / math.sqrt(values.shape[1]))
    se = math.hypot(_se(got), se_b)
    return want, float(got.lux.mean()), max(0.01 * want, 3.0 * se)


def beer_lambert(x: float, lad: float, mu: float) -> float:
    """exp(−u·G(μ)·R) of the crown's leaves (G of the ellipsoidal distribution)."""
    g = float(leaf_kind(_lv(x), "leaf").g(np.array([mu]))[0])
    return math.exp(-lad * g * RADIUS)


def sky_through_crown(x: float, lad: float) -> float:
    """E = 2π L ∫₀¹ μ exp(−u R G(μ)) dμ (lx), midpoint rule."""
    n = 20000
    mu = (np.arange(n) + 0.5) / n
    g = leaf_kind(_lv(x), "leaf").g(mu)
    return float(2.0 * math.pi * LUMINANCE * np.mean(mu * np.exp(-lad * RADIUS * g)))


def _params(ab: int, rays: int, seed: int) -> EngineParams:
    return EngineParams(name=ENGINE, max_bounces=ab, rays=rays, seed=seed)


def turbid_checks(*, rays: int = 8000, seed: int = 7, forward_photons: int = 100_000
                  ) -> list[Check]:
    """The checks of the module text, as :class:`~radtree.verify.checks.Check` rows (each
    logged, INFO)."""
    out: list[Check] = []
    black = Trans("black_leaf", 1e-9, 0.0, 0.0)   # trans needs R + T > 0: 1e-9, nil
    for x, lad in CASES:
        scene = crown_scene(x, lad, black, sensors=SENSORS)
        for z in (0.0, 30.0, 60.0):
            st = sky_state("none", altitude=90.0 - z, dni=DNI, ground_glow=False)
            got = trace(scene, st, _params(1, 16, seed))["facade"]
            value = float(got.lux[0]) / (DNI * math.cos(math.radians(z)))
            want = beer_lambert(x, lad, math.cos(math.radians(z)))
            out.append(Check(f"turbid uncollided sun, ellipsoid x {x:g}, u {lad:g}, zenith "
                             f"{z:g}°", ENGINE, want, value, 0.01 * want))
        st = sky_state("uniform", zenith_luminance=LUMINANCE, ground_glow=False)
        res = trace(scene, st, _params(1, rays, seed))["facade"]
        want = sky_through_crown(x, lad)
        out.append(Check(f"turbid uncollided sky (sampled free paths), ellipsoid x {x:g}, "
                         f"u {lad:g}", ENGINE, want, float(res.lux.mean()),
                         max(0.01 * want, 3.0 * _se(res))))
    st = sky_state("uniform", zenith_luminance=LUMINANCE, ground_reflectance=1.0,
                   ground_glow=True)
    for white in (Trans("white_leaf", 0.5, 0.5, 0.0), Trans("white_leaf", 0.4, 0.3, 0.3)):
        scene = crown_scene(1.0, 1.0, white, floor_m=0.005)
        res = trace(scene, st, _params(40, rays // SENSORS, seed))["facade"]
        want = math.pi * LUMINANCE
        out.append(Check(f"turbid energy conservation (white furnace, R {white.reflectance:g}"
                         f" + T_d {white.diffuse_transmittance:g} + T_s "
                         f"{white.specular_transmittance:g} = 1)", ENGINE, want,
                         float(res.lux[0]), max(0.01 * want, 3.0 * _se(res))))
    out += forward_checks(forward_photons, seed)
    return log_checks(out, log)


def forward_checks(photons: int, seed: int = 7) -> list[Check]:
    """The forward engine through the crown (black leaves, sun at zenith 30°, a 9 m beam):
    the mean over 36 horizontal 1 m detectors 2.5 m under the crown's centre against the
    Beer–Lambert transmission integrated over the same squares (the NumPy engine's direct
    sun, exact per point, at 256 random points per square) — within 1 % or 3 combined
    standard errors; and its ledger (launched = escaped + absorbed + capped + killed −
    promoted) balanced to 10⁻⁶ of the launched flux, leaves absorbing."""
    from radtree.engines.forward import ForwardSettings, trace_forward

    xs = np.arange(-2.5, 3.0, 1.0)
    gx, gy = np.meshgrid(xs, xs)
    det = SensorGrid("facade", np.column_stack([gx.ravel(), gy.ravel(), np.full(36, 0.5)]),
                     np.tile([0.0, 0.0, 1.0], (36, 1)))
    base = crown_scene(1.0, 1.0, Trans("black_leaf", 1e-9, 0.0, 0.0))
    scene = Scene(base.meshes, base.materials, {"facade": det}, media=base.media)
    st = sky_state("none", altitude=60.0, dni=DNI, ground_glow=False)
    res = trace_forward(scene, st, ForwardSettings(photons=photons, max_bounces=1, batches=8,
                                                   beam_diameter_m=9.0, patch_m=1.0,
                                                   seed=seed))
    want, got, tol = uncollided_patches(res, scene, st, seed=seed)
    led = res.ledger
    return [Check("turbid uncollided sun under the crown, forward vs Beer–Lambert (36 squares)",
                  "forward", want, got, tol),
            Check("turbid energy ledger (forward): |balance| / launched", "forward", 0.0,
                  abs(led.balance) / led.launched, 1e-6),
            Check("turbid leaves absorb (forward): leaf share of the launched flux > 0",
                  "forward", 1.0, float(led.absorbed_by("black_leaf") > 0), 0.0)]


def _se(res: GridResult) -> float:
    """Standard error of the mean over the grid's sensors (independent paths)."""
    if res.stderr is None:
        return 0.0
    return float(np.sqrt(np.sum(res.stderr ** 2)) / len(res.stderr))
