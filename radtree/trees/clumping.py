"""Clumped foliage for the volume louvers crowns (``louvers.clumping`` Ω < 1) and the
clumping the photo fit estimates (``louvers.clumping_fit``).

The cluster model. Slats are grouped in spherical clusters of radius R
(``cluster_radius_m``): cluster centres uniform at random in the crown spheroid (a Poisson
process of n_c clusters per m³), each slat's centre uniform in the ball of a cluster drawn at
random for it, m slats per cluster on average — so the crown keeps its true leaf area density
u = n_c·m·s² (clumping moves slats, it adds none). Seen along a direction of mean slat
projection G, one slat covers a projected area A = s²·G; a line at impact point ρ from a
cluster's centre misses all its slats with probability exp(−m·p(ρ)), p = f ⊛ 1_A the
cluster's projected slat-centre density f(ρ) = 2√(R² − ρ²) / (4/3 πR³) smoothed by the
projected slat (a disc of area A): the Boolean model, exact for Poisson slat counts and any
slat size. The cluster's cross-section is σ = ∫(1 − exp(−m·p)) d²ρ, so lines meet blocking
clusters at n_c·σ per metre and the gap probability over a path L is

    exp(−n_c·σ·L) = exp(−G·u·Ω·L),    Ω = σ / (m·A)            (:func:`cluster_omega`)

— Nilson's (1971) clumped (Neyman type A) gap law; for slats small against R it tends to the
turbid sphere's Ω(τ) = 3(1 − P(τ))/(2τ), P(τ) = 2(1 − (1 + τ)e^(−τ))/τ², τ = 2R·u_c·G. The
parameter ``louvers.clumping`` is Ω at G = ½ (the mean projection of every leaf-angle
distribution over all directions); it sets m (:func:`slats_per_cluster`); other directions
have Ω(G) (:func:`clumped_g`), so Ω varies a little with the view for non-spherical leaves.

What a photo shows of it. Hemi's ``clumping_lx`` (Lang & Xiang 1986: Miller's LAI on ring-mean
gaps over the LAI on per-segment log-averaged gaps; hemispheR's ``LX``) measures the
between-segment variance of the gaps. :func:`cast_slats` ray-casts realisations of the
generator's slats (:func:`radtree.trees.volume.draw_crown_slats`) along a photo's cell sample
directions; :func:`lx_clumping` computes their clumping_lx as hemi does, which the photo fit
(:func:`radtree.trees.photo_fit.fit_omega`) matches to the photo's. References: Nilson T.
1971, Agric. Meteorol. 8, 25–38, doi:10.1016/0002-1571(71)90092-6; Lang A.R.G., Xiang Y. 1986,
Agric. For. Meteorol. 37, 229–243, doi:10.1016/0168-1923(86)90033-X; Chianucci F. et al. 2019,
Can. J. For. Res. 49, doi:10.1139/cjfr-2018-0213 (hemispheR's LX, LXG1, LXG2).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from functools import lru_cache

import numpy as np

from radtree.hemi.metrics import DEFAULT_GAP_FLOOR, GapTable, RingGrid, lai_lang_xiang, lai_miller

GRID_CELLS = 96          # projection grid of one cluster, cells across its diameter
G_TABLE = np.linspace(0.02, 1.0, 50)   # slat projections Ω(G) is tabulated at


@lru_cache(maxsize=256)
def cluster_omega(m: float, radius: float, slat: float, g: float) -> float:
    """Ω of clusters of ``m`` slats (side ``slat`` m) in balls of ``radius`` m, seen along a
    direction of mean slat projection ``g``: σ / (m·A) on a projection grid."""
    area = slat * slat * g
    r_s = math.sqrt(area / math.pi)
    half = radius + r_s
    h = 2.0 * half / GRID_CELLS
    ax = (np.arange(GRID_CELLS) + 0.5) * h - half
    xx, yy = np.meshgrid(ax, ax, indexing="ij")
    rho2 = xx * xx + yy * yy
    f = 2.0 * np.sqrt(np.clip(radius * radius - rho2, 0.0, None)) / (4.0 / 3.0 * math.pi
                                                                      * radius ** 3)
    k = int(math.ceil(r_s / h))
    kx = np.arange(-k, k + 1) * h
    kxx, kyy = np.meshgrid(kx, kx, indexing="ij")
    disc = (kxx * kxx + kyy * kyy <= r_s * r_s).astype(float)
    disc *= area / max(disc.sum() * h * h, 1e-30)      # exact area on the grid
    n = GRID_CELLS + disc.shape[0]           # zero-padded: no wrap-around
    full = np.fft.irfft2(np.fft.rfft2(f * h * h, (n, n)) * np.fft.rfft2(disc, (n, n)), (n, n))
    p = full[k:k + GRID_CELLS, k:k + GRID_CELLS]   # "same" part, centred on the cluster
    p *= 1.0 / max(p.sum() * h * h, 1e-30) * area        # ∫p = A
    sigma = float((1.0 - np.exp(-m * p)).sum() * h * h)
    return sigma / (m * area) if m > 0 else 1.0


def slats_per_cluster(omega: float, radius: float, slat: float) -> float:
    """m with Ω(m) = ``omega`` at G = ½ (0 for Ω = 1: no clusters)."""
    if omega >= 1.0:
        return 0.0
    lo, hi = 1e-3, 1e6

    def miss(m: float) -> float:
        return cluster_omega(float(m), radius, slat, 0.5) - omega

    if miss(hi) > 0:
        raise ValueError(f"clumping {omega} is out of reach of clusters of radius {radius} m")
    from scipy.optimize import brentq  # here: ~0.5 s to import

    return float(brentq(miss, lo, hi, xtol=1e-6, rtol=1e-8))


@lru_cache(maxsize=64)
def _omega_table(omega: float, radius: float, slat: float) -> np.ndarray:
    m = slats_per_cluster(omega, radius, slat)
    return np.array([cluster_omega(m, radius, slat, float(g)) for g in G_TABLE])


def clumped_g(g: np.ndarray, omega: float, radius: float = 0.5, slat: float = 0.3
              ) -> np.ndarray:
    """G·Ω(G) of every direction: the effective projection of clumped slats (G itself at
    Ω = 1)."""
    if omega >= 1.0:
        return g
    table = _omega_table(float(omega), float(radius), float(slat))
    ga = np.asarray(g, float)
    return np.asarray(ga * np.interp(ga, G_TABLE, table), float)


def cluster_lad(omega: float, radius: float, slat: float) -> float:
    """u_c (m²/m³): the mean leaf area density inside a cluster's ball."""
    return slats_per_cluster(omega, radius, slat) * slat * slat / (4.0 / 3.0 * math.pi
                                                                   * radius ** 3)


def _unit_ball(rng: np.random.Generator, n: int) -> np.ndarray:
    d = rng.standard_normal((n, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    return d * rng.random(n)[:, None] ** (1.0 / 3.0)


def clustered_slat_centres(rng: np.random.Generator, offsets: np.ndarray, centre: np.ndarray,
                           *, to_crown: Callable[[np.ndarray], np.ndarray], slat: float,
                           omega: float, radius: float) -> tuple[np.ndarray, int]:
    """Slat centres grouped in clusters: the k slats' ``offsets`` (uniform in the unit ball)
    scaled to the cluster radius about a cluster drawn at random for each slat (cluster
    centres uniform in the crown about ``centre``: ``to_crown`` maps points uniform in the
    unit ball to offsets uniform in the crown, e.g. ×(a, a, b) for a spheroid; k/m of them);
    also the number of clusters."""
    n_cl = max(1, int(round(len(offsets) / slats_per_cluster(omega, radius, slat))))
    cl = np.asarray(centre, float) + to_crown(_unit_ball(rng, n_cl))
    which = rng.integers(0, n_cl, len(offsets))
    return cl[which] + radius * offsets, n_cl


def cast_slats(direction: np.ndarray, camera: np.ndarray, centres: np.ndarray,
               e1: np.ndarray, e2: np.ndarray, slat: float) -> np.ndarray:
    """Which rays (``direction`` (k, 3) unit, from ``camera``) hit a square slat (centres,
    unit edge vectors e1, e2, side ``slat``): candidate pairs within the slat's angular radius
    (k-d trees of the ray and slat directions, slats binned by that radius), then the exact
    ray–square test."""
    from scipy.spatial import cKDTree

    hit = np.zeros(len(direction), bool)
    if len(centres) == 0:
        return hit
    rays = cKDTree(direction)
    rel = centres - camera
    dist = np.linalg.norm(rel, axis=1)
    half = np.arcsin(np.clip(slat / math.sqrt(2.0) / np.maximum(dist, 1e-9), 0.0, 1.0))
    chord = 2.0 * np.sin(half / 2.0) + 1e-9
    unit = rel / dist[:, None]
    edges = np.quantile(chord, [0.0, 0.5, 0.8, 0.95, 1.0])
    for lo, hi in zip(edges[:-1], edges[1:]):
        sel = np.flatnonzero((chord >= lo) & (chord <= hi))
        if len(sel) == 0:
            continue
        pairs = cKDTree(unit[sel]).sparse_distance_matrix(rays, float(hi),
                                                          output_type="ndarray")
        s_idx, ray = sel[pairs["i"]], pairs["j"]
        normal = np.cross(e1[s_idx], e2[s_idx])
        d = direction[ray]
        den = np.einsum("ij,ij->i", d, normal)
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.einsum("ij,ij->i", rel[s_idx], normal) / den
        q = t[:, None] * d - rel[s_idx]
        ok = ((t > 0) & (np.abs(np.einsum("ij,ij->i", q, e1[s_idx])) <= slat / 2)
              & (np.abs(np.einsum("ij,ij->i", q, e2[s_idx])) <= slat / 2))
        hit[ray[ok]] = True
    return hit


def lx_clumping(gaps: np.ndarray, grid: RingGrid, floor: float = DEFAULT_GAP_FLOOR) -> float:
    """Lang & Xiang's clumping index LAI_eff / LAI_LX of a rings × segments gap table, as
    :func:`radtree.hemi.metrics.canopy_metrics` computes it (NaN without foliage)."""
    z = np.zeros(gaps.shape)
    table = GapTable(grid, gaps, gaps, z.astype(np.int64), z.astype(np.int64), z)
    lx = lai_lang_xiang(table, floor)
    return lai_miller(table, floor) / lx if lx > 0 else math.nan
