"""Leaf (slat) inclination distributions for the volume crowns.

``fixed``: every slat normal is inclined ``louvers.inclination_deg`` from the vertical.
``ellipsoidal``: inclinations θ_L (normal from vertical = leaf from horizontal) drawn from
Campbell's (1990) ellipsoidal distribution of parameter x (``louvers.ellipsoid_x``),

    g(θ_L) ∝ sin θ_L / (cos²θ_L + x² sin²θ_L)²       (0 ≤ θ_L ≤ 90°)

(Campbell, G. S. 1990, Agric. For. Meteorol. 49, 173–176: x = 1 spherical, x > 1 planophile,
x < 1 erectophile), normalised numerically on :data:`BINS` bins and drawn by inverse CDF.
The projection G(μ) of a set of slats with random azimuths is the mean of the fixed-angle
closed form :func:`projection_g` (used by :mod:`radtree.trees.volume`) over the distribution
(:func:`mean_projection`), so the crown's extinction follows from the slats actually drawn,
not from Campbell's approximate K(θ, x).
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

BINS = 900


def _grid() -> np.ndarray:
    edges = np.linspace(0.0, 0.5 * math.pi, BINS + 1)
    return 0.5 * (edges[1:] + edges[:-1])


def inclination_pdf(x: float) -> tuple[np.ndarray, np.ndarray]:
    """(bin centres in radians, probabilities per bin) of the ellipsoidal distribution."""
    t = _grid()
    w = np.sin(t) / (np.cos(t) ** 2 + x * x * np.sin(t) ** 2) ** 2
    return t, w / w.sum()


def draw_inclinations(rng: np.random.Generator, n: int, x: float) -> np.ndarray:
    """``n`` inclinations (radians) from the ellipsoidal distribution (inverse CDF, one
    uniform per slat: a nearby x gives nearby angles for the same seed)."""
    t, p = inclination_pdf(x)
    cdf = np.concatenate([[0.0], np.cumsum(p)])
    edges = np.linspace(0.0, 0.5 * math.pi, BINS + 1)
    return np.interp(rng.random(n), cdf, edges)


def mean_tilt(x: float) -> float:
    """Mean inclination (degrees) of the distribution (exact on the bins)."""
    t, p = inclination_pdf(x)
    return float(np.degrees(t @ p))


MU_TABLE = 401   # μ nodes of the tabulated fixed-angle projections


@lru_cache(maxsize=1)
def _projection_table() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(μ nodes, 90 coarse inclinations in radians, G table (angles × μ))."""
    t = _grid()
    step = max(1, BINS // 90)
    tt = t.reshape(-1, step).mean(axis=1)
    mu = np.linspace(0.0, 1.0, MU_TABLE)
    table = np.stack([projection_g(mu, math.degrees(a)) for a in tt])
    return mu, tt, table


def mean_projection(mu: np.ndarray, x: float) -> np.ndarray:
    """G(μ) = E over θ_L of the fixed-angle projection for |Ω_z| = μ (90 inclination classes,
    tabulated on :data:`MU_TABLE` values of μ and interpolated linearly)."""
    nodes, _, table = _projection_table()
    _, p = inclination_pdf(x)
    step = max(1, BINS // 90)
    pp = p.reshape(-1, step).sum(axis=1)
    g = pp @ table
    mu = np.atleast_1d(np.abs(np.asarray(mu, float)))
    return np.interp(mu, nodes, g)


def projection_g(mu: float | np.ndarray, inclination_deg: float) -> np.ndarray:
    """G = mean over a uniform azimuth of |m·Ω| for slat normals inclined α from vertical and
    a direction Ω with |Ω_z| = mu (closed form): with p = μ cos α, q = √(1 − μ²) sin α,
    G = p when q ≤ p, else (2/π)(q √(1 − p²/q²) + p·asin(p/q))."""
    a = math.radians(inclination_deg)
    mu = np.abs(np.asarray(mu, float))
    p = mu * math.cos(a)
    q = np.sqrt(np.clip(1.0 - mu * mu, 0.0, 1.0)) * math.sin(a)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.where(q > p, p / np.where(q > 0, q, 1.0), 1.0)
        g = (2.0 / math.pi) * (q * np.sqrt(np.clip(1.0 - r * r, 0.0, 1.0)) + p * np.arcsin(r))
    return np.where(q > p, g, p)
