"""Checks of the voxel crowns (:mod:`radtree.media_voxels`, traced by
:mod:`radtree.engines.common.voxels`), rows of ``radtree verify``.

A heterogeneous grid of 8 × 8 × 6 voxels of 0.5 m (4 m × 4 m × 3 m, lower corner 1.5 m up),
plant area density drawn once (seeded) in 0 … 1.6 m²/m³ voxel by voxel, spherical leaves
(Campbell's ellipsoidal x = 1, G = ½); a sensor inside it facing up, a black floor far below:

* **Uncollided transmission, direct sun** (black leaves, zeniths 0°, 30°, 60°): the sensor's
  direct sun over DNI·cos θ against Beer–Lambert for the piecewise-constant density,
  exp(−G·Σ u_i ℓ_i), the lengths ℓ_i from an independent computation (every crossing of the
  ray with the grid's planes, sorted: each segment between two lies in one voxel) — within 1 %
  (the shadow rays carry the exact transmittance).
* **Uncollided transmission, sampled free paths** (black leaves, a uniform sky of luminance
  L): E = L ∫ cos θ exp(−τ(Ω)) dΩ over the upper hemisphere (midpoint rule, 240 × 240 nodes in
  μ = cos θ and azimuth, τ as above) against the engine's mean — within 1 % or 3 standard
  errors; exercises the DDA free-path sampling.
* **A voxel grid that rasterises a sphere vs the spheroid crown** (black leaves, uniform sky,
  the sensor at the sphere's centre): the sphere of :mod:`radtree.verify.turbid` (R = 2 m,
  u = 1 m²/m³) on 0.2 m voxels, each voxel's density u times its volume share inside the
  sphere (8³ sub-points), so the leaf area is the sphere's; both traced with the same rays —
  within 1 % or 3 combined standard errors (the staircase's own bias included).
* **Energy conservation (white furnace)**: white leaves (R + T_d = 1), uniform luminance from
  every direction, the grid overlapping a spheroid crown (superposed media) — E = π L within
  1 % or 3 standard errors at up to 40 bounces.
* **Forward engine** (:func:`forward_ledger`): the sun through the grid onto 36 detectors
  under it against Beer–Lambert integrated over them (black leaves); the photon ledger
  balanced with grey leaves (launched = escaped + absorbed + capped + killed − promoted, to
  10⁻⁶ of the launched flux), leaves absorbing.

References: Ross 1981 (Beer–Lambert with the G-function); Amanatides & Woo 1987 (the walk
checked); the white furnace as in :mod:`radtree.verify.turbid`.
"""

from __future__ import annotations

import logging
import math

import numpy as np

from radtree.engines.numpy.scenes import sky_state
from radtree.engines.numpy.tracing import trace
from radtree.media import TurbidCrowns
from radtree.media_voxels import MediaSet, VoxelCrowns
from radtree.optics import Trans
from radtree.scene import Scene, SensorGrid
from radtree.trees.turbid import leaf_kind
from radtree.verify.checks import Check, log_checks
from radtree.verify.turbid import (
    CENTRE,
    DNI,
    ENGINE,
    LUMINANCE,
    RADIUS,
    SENSORS,
    _lv,
    _params,
    _se,
    crown_scene,
    furnace_scene,
    uncollided_patches,
)

log = logging.getLogger(__name__)

ORIGIN = np.array([-2.0, -2.0, 1.5])
SIZE = 0.5
SHAPE = (8, 8, 6)
SENSOR = np.array([0.1, 0.2, 2.75])   # inside the grid, off every voxel face
SPHERE_VOXEL = 0.2
LAD = 1.0                              # the sphere's density, m²/m³


def grid_pad(seed: int = 11) -> np.ndarray:
    """The heterogeneous density of the module text (m²/m³)."""
    return np.random.default_rng(seed).uniform(0.0, 1.6, SHAPE)


def path_area(pad: np.ndarray, origin: np.ndarray, size: float, o: np.ndarray,
              d: np.ndarray) -> np.ndarray:
    """Σ u_i ℓ_i along the rays ``o + t d`` (t ≥ 0, unit ``d`` (k, 3)) through the grid, by
    the planes' crossings (module text) — independent of the tracer's DDA."""
    ts = [np.zeros((len(d), 1))]
    for a in range(3):
        planes = origin[a] + np.arange(pad.shape[a] + 1) * size
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (planes[None, :] - o[:, a:a + 1]) / d[:, a:a + 1]
        ts.append(np.where(np.isfinite(t) & (t > 0), t, np.nan))
    t = np.sort(np.concatenate(ts, axis=1), axis=1)            # NaN last
    mid, length = 0.5 * (t[:, 1:] + t[:, :-1]), np.diff(t, axis=1)
    p = o[:, None, :] + np.nan_to_num(mid)[..., None] * d[:, None, :]
    q = np.floor((p - origin) / size).astype(np.int64)
    ok = np.all((q >= 0) & (q < pad.shape), axis=2) & np.isfinite(length)
    u = np.zeros(ok.shape)
    u[ok] = pad[q[ok][:, 0], q[ok][:, 1], q[ok][:, 2]]
    return np.sum(u * np.nan_to_num(length), axis=1)


def _g(mu: np.ndarray) -> np.ndarray:
    return leaf_kind(_lv(1.0), "leaf").g(mu)


def grid_scene(leaf: Trans, *, sensors: int = 1, floor_m: float = 500.0,
               spheroid: bool = False) -> Scene:
    """The grid (and, with ``spheroid``, the sphere of :mod:`radtree.verify.turbid`
    overlapping it), a black floor 50 m below, ``sensors`` sensors at :data:`SENSOR` up."""
    kind = leaf_kind(_lv(1.0), leaf.name)
    vox = VoxelCrowns.of(ORIGIN[None], size_m=SIZE, pads=[grid_pad()], kinds=[kind])
    media = (MediaSet(TurbidCrowns.of(np.array([CENTRE]), RADIUS, RADIUS, LAD, 0, [kind]), vox)
             if spheroid else vox)
    return furnace_scene(media, leaf, sensor=np.asarray(SENSOR, float), sensors=sensors,
                         floor_m=floor_m)


def sky_through_grid(nodes: int = 240) -> float:
    """E = L ∫ cos θ exp(−G·Σ u ℓ) dΩ at :data:`SENSOR` (lx), midpoint rule in μ and φ."""
    mu = (np.arange(nodes) + 0.5) / nodes
    phi = (np.arange(nodes) + 0.5) / nodes * 2.0 * math.pi
    m, f = (v.ravel() for v in np.meshgrid(mu, phi))
    s = np.sqrt(1.0 - m * m)
    d = np.column_stack([s * np.sin(f), s * np.cos(f), m])
    area = path_area(grid_pad(), ORIGIN, SIZE, np.tile(SENSOR, (len(d), 1)), d)
    return float(2.0 * math.pi * LUMINANCE * np.mean(m * np.exp(-_g(m) * area)))


def rasterised_sphere(leaf: Trans, *, sensors: int) -> Scene:
    """The sphere of :func:`radtree.verify.turbid.crown_scene` as a voxel grid (module
    text), the same floor and sensors."""
    n = int(round(2 * RADIUS / SPHERE_VOXEL))
    sub = (np.arange(8) + 0.5) / 8
    offs = np.stack(np.meshgrid(sub, sub, sub, indexing="ij"), -1).reshape(-1, 3)
    idx = np.indices((n, n, n)).reshape(3, -1).T
    lo = np.array(CENTRE) - RADIUS
    share = np.empty(len(idx))
    for c in range(0, len(idx), 512):
        p = lo + (idx[c:c + 512, None, :] + offs[None]) * SPHERE_VOXEL
        share[c:c + 512] = np.mean(np.sum((p - CENTRE) ** 2, axis=2) <= RADIUS ** 2, axis=1)
    pad = (LAD * share).reshape(n, n, n)
    base = crown_scene(1.0, LAD, leaf, sensors=sensors)
    kind = leaf_kind(_lv(1.0), leaf.name)
    vox = VoxelCrowns.of(lo[None], size_m=SPHERE_VOXEL, pads=[pad], kinds=[kind])
    return Scene(base.meshes, base.materials, base.grids, media=vox)


def voxel_checks(*, rays: int = 8000, seed: int = 7, forward_photons: int = 100_000
                 ) -> list[Check]:
    """The checks of the module text, as :class:`~radtree.verify.checks.Check` rows (each
    logged, INFO)."""
    out: list[Check] = []
    black = Trans("black_leaf", 1e-9, 0.0, 0.0)
    scene = grid_scene(black, sensors=SENSORS)
    for z in (0.0, 30.0, 60.0):
        st = sky_state("none", altitude=90.0 - z, dni=DNI, ground_glow=False)
        got = trace(scene, st, _params(1, 16, seed))["facade"]
        value = float(got.lux[0]) / (DNI * math.cos(math.radians(z)))
        d = np.array([[0.0, math.sin(math.radians(z)), math.cos(math.radians(z))]])
        want = math.exp(-_g(d[:, 2])[0] * path_area(grid_pad(), ORIGIN, SIZE, SENSOR[None], d)[0])
        out.append(Check(f"voxel grid uncollided sun, zenith {z:g}° (piecewise Beer–Lambert)",
                         ENGINE, want, value, 0.01 * want))
    sky = sky_state("uniform", zenith_luminance=LUMINANCE, ground_glow=False)
    res = trace(scene, sky, _params(1, rays, seed))["facade"]
    want = sky_through_grid()
    out.append(Check("voxel grid uncollided sky (sampled free paths, DDA)", ENGINE, want,
                     float(res.lux.mean()), max(0.01 * want, 3.0 * _se(res))))
    sph = trace(crown_scene(1.0, LAD, black, sensors=SENSORS), sky,
                _params(1, rays, seed))["facade"]
    vox = trace(rasterised_sphere(black, sensors=SENSORS), sky, _params(1, rays, seed))["facade"]
    se = math.hypot(_se(sph), _se(vox))
    out.append(Check(f"voxel sphere ({SPHERE_VOXEL:g} m voxels) vs spheroid crown, same leaf "
                     "area, uncollided sky", ENGINE, float(sph.lux.mean()),
                     float(vox.lux.mean()), max(0.01 * float(sph.lux.mean()), 3.0 * se)))
    st = sky_state("uniform", zenith_luminance=LUMINANCE, ground_reflectance=1.0,
                   ground_glow=True)
    white = Trans("white_leaf", 0.4, 0.3, 0.3)
    res = trace(grid_scene(white, floor_m=0.005, spheroid=True), st,
                _params(40, rays // SENSORS, seed))["facade"]
    want = math.pi * LUMINANCE
    out.append(Check("voxel grid + spheroid energy conservation (white furnace, R 0.4 + T_d "
                     "0.3 + T_s 0.3 = 1)", ENGINE, want, float(res.lux[0]),
                     max(0.01 * want, 3.0 * _se(res))))
    out += forward_ledger(forward_photons, seed)
    return log_checks(out, log)


def forward_ledger(photons: int, seed: int = 7) -> list[Check]:
    """The forward engine through the grid (sun at zenith 30°, a 9 m beam, 36 horizontal
    1 m detectors 0.5 m up): black leaves — the detectors' mean against the Beer–Lambert
    transmission integrated over the same squares (the NumPy engine's exact direct sun at 256
    random points per square), within 1 % or 3 combined standard errors; grey leaves — the
    photon ledger balanced to 10⁻⁶ of the launched flux, and leaves absorbing."""
    from radtree.engines.forward import ForwardSettings, trace_forward

    xs = np.arange(-2.5, 3.0, 1.0)
    gx, gy = np.meshgrid(xs, xs)
    det = SensorGrid("facade", np.column_stack([gx.ravel(), gy.ravel(), np.full(36, 0.5)]),
                     np.tile([0.0, 0.0, 1.0], (36, 1)))
    st = sky_state("none", altitude=60.0, dni=DNI, ground_glow=False)
    out = []
    for leaf, bounces in ((Trans("black_leaf", 1e-9, 0.0, 0.0), 1),
                          (Trans("grey_leaf", 0.3, 0.2, 0.1), 8)):
        base = grid_scene(leaf)
        scene = Scene(base.meshes, base.materials, {"facade": det}, media=base.media)
        res = trace_forward(scene, st, ForwardSettings(
            photons=photons, max_bounces=bounces, batches=8, beam_diameter_m=9.0,
            patch_m=1.0, seed=seed))
        if bounces == 1:
            want, got, tol = uncollided_patches(res, scene, st, seed=seed)
            out.append(Check("voxel grid uncollided sun under the grid, forward vs "
                             "Beer–Lambert (36 squares)", "forward", want, got, tol))
            continue
        led = res.ledger
        out += [Check("voxel grid energy ledger (forward): |balance| / launched", "forward",
                      0.0, abs(led.balance) / led.launched, 1e-6),
                Check("voxel grid leaves absorb (forward): leaf share of the launched flux > 0",
                      "forward", 1.0, float(led.absorbed_by("grey_leaf") > 0), 0.0)]
    return out
