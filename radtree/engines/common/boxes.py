"""Which axis-aligned boxes a batch of rays crosses: the boxes as a proxy mesh in a ray caster.

Every box (12 triangles, 1–5 cm larger than the volume it bounds, the margin differing from box
to box so that overlapping neighbours never share a coplanar face, one of which a ray stepping
past the other would miss) goes into its own ray caster (Embree when available); the faces a
ray crosses name the candidate boxes (:meth:`BoxProxies.candidates`: repeated first-hit
queries until the ray leaves the last box or passes its end). The caller then solves the exact
interval of the volume inside each candidate. Memory: O(boxes + rays in a batch).

Used by the turbid media of :mod:`radtree.engines.common.turbid` (spheroids) and
:mod:`radtree.engines.common.voxels` (voxel grids).
"""

from __future__ import annotations

import numpy as np

from radtree.engines.common.raycast import make_caster

MAX_FACES = 4096   # proxy faces one ray may cross (a safety bound)
BOX_MARGIN = 0.01  # m added to the proxy boxes (times 1–5, box by box)
MARGIN_STEPS = 23  # distinct margins (neighbours in a row never share one)

_BOX_FACES = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                       [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])


class BoxProxies:
    """Proxy boxes around the volumes ``lo`` … ``hi`` ((n, 3) each, m, world frame)."""

    def __init__(self, lo: np.ndarray, *, hi: np.ndarray, backend: str = "auto",
                 workers: int = 1):
        n = len(lo)
        self.n = n
        margin = (BOX_MARGIN * (1.0 + 4.0 * (np.arange(n) % MARGIN_STEPS) / MARGIN_STEPS))[:, None]
        lo, hi = np.asarray(lo, float) - margin, np.asarray(hi, float) + margin
        corners = np.array([[i & 1, (i >> 1) & 1, (i >> 2) & 1] for i in range(8)], float)
        verts = lo[:, None, :] + corners[None] * (hi - lo)[:, None, :]
        faces = _BOX_FACES[None] + 8 * np.arange(n)[:, None, None]
        self.corners = verts.reshape(-1, 3)
        self.caster = make_caster(self.corners, faces.reshape(-1, 3), backend, workers)
        self.face_box = np.repeat(np.arange(n), 12)
        self.scale = max(1.0, float(np.ptp(np.vstack([lo, hi]), axis=0).max())) if n else 1.0
        # the longest box diagonal: a ray leaves every box holding its origin within it
        self.reach = float(np.linalg.norm(hi - lo, axis=1).max()) if n else 0.0

    def candidates(self, o: np.ndarray, d: np.ndarray, tmax: np.ndarray, parallel: bool = True
                   ) -> tuple[np.ndarray, np.ndarray]:
        """(ray, box) of every proxy box the rays ``o + t d`` (0 ≤ t ≤ ``tmax``) cross, once
        each, sorted by ray then box.

        The faces are followed to ``max(tmax, reach)`` (:attr:`reach`: the longest box
        diagonal), not just to ``tmax``: a ray starting inside boxes (a scattered path, a
        point on a wall within a crown's box) names those boxes only by their exit faces,
        which may lie beyond a near surface — stopping at ``tmax`` lost every such box but
        the first (up to a third of the in-medium length of paths from a wall between
        overlapping crowns; found on the turbid-vs-slats comparison, issue 43)."""
        k = len(o)
        idx = np.arange(k)
        cur = np.array(o, float)
        dd = np.asarray(d, float)
        done = np.zeros(k)
        step = 1e-6 * self.scale
        rays, boxes = [], []
        for _ in range(MAX_FACES):
            if len(idx) == 0:
                break
            tri, t = self.caster.first_hit(cur, dd, parallel)
            hit = tri >= 0
            if not hit.any():
                break
            rays.append(idx[hit])
            boxes.append(self.face_box[tri[hit]])
            t_all = done[hit] + t[hit]
            go = t_all < np.maximum(tmax[idx[hit]], self.reach)
            keep = hit.nonzero()[0][go]
            idx, dd = idx[keep], dd[keep]
            cur = cur[keep] + (t[keep] + step)[:, None] * dd
            done = t_all[go] + step
        if not rays:
            return np.zeros(0, np.int64), np.zeros(0, np.int64)
        key = np.unique(np.concatenate(rays).astype(np.int64) * self.n
                        + np.concatenate(boxes).astype(np.int64))
        return key // self.n, key % self.n


def clip_to_planes(o: np.ndarray, *, d: np.ndarray, planes: np.ndarray, t0: np.ndarray,
                   t1: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """[t0, t1] of the rays ``o + t d`` cut by the half-spaces ``planes`` ((k, p, 4): keep
    n·x ≥ c per row (n_x, n_y, n_z, c); rows of zeros with c = −1 keep everything); empty:
    t1 ≤ t0."""
    for j in range(planes.shape[1]):
        pl = planes[:, j]
        nd = np.einsum("ij,ij->i", pl[:, :3], d)
        no = np.einsum("ij,ij->i", pl[:, :3], o) - pl[:, 3]
        with np.errstate(divide="ignore", invalid="ignore"):
            tp = -no / nd
        t0 = np.where(nd > 0, np.maximum(t0, tp), t0)
        t1 = np.where(nd < 0, np.minimum(t1, tp), t1)
        t1 = np.where((nd == 0) & (no < 0), -1.0, t1)
    return t0, t1
