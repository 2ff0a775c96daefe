"""Layered louvers of free-standing crowns (the ``layers`` arrangement; optics, readings and
the assembled crown: :mod:`radtree.trees.louvers`).

``layers`` nested lens-shaped surfaces inside each spheroid,
z_k(ρ) = z_c + h(ρ)·(2(k + ½)/N − 1) with h(ρ) = b·√(1 − ρ²/a²) (a crown following its
outline: a → r(θ), :mod:`radtree.trees.outline`), so every vertical line
through a crown crosses each layer exactly once. Slats are exact squares of side s with their
tilt axis along the rows, so their plan projections are s × s·cos α rectangles; rows are
s·cos α apart with a random heading per layer: a vertical beam meets a slat in each layer
with probability exactly f. Branch steps are s·tan β/f (at most a quarter of the local layer
spacing). Slats that would leave the spheroid, come within 4·s·sin α of the next layer
(near the rim) or cut the trunk are dropped; slats crossing the wall-side clip plane or the
plane shared with a neighbour crown are cut there. Bound (:func:`free_slat_bound`):
slats ≤ count · N · π(a + s)² f / (s² cos α); triangles ≤ 3 × that bound (cut slats have up
to 6 corners). Near-horizontal views from a façade sensor cross far fewer than N layers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from radtree.config import Louvers
from radtree.errors import ConfigError
from radtree.trees.crown_clip import cut_to_share, touches_share, trunk_clash
from radtree.trees.envelope import CrownRowSpec
from radtree.trees.model import MAX_SLATS

BRANCH_SLATS = 3


def free_slat_bound(spec: CrownRowSpec, lv: Louvers) -> int:
    """Upper bound on the number of slats of the free form (documented, tested)."""
    s = lv.slat_size_m
    cos_a = max(math.cos(math.radians(lv.inclination_deg)), 0.05)
    per_layer = math.pi * (spec.max_radius + s) ** 2 * lv.cover_fraction / (s * s * cos_a)
    return int(math.ceil(spec.count * lv.layers * per_layer))


@dataclass(frozen=True)
class _FreeGrid:
    """The slat grid of every layer (m): slat side ``s``, cover ``f``, ``N`` layers, tilt
    tangent and cosine, cell pitch along (``dx``) and across (``dy``) the rows, branch climb
    per cell and the least layer spacing that keeps slats apart."""

    s: float
    f: float
    N: int
    tana: float
    cosa: float
    dx: float
    dy: float
    climb: float
    min_spacing: float

    @classmethod
    def of(cls, lv: Louvers) -> _FreeGrid:
        s, f = lv.slat_size_m, lv.cover_fraction
        alpha = math.radians(lv.inclination_deg)
        dx = s / f
        return cls(s, f, lv.layers, math.tan(alpha), math.cos(alpha), dx, s * math.cos(alpha),
                   dx * math.tan(math.radians(lv.branch_inclination_deg)),
                   4.0 * s * math.sin(alpha) + 0.05)


def build_free_louvers(spec: CrownRowSpec, lv: Louvers, source: str | None = None
                       ) -> tuple[list[np.ndarray], dict[str, float]]:
    """Slat polygons (local coordinates) of the free form and geometry info: check the
    bound, then lay every crown's layers (one seeded stream per crown and layer)."""
    bound = free_slat_bound(spec, lv)
    if bound > MAX_SLATS:
        raise ConfigError(f"the louvers would need up to {bound} slats (limit {MAX_SLATS}): "
                          "use larger slats (tree.louvers.slat_size_m) or fewer layers",
                          source=source, field="tree.louvers.slat_size_m")
    grid = _FreeGrid.of(lv)
    if grid.dy <= 1e-9:
        raise ConfigError("vertical slats (inclination 90°) cannot cover a horizontal layer",
                          source=source, field="tree.louvers.inclination_deg")
    ss = np.random.SeedSequence(lv.seed)
    polys: list[np.ndarray] = []
    dropped = 0
    cut = 0
    for ti, child in enumerate(ss.spawn(spec.count)):
        for layer, lchild in enumerate(child.spawn(grid.N)):
            kept, n_cut, n_dropped = _layer_slats(spec, ti=ti, layer=layer, grid=grid,
                                                  rng=np.random.default_rng(lchild))
            polys.extend(kept)
            cut += n_cut
            dropped += n_dropped
    s, b = grid.s, spec.b
    info = {"slat_bound": float(bound), "slats_cut": float(cut), "slats_dropped": float(dropped),
            "slat_mean_area_m2": s * s, "layer_spacing_axis_m": 2.0 * b / grid.N,
            "branch_step_m": grid.climb}
    return polys, info


def _layer_slats(spec: CrownRowSpec, *, ti: int, layer: int, grid: _FreeGrid,
                 rng: np.random.Generator) -> tuple[list[np.ndarray], int, int]:
    """One layer of crown ``ti``: (kept slat polygons, slats cut, slats dropped)."""
    s, N, dx, dy = grid.s, grid.N, grid.dx, grid.dy
    a, b = spec.max_radius, spec.b
    c = spec.centres[ti]
    lo, hi = spec.strips[ti]
    psi = rng.uniform(0.0, 2.0 * math.pi)
    ex = np.array([math.cos(psi), math.sin(psi)])
    ey = np.array([-math.sin(psi), math.cos(psi)])
    oy = rng.uniform(0.0, 1.0)
    nj = int(math.ceil((a + s) / dy)) + 1
    ni = int(math.ceil((a + s) / dx)) + 1
    row_offset = rng.uniform(0.0, 1.0, 2 * nj + 1)
    jj, ii = np.meshgrid(np.arange(-nj, nj + 1), np.arange(-ni, ni + 1), indexing="ij")
    J, Ii = jj.ravel(), ii.ravel()
    # rows packed across (height s·cosα = one slat); along a row cells of s/f, one
    # slat of side s at a random place in each; every row at a random offset
    xs = (Ii + row_offset[J + nj]) * dx + rng.uniform(-0.5, 0.5, len(J)) * (dx - s)
    ys = (J + oy) * dy
    sigma = rng.choice([-1.0, 1.0], len(J))
    plan = c[:2][None, :] + xs[:, None] * ex + ys[:, None] * ey
    rho = np.hypot(plan[:, 0] - c[0], plan[:, 1] - c[1])
    r = spec.reach(plan - c[:2])   # a, or the outline's r(θ)
    ok = rho < r
    h = b * np.sqrt(np.clip(1.0 - (rho / r) ** 2, 0.0, 1.0))
    spacing = 2.0 * h / N
    z_layer = c[2] + h * (2.0 * (layer + 0.5) / N - 1.0)
    q = np.mod(Ii, BRANCH_SLATS) - (BRANCH_SLATS - 1) / 2.0
    step = np.minimum(grid.climb, 0.25 * spacing / max((BRANCH_SLATS - 1) / 2.0, 1.0))
    zc = z_layer + q * step
    ok &= spacing >= grid.min_spacing
    corners = _corners(plan, zc=zc, sigma=sigma, grid=grid, ex=ex, ey=ey)
    d = corners[:, :, :2] - c[:2]
    qv = ((d[..., 0] ** 2 + d[..., 1] ** 2) / spec.reach(d) ** 2
          + (corners[:, :, 2] - c[2]) ** 2 / b**2)
    ok &= np.all(qv <= 1.0, axis=1)
    ok &= ~trunk_clash(rho, corners[:, :, 2].min(axis=1), spec, s)
    ok &= touches_share(corners, spec, lo, hi)
    kept, n_cut = cut_to_share(corners[ok], spec, lo, hi)
    return kept, n_cut, int(np.sum(~ok & (rho < r)))


def _corners(plan: np.ndarray, *, zc: np.ndarray, sigma: np.ndarray, grid: _FreeGrid,
             ex: np.ndarray, ey: np.ndarray) -> np.ndarray:
    """Slat corners (k, 4, 3): (±s/2 along rows, ±s·cosα/2 across), rising σ·tanα across the
    rows, around the slats' plan centres ``plan`` at heights ``zc``."""
    s = grid.s
    hx = np.array([-0.5, 0.5, 0.5, -0.5]) * s
    hy = np.array([-0.5, -0.5, 0.5, 0.5]) * s * grid.cosa
    cu = plan[:, None, 0] + hx[None, :] * ex[0] + hy[None, :] * ey[0]
    cn = plan[:, None, 1] + hx[None, :] * ex[1] + hy[None, :] * ey[1]
    cz = zc[:, None] + sigma[:, None] * grid.tana * hy[None, :]
    return np.stack([cu, cn, cz], axis=2)
