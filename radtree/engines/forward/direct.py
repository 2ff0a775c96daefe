"""The direct sun at the sensor points themselves (``engine.forward_direct_sun``).

A patch detector reports the illuminance averaged over its square; the backward engines and
Radiance report it at the sensor point. Where sun flecks through a crown are smaller than the
patch the two differ by far more than any noise: on the reference-case perforated dome at 12:30 the
NumPy engine reads 586 lx at the 8 sensor points and 3 304 lx averaged over their 0.5 m squares
(+464 %), 1 064 lx over 0.1 m squares (+81 %) (benchmarks/forward.py ``--patch-bias``).

So, with a whole-scene sun, the forward engine splits the light as a backward engine does:

* the **direct sun** — the sun's beam, undeviated (through specular transmissions only) — is
  computed at each sensor point, E = E_dn · max(0, n·s) · Π T_s, the product over the surfaces
  the ray from the point towards the sun crosses of their specular transmittance (``Trans``
  T_s, ``Glass`` T(θ) by Radiance's formulas, opaque surfaces 0), times the turbid crowns'
  mean transmittance exp(−τ) along it (as the NumPy engine's shadow rays): exact, no noise;
* sun photons are **not tallied** on the patches until their first diffuse event or mirror
  reflection (what remains is scattered light, smooth across a patch); sky and ground-glow
  photons likewise with ``engine.forward_direct_sky`` (their unscattered light estimated at the
  points by :mod:`.skypoint`, through the same :func:`transmittance`), else from the start.

Every lumen still travels (the ledger is unchanged); only what the patches count changes.
"""

from __future__ import annotations

import numpy as np

from radtree.engines.common.geometry import Geometry, Optics, glass_coefficients
from radtree.scene import SensorGrid

MAX_LAYERS = 64
"""Surfaces a ray towards the sun may cross (then it counts as blocked)."""


def transmittance(geo: Geometry, optics: Optics, origins: np.ndarray, dirs: np.ndarray
                  ) -> np.ndarray:
    """Undeviated transmittance along the rays ``origins + t·dirs`` (t > 0, unit ``dirs``,
    (k, 3) each): the product of the specular transmittances of the surfaces crossed (``Trans``
    T_s, ``Glass`` T(θ), opaque 0; more than :data:`MAX_LAYERS`: 0; the surface rays start a
    hair along ``dirs``) times the turbid crowns' mean transmittance exp(−τ) from ``origins``
    (as the NumPy engine's shadow rays)."""
    d = np.ascontiguousarray(np.broadcast_to(np.asarray(dirs, float), np.shape(origins)))
    tau = np.ones(len(d))
    if len(d) == 0:
        return tau
    eps = max(1e-5, 2e-6 * geo.size)
    o = np.asarray(origins, float) + eps * d
    live = np.arange(len(o))
    for _ in range(MAX_LAYERS):
        tri, t = geo.caster.first_hit(o[live], d[live])
        hit = tri >= 0
        if not hit.any():
            break
        live, tri, t = live[hit], tri[hit], t[hit]
        mat = geo.tri_material[tri]
        ts = optics.ts[mat].copy()
        glass = np.isfinite(optics.glass_tn[mat])
        if glass.any():
            cos_i = np.abs(np.einsum("ij,ij->i", geo.normals[tri[glass]], d[live[glass]]))
            ts[glass] = glass_coefficients(cos_i, optics.glass_tn[mat][glass])[0]
        tau[live] *= ts
        o[live] = o[live] + (t + eps)[:, None] * d[live]
        live = live[tau[live] > 0]
        if len(live) == 0:
            break
    else:
        tau[live] = 0.0
    if geo.media is not None:   # turbid crowns: their exact mean transmittance exp(−τ)
        on = np.flatnonzero(tau > 0)
        if len(on):
            tau[on] *= geo.media.transmittance(np.asarray(origins, float)[on], d[on])
    return tau


def direct_sun(geo: Geometry, optics: Optics, grid: SensorGrid, sun: np.ndarray,
               dni: float) -> np.ndarray:
    """Direct sun illuminance (lux) at each sensor point of ``grid``: ``dni`` (lux, normal to
    the beam) × cosine on the sensor's normal × the specular transmittance towards ``sun``
    (unit vector to the sun, x east, y north, z up)."""
    s = np.asarray(sun, float)
    s = s / np.linalg.norm(s)
    cos = np.asarray(grid.normals, float) @ s
    out = np.where(cos > 0, dni * cos, 0.0)
    idx = np.flatnonzero(out > 0)
    if len(idx) == 0:
        return out
    out[idx] *= transmittance(geo, optics, np.asarray(grid.points, float)[idx],
                              np.tile(s, (len(idx), 1)))
    return out
