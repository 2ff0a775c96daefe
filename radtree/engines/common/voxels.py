"""Free paths through voxel crowns (:class:`radtree.media_voxels.VoxelCrowns`) for the NumPy
engine and the forward light tracer — the voxel form of :mod:`radtree.engines.common.turbid`.

Which grids a ray crosses: each grid's box (its world bounds, when the grid is turned about
the vertical) is a proxy in a ray caster (:class:`~radtree.engines.common.boxes.BoxProxies`);
per candidate (ray, grid) pair the ray is taken into the grid's frame (a rotation about z:
lengths, and so t, unchanged) and the exact interval is its slab interval in the grid's box,
cut by the crown's half-spaces.

Free paths are sampled **exactly** for the piecewise-constant density by an optical-depth walk
(regular tracking, not delta tracking): the pair's voxels are visited in the order the ray
crosses them by the 3-D DDA of Amanatides & Woo (1987, *A fast voxel traversal algorithm for
ray tracing*, Eurographics '87, 3–10), vectorised over all pairs (one NumPy step per voxel
crossed, the pairs that are done dropped at each step), accumulating the plant-area path
integral A = Σ u_i ℓ_i. With the pair's coefficient c = G·Ω_c(|Ω_z|)·(1 − T_s) (deflecting
leaves per unit plant area along Ω; the undeviated share T_s thins them, as in the spheroid
crowns), a uniform ξ of the pair's stream sets the target A* = −ln(1 − ξ)/c, and the
collision is where A reaches A* (inside voxel i: t = t_i + (A* − A(t_i))/u_i) — inverse-CDF
sampling of exp(−c·A(t)), the uncollided law of the grid. Several media superpose (spheroid
crowns, other grids): each draws its own free path and the nearest wins
(:func:`~radtree.engines.common.turbid.first_hits`). The leaf events at a collision are the
spheroids' (:func:`~radtree.engines.common.turbid.leaf_normals`,
:func:`~radtree.engines.common.turbid.leaf_optics`).

Shadow rays: the exact expected transmittance exp(−c·Σ u_i ℓ_i) along the whole ray (the same
walk without a target). Memory: O(voxels + pairs in a batch); work: O(pairs × voxels crossed).
"""

from __future__ import annotations

import numpy as np

from radtree.engines.common.boxes import BoxProxies, clip_to_planes
from radtree.engines.common.streams import Draws
from radtree.engines.common.turbid import first_hits, leaf_normals, leaf_optics, pair_uniforms
from radtree.errors import EngineError
from radtree.media_voxels import VoxelCrowns, media_parts
from radtree.optics import Material
from radtree.scene import Scene

_EMPTY = (np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0), np.zeros(0))


def refuse_voxels(scene: Scene, *, engine: str) -> None:
    """EngineError when ``scene`` holds voxel crowns and ``engine`` cannot trace them (the
    Radiance engine: not implemented)."""
    if media_parts(scene.media)[1] is not None:
        raise EngineError(f"the {engine} engine cannot trace voxel crowns ([tree] points or "
                          "[tree] voxels with representation = \"turbid\"): use --engine "
                          "numpy or --engine forward, or representation = \"explicit\" with "
                          "[tree] points")


def slab_interval(o: np.ndarray, *, d: np.ndarray, lo: np.ndarray, hi: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray]:
    """[t_in, t_out] of rays ``o + t d`` in the boxes ``lo`` … ``hi`` (all (k, 3)); empty:
    t_out < t_in. A ray parallel to a slab is inside it for all t or for none."""
    with np.errstate(divide="ignore", invalid="ignore"):
        ta, tb = (lo - o) / d, (hi - o) / d
    par = d == 0
    inside = (o >= lo) & (o <= hi)
    near = np.where(par, np.where(inside, -np.inf, np.inf), np.minimum(ta, tb))
    far = np.where(par, np.where(inside, np.inf, -np.inf), np.maximum(ta, tb))
    return near.max(axis=1), far.min(axis=1)


class VoxelTracer:
    """The voxel crowns of one scene, ready for the engine's queries (module text).
    ``first_id``: the number of the first grid among all the scene's media (its collisions
    are reported as ``first_id + grid``; the pairs' streams are shifted by it)."""

    def __init__(self, media: VoxelCrowns, *, materials: dict[str, Material],
                 backend: str = "auto", workers: int = 1, first_id: int = 0):
        self.media = media
        self.n = len(media)
        self.first_id = int(first_id)
        self.dims = media.dims()
        sizes = np.array([p.size for p in media.pads], np.int64)
        starts = np.concatenate([[0], np.cumsum(sizes)[:-1]])
        self.values = np.concatenate([p.ravel() for p in media.pads])   # C order (i, j, k)
        self.offset = starts[media.pad_of]
        self.basis = media.basis()
        self.extent = self.dims * media.size_m[:, None]
        lo, hi = media.bounds()
        self.boxes = BoxProxies(lo, hi=hi, backend=backend, workers=workers)
        self.pass_, self.events = leaf_optics(media.kinds, materials=materials)

    def corners(self) -> np.ndarray:
        """(8·n, 3) corners of the grids' proxy boxes (a forward source must enclose them)."""
        return self.boxes.corners

    def material_index(self, grid: np.ndarray, names: list[str]) -> np.ndarray:
        """Index in ``names`` of the leaf material of each grid in ``grid`` (own numbering)."""
        table = np.array([names.index(k.material) for k in self.media.kinds], np.int64)
        return table[self.media.kind[grid]]

    def to_grid(self, o: np.ndarray, d: np.ndarray, grid: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray]:
        """Pairs' origins and directions (k, 3) in their grids' frames (m from the origin)."""
        b = self.basis[grid]
        return (np.einsum("kij,kj->ki", b, o - self.media.origins[grid]),
                np.einsum("kij,kj->ki", b, d))

    def crossings(self, o: np.ndarray, d: np.ndarray, tmax: np.ndarray, parallel: bool = True
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(ray, grid, t_in, t_out) of every grid the rays ``o + t d`` (0 ≤ t ≤ ``tmax``)
        cross inside its half-spaces, t in metres along the unit ``d``."""
        ray, grid = self.boxes.candidates(o, d, tmax, parallel)
        if len(ray) == 0:
            return _EMPTY
        oo, dd = np.asarray(o, float)[ray], np.asarray(d, float)[ray]
        og, dg = self.to_grid(oo, dd, grid)
        t0, t1 = slab_interval(og, d=dg, lo=np.zeros_like(og), hi=self.extent[grid])
        t0, t1 = clip_to_planes(oo, d=dd, planes=self.media.planes[grid], t0=np.maximum(t0, 0.0),
                                t1=t1)
        t1 = np.minimum(t1, tmax[ray])
        ok = t1 > t0
        return ray[ok], grid[ok], t0[ok], t1[ok]

    def _coef(self, d: np.ndarray, grid: np.ndarray) -> np.ndarray:
        """Deflecting collisions per unit plant area, G·Ω_c(|Ω_z|)·(1 − T_s), per pair."""
        kind = self.media.kind[grid]
        g = np.empty(len(grid))
        for k, lk in enumerate(self.media.kinds):
            m = kind == k
            if m.any():
                g[m] = lk.g(d[m, 2])
        return g * self.pass_[kind]

    def walk(self, o: np.ndarray, *, d: np.ndarray, grid: np.ndarray, t0: np.ndarray,
             t1: np.ndarray, target: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """The DDA walk of the module text for pairs (ray ``o + t d`` in ``grid`` over
        [``t0``, ``t1``]; ``o``, ``d`` in the grid's frame, :meth:`to_grid`): (t where the plant-area path integral reaches ``target``, inf
        where it does not or without a target; the integral Σ u_i ℓ_i over the whole walk or
        up to the hit, m²/m²)."""
        k = len(grid)
        hit, area = np.full(k, np.inf), np.zeros(k)
        if k == 0:
            return hit, area
        size = self.media.size_m[grid][:, None]
        dims = self.dims[grid]
        q = (o + t0[:, None] * d) / size
        idx = np.clip(np.floor(q), 0, dims - 1).astype(np.int64)
        step = np.where(d >= 0, 1, -1)
        with np.errstate(divide="ignore", invalid="ignore"):
            delta = np.where(d != 0, size / np.abs(d), np.inf)
            nxt = np.where(d != 0, t0[:, None] + (idx + (d > 0) - q) * size / d, np.inf)
        nxt = np.maximum(nxt, t0[:, None])
        act, tcur, acc = np.arange(k), t0.copy(), np.zeros(k)
        end, off, goal = t1.copy(), self.offset[grid], target
        rows = np.arange(k)
        for _ in range(int(dims.sum(axis=1).max()) + 4):
            ax = np.argmin(nxt, axis=1)
            tn = np.minimum(nxt[rows, ax], end)
            lin = off + (idx[:, 0] * dims[:, 1] + idx[:, 1]) * dims[:, 2] + idx[:, 2]
            u = self.values[lin]
            gain = u * (tn - tcur)
            done = tn >= end
            if goal is not None:
                over = (u > 0) & (acc + gain >= goal)
                hit[act[over]] = tcur[over] + (goal[over] - acc[over]) / u[over]
                gain = np.where(over, goal - acc, gain)
                done |= over
            acc += gain
            idx[rows, ax] += step[rows, ax]
            nxt[rows, ax] += delta[rows, ax]
            tcur = tn
            done |= np.any((idx < 0) | (idx >= dims), axis=1)
            area[act[done]] = acc[done]
            keep = ~done
            if not keep.any():
                break
            act, tcur, acc, end, off = act[keep], tcur[keep], acc[keep], end[keep], off[keep]
            idx, nxt, delta, step, dims = idx[keep], nxt[keep], delta[keep], step[keep], dims[keep]
            goal = None if goal is None else goal[keep]
            rows = np.arange(len(act))
        return hit, area

    # -- the engine's hooks
    def collide(self, o: np.ndarray, d: np.ndarray, t: np.ndarray, draws: Draws,
                parallel: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """(first_id + grid met, or −1; distance) per ray: the first deflecting leaf before
        the surface at ``t``; ``draws``: the rays' streams at this place."""
        ray, grid, t0, t1 = self.crossings(o, d, t, parallel)
        met = np.full(len(o), -1, np.int64)
        dist = np.array(t, float)
        if len(ray) == 0:
            return met, dist
        dd = np.asarray(d, float)[ray]
        coef = self._coef(dd, grid)
        xi = pair_uniforms(draws, ray, grid + self.first_id)
        with np.errstate(divide="ignore"):
            target = -np.log1p(-xi) / coef
        live = np.isfinite(target)
        ray, grid, t0, t1, dd, target = (ray[live], grid[live], t0[live], t1[live], dd[live],
                                         target[live])
        og, dg = self.to_grid(np.asarray(o, float)[ray], dd, grid)
        tc, _ = self.walk(og, d=dg, grid=grid, t0=t0, t1=t1, target=target)
        ok = np.isfinite(tc)
        first_hits(ray[ok], which=grid[ok] + self.first_id, tc=tc[ok], met=met, dist=dist)
        return met, dist

    def leaf_events(self, grid: np.ndarray, d: np.ndarray, draws: Draws
                    ) -> tuple[np.ndarray, np.ndarray]:
        """For rays along ``d`` that met a leaf of ``grid`` (own numbering): the leaf normal
        on the side the ray came from (k, 3) and the event coefficients (4, k), as
        :meth:`radtree.engines.common.turbid.MediumTracer.leaf_events`."""
        kind = self.media.kind[grid]
        normal = leaf_normals(kind, kinds=self.media.kinds, d=d, draws=draws)
        coef = np.zeros((4, len(grid)))
        coef[:2] = self.events[kind].T
        return normal, coef

    def transmittance(self, o: np.ndarray, d: np.ndarray, parallel: bool = True) -> np.ndarray:
        """exp(−Σ_grids c·Σ u_i ℓ_i) along the whole rays ``o + t d`` (t ≥ 0)."""
        d = np.ascontiguousarray(np.broadcast_to(np.asarray(d, float), np.shape(o)))
        ray, grid, t0, t1 = self.crossings(o, d, np.full(len(o), np.inf), parallel)
        tau = np.zeros(len(o))
        if len(ray):
            og, dg = self.to_grid(np.asarray(o, float)[ray], d[ray], grid)
            _, area = self.walk(og, d=dg, grid=grid, t0=t0, t1=t1)
            np.add.at(tau, ray, self._coef(d[ray], grid) * area)
        return np.exp(-tau)
