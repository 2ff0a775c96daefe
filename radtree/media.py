"""Turbid-medium crowns as plain scene data (``[tree] representation = "turbid"``).

A turbid crown is a volume of leaves described statistically instead of leaf by leaf: an
envelope (a spheroid of horizontal semi-axis a and vertical semi-axis b about a centre, x east,
y north, z up, metres, optionally cut by half-spaces) filled with one-sided leaf area density
u (m²/m³). A straight path of length L through it meets leaves at the rate

    σ(Ω) = u · G(Ω) · Ω_c(G)      (per metre)

G(Ω) the leaves' mean projection along the direction Ω (the G-function of the leaf angle
distribution, azimuths uniform; it depends only on μ = |Ω_z|), Ω_c the clumping index (1 =
leaves at random), so the uncollided (gap) probability is exp(−σ L) — the Beer–Lambert law of
canopy radiative transfer (Ross 1981, *The Radiation Regime and Architecture of Plant Stands*,
ch. 2; Nilson 1971 for the clumped form). At a collision the leaf met has a normal drawn from
the leaf angle distribution weighted by |n·Ω| (the leaves a beam meets are seen in
projection) and scatters as a bi-Lambertian leaf: diffuse reflectance R, diffuse
transmittance T_d, and an undeviated share T_s — the optics of the crown's leaf material
(a :class:`radtree.optics.Trans`, the same material the explicit slats use).

Memory: a crown is a few numbers (centre, axes, density, kind, clip planes), whatever its
leaf count. The engines that trace media sample free paths through them
(:mod:`radtree.engines.common.turbid`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class LeafKind:
    """What the leaves of one group of crowns are like (a species, or the project's slats).

    ``material``: the scene material of the leaves (``Trans``: R, T_d, T_s). ``mu``: nodes of
    μ = |Ω_z| in [0, 1] (increasing); ``g_eff``: G(μ)·Ω_c(G) at those nodes (the effective
    projection, clumping included). ``incl_edges`` / ``incl_cdf``: the leaf-normal
    inclination from the vertical (radians, 0 … π/2) as a cumulative distribution at those
    edges, to draw the normals of the leaves met. ``clumping``: Ω_c at G = ½ (for notes)."""

    material: str
    mu: np.ndarray
    g_eff: np.ndarray
    incl_edges: np.ndarray
    incl_cdf: np.ndarray
    clumping: float = 1.0

    def __post_init__(self) -> None:
        if len(self.mu) != len(self.g_eff) or len(self.mu) < 2:
            raise ValueError(f"leaf kind '{self.material}': one G per μ node, at least two")
        if np.any(np.diff(self.mu) <= 0) or self.mu[0] > 0 or self.mu[-1] < 1:
            raise ValueError(f"leaf kind '{self.material}': μ nodes must rise over [0, 1]")
        if len(self.incl_edges) != len(self.incl_cdf) or abs(self.incl_cdf[-1] - 1) > 1e-9:
            raise ValueError(f"leaf kind '{self.material}': inclination CDF must end at 1")

    def g(self, mu: np.ndarray) -> np.ndarray:
        """G(μ)·Ω_c at ``mu`` (linear interpolation between the nodes)."""
        return np.interp(np.abs(mu), self.mu, self.g_eff)


@dataclass
class TurbidCrowns:
    """Spheroidal turbid crowns: ``centres`` (n, 3) m, semi-axes ``a`` (horizontal) and ``b``
    (vertical) (n,) m, leaf area density ``lad`` (n,) m²/m³, ``kind`` (n,) index into
    ``kinds``; ``planes`` (n, p, 4): each crown keeps the points x with n·x ≥ c for each row
    (n_x, n_y, n_z, c) — the wall-side and shared-neighbour cuts of a crown row (rows of zeros
    with c = −1 keep everything)."""

    centres: np.ndarray
    a: np.ndarray
    b: np.ndarray
    lad: np.ndarray
    kind: np.ndarray
    kinds: list[LeafKind]
    planes: np.ndarray = field(default_factory=lambda: np.zeros((0, 0, 4)))

    def __post_init__(self) -> None:
        """Scalars broadcast to one per crown: after this every field is an array."""
        self.centres = np.asarray(self.centres, float).reshape(-1, 3)
        n = len(self.centres)
        self.a = np.broadcast_to(np.asarray(self.a, float), (n,)).copy()
        self.b = np.broadcast_to(np.asarray(self.b, float), (n,)).copy()
        self.lad = np.broadcast_to(np.asarray(self.lad, float), (n,)).copy()
        self.kind = np.broadcast_to(np.asarray(self.kind, np.int64), (n,)).copy()
        planes = np.asarray(self.planes, float)
        self.planes = (np.zeros((n, 0, 4)) if planes.size == 0 else planes.reshape(n, -1, 4))
        if np.any(self.a <= 0) or np.any(self.b <= 0):
            raise ValueError("turbid crowns: semi-axes must be positive")
        if np.any(self.lad < 0) or not np.all(np.isfinite(self.lad)):
            raise ValueError("turbid crowns: leaf area density must be finite and ≥ 0")
        if n and (self.kind.min() < 0 or self.kind.max() >= len(self.kinds)):
            raise ValueError("turbid crowns: a crown's kind is not among the leaf kinds")

    @classmethod
    def of(cls, centres: np.ndarray, a: float | np.ndarray, b: float | np.ndarray,
           lad: float | np.ndarray, kind: int | np.ndarray, kinds: list[LeafKind],
           planes: np.ndarray | None = None) -> TurbidCrowns:
        """Crowns from per-crown arrays or scalars shared by all."""
        return cls(np.asarray(centres, float), np.asarray(a, float), np.asarray(b, float),
                   np.asarray(lad, float), np.asarray(kind, np.int64), kinds,
                   np.zeros((0, 0, 4)) if planes is None else planes)

    def __len__(self) -> int:
        return len(self.centres)

    @property
    def materials(self) -> list[str]:
        return [k.material for k in self.kinds]

    def inside(self, points: np.ndarray) -> np.ndarray:
        """(k, n) whether each point lies in each crown (the spheroid and its half-spaces)."""
        p = np.asarray(points, float).reshape(-1, 3)
        rel = (p[:, None, :] - self.centres[None]) / np.stack([self.a, self.a, self.b], 1)[None]
        ok = np.einsum("kni,kni->kn", rel, rel) <= 1.0
        for j in range(self.planes.shape[1]):
            pl = self.planes[:, j]
            ok &= p @ pl[:, :3].T >= pl[:, 3][None]
        return ok

    def leaf_area(self, samples: int = 200_000, seed: int = 0) -> float:
        """One-sided leaf area (m²) of all crowns: Σ u·V, V by Monte Carlo when clipped."""
        vol = 4.0 / 3.0 * np.pi * self.a ** 2 * self.b
        if self.planes.shape[1]:
            rng = np.random.default_rng(seed)
            x = rng.standard_normal((samples, 3))
            x *= (rng.random(samples) ** (1 / 3) / np.linalg.norm(x, axis=1))[:, None]
            for i in range(len(self)):
                p = self.centres[i] + x * [self.a[i], self.a[i], self.b[i]]
                keep = np.ones(samples, bool)
                for pl in self.planes[i]:
                    keep &= p @ pl[:3] >= pl[3]
                vol[i] *= keep.mean()
        return float(np.sum(self.lad * vol))
