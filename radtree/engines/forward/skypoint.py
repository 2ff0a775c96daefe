"""The unscattered sky at the sensor points (``engine.forward_direct_sky``).

A sky photon that reaches a patch without scattering carries its launched flux: behind a
crown the few that pass straight through its gaps are the heaviest crossings of all. On the
reference street's free crowns (scenario F at 12:30, ``benchmarks/forward.py --lineage 8``)
the sky photons launched within 1 m of the line through the target held 43 % of the façade's
variance, ten of 13 696 of them 61 % of that ring's light — a run short of them read ~3 % low
with a normal-looking error. And a patch averages what Radiance and the backward engines
report at the sensor point.

So, as for the direct sun (:mod:`.direct`), the light is split the way a backward tracer
splits it — "direct lighting" by next-event estimation (Veach 1997, *Robust Monte Carlo
methods for light transport simulation*, PhD thesis, Stanford, ch. 9; cited from memory):

* the **unscattered sky** — sky and ground-glow luminance seen from the point through
  specular transmissions only — is estimated at each sensor point,
  E = ∫ L(ω) T(ω) cos⁺θ dω, T the undeviated transmittance towards ω
  (:func:`.direct.transmittance`: ``Trans`` T_s, ``Glass`` T(θ), turbid exp(−τ)), the NumPy
  engine's escaping zero-bounce paths; and
* sky photons are **not tallied** on the patches until their first diffuse event or mirror
  reflection (as the sun's: :attr:`Photons.direct`).

The integral is sampled from a defensive mixture (Hesterberg 1995, "Weighted average
importance sampling and defensive mixture distributions", Technometrics 37(2); cited from
memory): with probability ``COSINE_SHARE`` ∝ cos θ about the sensor's normal, otherwise from
the environment's luminance table restricted to the sensor's hemisphere (cells ∝ L·cos⁺ at
their centres, uniform within a cell). The estimate L·T·cos⁺ / p is then bounded by
π L T / ``COSINE_SHARE`` whatever the table, and unbiased. Every batch of every round gets
its own independent directions, so the batches' spread includes this estimator's error.
"""

from __future__ import annotations

import math

import numpy as np

from radtree.engines.common.geometry import Geometry, Optics
from radtree.engines.common.sampling import cosine_directions
from radtree.engines.forward.direct import transmittance
from radtree.engines.forward.sources import EnvironmentSource
from radtree.scene import SensorGrid

COSINE_SHARE = 0.3
"""Share of the directions drawn ∝ cos θ (the rest from the luminance table)."""
CHUNK = 1 << 18
"""Directions traced at once (bounded memory)."""


def _table(env: EnvironmentSource, normal: np.ndarray) -> np.ndarray | None:
    """Probabilities of the table's cells for a sensor of unit ``normal``: ∝ L · cos⁺ at the
    cell centres (None: the hemisphere's cells are all dark)."""
    weight = env.cell_l * np.maximum(env.cell_dirs @ normal, 0.0)
    total = float(weight.sum())
    return weight / total if total > 0 else None


def _draw(env: EnvironmentSource, normal: np.ndarray, prob: np.ndarray | None, k: int,
          rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``k`` unit directions towards the sky for a sensor of unit ``normal`` from the
    mixture, their cos⁺ on ``normal`` and the mixture's density at each (per steradian)."""
    share = 1.0 if prob is None else COSINE_SHARE
    normals = np.broadcast_to(normal, (k, 3))
    w = cosine_directions(rng.random(k), rng.random(k), normals)
    if prob is not None:
        table = rng.random(k) >= share
        w[table] = env.draw_cells(np.cumsum(prob), int(table.sum()), rng)[0]
    cos = np.maximum(w @ normal, 0.0)
    pdf = share * cos / math.pi
    if prob is not None:
        pdf = pdf + (1.0 - share) * prob[env.cell_of(w)] / env.omega
    return w, cos, pdf


def direct_sky(geo: Geometry, optics: Optics, grid: SensorGrid, env: EnvironmentSource,
               rays: int, batches: int, rng: np.random.Generator) -> np.ndarray:
    """(batches, sensors) estimates of the unscattered sky's illuminance (lux) at each sensor
    point of ``grid``, each batch from its own ``rays`` directions per sensor."""
    pts = np.asarray(grid.points, float)
    nrm = np.asarray(grid.normals, float)
    out = np.zeros((batches, len(pts)))
    keys = np.round(nrm, 9)
    for key in np.unique(keys, axis=0):   # sensors sharing a normal share the table
        same = np.flatnonzero((keys == key).all(axis=1))
        normal = nrm[same[0]]
        prob = _table(env, normal)
        step = max(1, CHUNK // (batches * rays))
        for c0 in range(0, len(same), step):
            idx = same[c0:c0 + step]
            f = _samples(geo, optics, env, (normal, prob),
                         np.repeat(pts[idx], batches * rays, axis=0), rng)
            out[:, idx] = f.reshape(len(idx), batches, rays).mean(axis=2).T
    return out


def _samples(geo: Geometry, optics: Optics, env: EnvironmentSource,
             table: tuple[np.ndarray, np.ndarray | None], origins: np.ndarray,
             rng: np.random.Generator) -> np.ndarray:
    """One estimate L·T·cos⁺ / p (lux) per row of ``origins`` (points sharing the ``table``'s
    normal and cell probabilities)."""
    normal, prob = table
    k = len(origins)
    w, cos, pdf = _draw(env, normal, prob, k, rng)
    f = np.zeros(k)
    live = np.flatnonzero((cos > 0) & (pdf > 0))
    f[live] = np.asarray(env.luminance(w[live]), float) * cos[live] / pdf[live]
    go = live[f[live] > 0]
    if len(go):
        f[go] *= transmittance(geo, optics, origins[go], w[go])
    return f
