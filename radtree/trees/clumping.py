"""Clumped foliage for the volume louvers crowns (``louvers.clumping`` Ω < 1) and the
clumping the photo fit estimates (``louvers.clumping_fit``).

The cluster model. Slats are grouped in spherical clusters of radius R
(``cluster_radius_m``): cluster centres uniform at random in the crown spheroid (a Poisson
process of n_c clusters per m³), each slat's centre uniform in the ball of its cluster, so
the leaf area density is u_c inside a cluster and u = n_c · (4/3)πR³ · u_c over the crown
(the crown's true density: clumping only moves slats, it adds none). A line of direction Ω̂
meets clusters as a Poisson process of n_c·πR² per metre; through one cluster at impact
parameter ρ it crosses a chord 2√(R² − ρ²) of turbid foliage, so — averaged over the
cluster's disc — it passes with probability

    P_w(τ) = ∫₀¹ exp(−τ√(1 − t)) dt = 2 (1 − (1 + τ) e^(−τ)) / τ²,   τ = 2R · u_c · G(Ω̂)

(τ the optical depth along a cluster's diameter). The gap probability over a path L is then
exp(−n_c πR² L (1 − P_w)) — Nilson's (1971) clumped (Neyman type A) gap law — which is
Beer–Lambert exp(−G·u·Ω·L) with the clumping index

    Ω(τ) = 3 (1 − P_w(τ)) / (2τ)          (1 at τ → 0, ≈ 3/(2τ) for dense clusters).

The parameter ``louvers.clumping`` is Ω at G = ½ (the mean projection of every leaf-angle
distribution over all directions), i.e. τ₀ = R·u_c; other directions have Ω(2τ₀·G(Ω̂))
(:func:`clumped_g`), so Ω varies a little with the view for non-spherical leaf angles.
Ω = 0.7 at R = 0.5 m is u_c ≈ 2 m²/m³ inside the clusters.

What a photo shows of it. Hemi's clumping index ``clumping_lx`` (Lang & Xiang 1986:
Miller's LAI on ring-mean gaps over the LAI on per-segment log-averaged gaps, hemispheR's
``LX``) measures the between-segment variance of the gaps that clusters comparable to a
segment's view cause. :func:`realised_gaps` draws cluster realisations of a fitted crown and
returns their ring × segment gaps, whose ``clumping_lx`` (:func:`lx_clumping`) the photo fit
(:mod:`radtree.trees.photo_clumping`) matches to the photo's. References: Nilson T. 1971,
Agric. Meteorol. 8, 25–38, doi:10.1016/0002-1571(71)90092-6; Lang A.R.G., Xiang Y. 1986,
Agric. For. Meteorol. 37, 229–243, doi:10.1016/0168-1923(86)90033-X; Chianucci F. et al.
2019, Can. J. For. Res. 49, doi:10.1139/cjfr-2018-0213 (hemispheR's LX, LXG1, LXG2).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq
from scipy.spatial import cKDTree

from radtree.hemi.metrics import DEFAULT_GAP_FLOOR, GapTable, RingGrid, lai_lang_xiang, lai_miller

TAU_MAX = 1e4


def sphere_transmission(tau: np.ndarray | float) -> np.ndarray:
    """P_w(τ): the disc-averaged transmission of a turbid sphere of diametral depth τ."""
    t = np.asarray(tau, float)
    small = t < 1e-3
    ts = np.where(small, 1.0, t)
    big = 2.0 * (1.0 - (1.0 + ts) * np.exp(-ts)) / (ts * ts)
    return np.where(small, 1.0 - 2.0 * t / 3.0 + t * t / 4.0, big)


def cluster_omega(tau: np.ndarray | float) -> np.ndarray:
    """Ω(τ) = 3 (1 − P_w(τ)) / (2τ) (1 at τ = 0)."""
    t = np.asarray(tau, float)
    small = t < 1e-3
    ts = np.where(small, 1.0, t)
    return np.where(small, 1.0 - 3.0 * t / 8.0,
                    1.5 * (1.0 - sphere_transmission(ts)) / ts)


def tau_of_omega(omega: float) -> float:
    """τ₀ with Ω(τ₀) = ``omega`` (0 for Ω = 1)."""
    if omega >= 1.0:
        return 0.0
    if not 0.0 < omega < 1.0:
        raise ValueError(f"clumping index must be in (0, 1], got {omega}")
    return float(brentq(lambda t: float(cluster_omega(t)) - omega, 1e-9, TAU_MAX,
                        xtol=1e-12))


def cluster_lad(omega: float, radius: float) -> float:
    """u_c (m²/m³): the leaf area density inside a cluster for clumping ``omega`` (at G = ½)."""
    return tau_of_omega(omega) / radius


def clumped_g(g: np.ndarray, omega: float) -> np.ndarray:
    """G·Ω of every direction: the effective projection of clumped slats (G unchanged at
    Ω = 1)."""
    if omega >= 1.0:
        return g
    tau0 = tau_of_omega(omega)
    return np.asarray(g * cluster_omega(2.0 * tau0 * np.asarray(g)), float)


def cluster_count(leaf_area: float, omega: float, radius: float) -> int:
    """Clusters holding ``leaf_area`` m² at density u_c (at least one)."""
    per = cluster_lad(omega, radius) * 4.0 / 3.0 * math.pi * radius ** 3
    return max(1, int(round(leaf_area / per)))


def _unit_ball(rng: np.random.Generator, n: int) -> np.ndarray:
    d = rng.standard_normal((n, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    return d * rng.random(n)[:, None] ** (1.0 / 3.0)


def cluster_centres(rng: np.random.Generator, n: int, centre: np.ndarray, a: float,
                    b: float) -> np.ndarray:
    """n cluster centres uniform in the spheroid (a, a, b) about ``centre`` (m)."""
    return np.asarray(centre, float) + _unit_ball(rng, n) * np.array([a, a, b])


def clustered_slat_centres(rng: np.random.Generator, offsets: np.ndarray, centre: np.ndarray,
                           a: float, b: float, slat_area: float, omega: float, radius: float
                           ) -> tuple[np.ndarray, int]:
    """Slat centres grouped in clusters: the k slats' ``offsets`` (uniform in the unit ball)
    scaled to the cluster radius about the centre of a cluster drawn at random for each
    slat (clusters uniform in the spheroid); also the number of clusters."""
    n_cl = cluster_count(len(offsets) * slat_area, omega, radius)
    cl = cluster_centres(rng, n_cl, centre, a, b)
    which = rng.integers(0, n_cl, len(offsets))
    return cl[which] + radius * offsets, n_cl


def realised_gaps(direction: np.ndarray, g: np.ndarray, weight: np.ndarray,
                  blocked: np.ndarray, camera: np.ndarray, crowns: np.ndarray, a: float,
                  b: float, lad: float, omega: float, radius: float,
                  rng: np.random.Generator, shape: tuple[int, int]) -> np.ndarray:
    """Ring × segment gaps of one realisation of clusters (crowns of density ``lad``):
    every sample ray (``direction`` (cells, samples, 3), local, from ``camera``) passes
    exp(−Σ u_c·G·chord) over the clusters it crosses (0 where ``blocked`` by a trunk)."""
    u_c = cluster_lad(omega, radius)
    volume = 4.0 / 3.0 * math.pi * a * a * b
    d = direction.reshape(-1, 3)
    tree = cKDTree(d)
    depth = np.zeros(len(d))
    for c in crowns:
        n = int(rng.poisson(lad * volume / (u_c * 4.0 / 3.0 * math.pi * radius ** 3)))
        if n == 0:
            continue
        rel = cluster_centres(rng, n, c, a, b) - camera          # (n, 3)
        dist = np.linalg.norm(rel, axis=1)
        # rays within the cluster's angular radius asin(R/dist) of its centre direction
        half = np.arcsin(np.clip(radius / np.maximum(dist, 1e-9), 0.0, 1.0))
        near = tree.query_ball_point(rel / dist[:, None], 2.0 * np.sin(half / 2.0) + 1e-9)
        counts = np.fromiter((len(x) for x in near), int, n)
        if not counts.any():
            continue
        ray = np.concatenate([np.asarray(x, int) for x in near if x])
        r = np.repeat(rel, counts, axis=0)
        t = np.einsum("ij,ij->i", d[ray], r)
        h2 = np.einsum("ij,ij->i", r, r) - t * t
        chord = np.where(t > 0.0, 2.0 * np.sqrt(np.clip(radius * radius - h2, 0.0, None)), 0.0)
        depth += np.bincount(ray, weights=chord, minlength=len(d))
    p = np.where(blocked.ravel(), 0.0, np.exp(-u_c * g.ravel() * depth)).reshape(weight.shape)
    return ((p * weight).sum(axis=1) / weight.sum(axis=1)).reshape(shape)


def lx_clumping(gaps: np.ndarray, grid: RingGrid, floor: float = DEFAULT_GAP_FLOOR) -> float:
    """Lang & Xiang's clumping index LAI_eff / LAI_LX of a rings × segments gap table, as
    :func:`radtree.hemi.metrics.canopy_metrics` computes it (NaN without foliage)."""
    z = np.zeros(gaps.shape)
    table = GapTable(grid, gaps, gaps, z.astype(np.int64), z.astype(np.int64), z)
    lx = lai_lang_xiang(table, floor)
    return lai_miller(table, floor) / lx if lx > 0 else math.nan
