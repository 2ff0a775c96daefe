"""Random discrete leaves for the physics suite: leaf-angle distributions, their G function,
and horizontally homogeneous layers of square leaves (after RAMI's abstract canopies).

Leaf inclination θ_L (normal from the vertical) has density f(θ_L) on [0, π/2] —
``spherical`` sin θ_L, ``planophile`` (2/π)(1 + cos 2θ_L), ``erectophile`` (2/π)(1 − cos 2θ_L)
(de Wit) — with a uniform azimuth. The projection function G(θ) = ∫ f(θ_L) ψ(θ, θ_L) dθ_L
(Ross), ψ = cos θ cos θ_L when |cot θ cot θ_L| ≥ 1, else cos θ cos θ_L (1 + (2/π)(tan τ − τ))
with τ = arccos(cot θ cot θ_L); spherical leaves have G = 0.5 in every direction. A layer of
leaf area index LAI then lets through the uncollided fraction exp(−G(θ)·LAI / cos θ) along a
direction of zenith angle θ (Beer–Lambert for Poisson-placed leaves).
"""

from __future__ import annotations

import math

import numpy as np

from radtree.engines.numpy.scenes import squares
from radtree.scene import Mesh

LEAF_DISTRIBUTIONS = ("spherical", "planophile", "erectophile")
_GRID = 4000  # quadrature / inverse-CDF points on [0, π/2]


def leaf_angle_density(distribution: str, theta_l: np.ndarray) -> np.ndarray:
    """f(θ_L) (per radian) of a leaf-angle distribution."""
    t = np.asarray(theta_l, float)
    if distribution == "spherical":
        return np.sin(t)
    if distribution == "planophile":
        return 2.0 / math.pi * (1.0 + np.cos(2.0 * t))
    if distribution == "erectophile":
        return 2.0 / math.pi * (1.0 - np.cos(2.0 * t))
    raise ValueError(f"leaf angle distribution must be one of {LEAF_DISTRIBUTIONS}, "
                     f"got {distribution!r}")


def _mid() -> np.ndarray:
    return (np.arange(_GRID) + 0.5) * (math.pi / 2) / _GRID


def g_function(distribution: str, zenith_deg: float) -> float:
    """Ross's G(θ): mean projected leaf area per unit leaf area along zenith angle θ."""
    th = math.radians(zenith_deg)
    tl = _mid()
    ct, st = math.cos(th), math.sin(th)
    cl, sl = np.cos(tl), np.sin(tl)
    with np.errstate(divide="ignore", invalid="ignore"):
        x = (ct / max(st, 1e-12)) * (cl / np.maximum(sl, 1e-12))  # cot θ · cot θ_L
    psi = ct * cl
    part = np.abs(x) < 1.0
    tau = np.arccos(np.clip(x[part], -1.0, 1.0))
    psi = np.array(psi, float)
    psi[part] = ct * cl[part] * (1.0 + 2.0 / math.pi * (np.tan(tau) - tau))
    f = leaf_angle_density(distribution, tl)
    dt = (math.pi / 2) / _GRID
    return float(np.sum(f * psi) * dt / (np.sum(f) * dt))


def uncollided_transmission(distribution: str, lai: float, zenith_deg: float) -> float:
    """exp(−G(θ)·LAI / cos θ)."""
    return math.exp(-g_function(distribution, zenith_deg) * lai
                    / math.cos(math.radians(zenith_deg)))


def sample_inclinations(distribution: str, k: int, rng: np.random.Generator) -> np.ndarray:
    """``k`` leaf inclinations (radians) drawn from the distribution (tabulated inverse CDF)."""
    tl = _mid()
    cdf = np.cumsum(leaf_angle_density(distribution, tl))
    cdf = np.concatenate([[0.0], cdf / cdf[-1]])
    edges = np.linspace(0.0, math.pi / 2, _GRID + 1)
    return np.interp(rng.random(k), cdf, edges)


def leaf_layer(name: str, material: str, *, lai: float, distribution: str, extent: float,
               z_bottom: float, z_top: float, size: float, rng: np.random.Generator) -> Mesh:
    """Square leaves of side ``size`` (m), Poisson-placed in the box ``extent`` × ``extent`` ×
    [z_bottom, z_top] (m), one-sided leaf area index ``lai``, inclinations from
    ``distribution``, random azimuths and spins."""
    k = int(rng.poisson(lai * extent * extent / (size * size)))
    xy = rng.uniform(-extent / 2, extent / 2, (k, 2))
    z = rng.uniform(z_bottom, z_top, k)
    inc = sample_inclinations(distribution, k, rng)
    az = rng.uniform(0.0, 2.0 * math.pi, k)
    normals = np.column_stack([np.sin(inc) * np.cos(az), np.sin(inc) * np.sin(az), np.cos(inc)])
    v, f = squares(np.column_stack([xy, z]), normals, size, rng.uniform(0, 2 * math.pi, k))
    return Mesh(name, material, v, f)
