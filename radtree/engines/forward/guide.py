"""Guided diffuse scattering: part of every diffuse event's directions aimed at the detectors.

A photon diffusely reflected or transmitted far from the detectors (a sunlit street seen
through a crown) rarely heads towards them. With a :class:`Guide`, a diffuse event at a point
outside the guide sphere (centre: the target grid's centre, radius ``radius`` m) draws its new
direction from the mixture

    p(ω) = (1 − q) · cos θ / π  +  q · [ω inside the cone subtending the sphere] / Ω_cone,

(θ from the side's normal, Ω_cone = 2π (1 − cos α), sin α = radius / distance) and multiplies
the photon's flux by (cos θ / π) / p(ω) — the Lambertian density over the mixture's — so the
expected tally is unchanged for every detector. Cone directions behind the surface (cos θ ≤ 0)
get the factor 0: the photon stops and its flux is counted as killed. Inside the sphere (among
the detectors) scattering stays Lambertian. The photon still travels from the source; only
where its scattered directions go is importance-sampled.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from radtree.engines.common.sampling import cosine_hemisphere, orthonormal_basis


@dataclass(frozen=True)
class Guide:
    """Aim a share ``share`` (0–1) of diffuse directions at the sphere (``target``, m;
    ``radius``, m)."""

    target: np.ndarray
    radius: float
    share: float

    def directions(self, points: np.ndarray, axes: np.ndarray, rng: np.random.Generator
                   ) -> tuple[np.ndarray, np.ndarray]:
        """New unit directions for diffuse events at ``points`` on the side of unit ``axes``
        (the normal the scattered light leaves along) and each one's flux factor."""
        k = len(points)
        d = cosine_hemisphere(axes, rng)
        factor = np.ones(k)
        to = self.target - points
        dist = np.linalg.norm(to, axis=1)
        outside = dist > self.radius * 1.0001
        if not outside.any():
            return d, factor
        idx = np.flatnonzero(outside)
        c = to[idx] / dist[idx, None]
        cos_a = np.sqrt(np.maximum(0.0, 1.0 - (self.radius / dist[idx]) ** 2))
        aimed = rng.random(len(idx)) < self.share
        if aimed.any():
            a = np.flatnonzero(aimed)
            u = rng.random((2, len(a)))
            cz = 1.0 - u[0] * (1.0 - cos_a[a])
            sz = np.sqrt(np.maximum(0.0, 1.0 - cz * cz))
            phi = 2.0 * math.pi * u[1]
            t, b = orthonormal_basis(c[a])
            d[idx[a]] = (t * (sz * np.cos(phi))[:, None] + b * (sz * np.sin(phi))[:, None]
                         + c[a] * cz[:, None])
        w = d[idx]
        cos_t = np.einsum("ij,ij->i", w, axes[idx])
        in_cone = np.einsum("ij,ij->i", w, c) >= cos_a
        p_cos = np.maximum(cos_t, 0.0) / math.pi
        p_cone = in_cone / (2.0 * math.pi * np.maximum(1.0 - cos_a, 1e-12))
        mix = (1.0 - self.share) * p_cos + self.share * p_cone
        factor[idx] = np.where(mix > 0, p_cos / np.where(mix > 0, mix, 1.0), 0.0)
        return d, factor
