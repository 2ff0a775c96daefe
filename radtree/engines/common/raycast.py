"""First-hit ray–triangle queries: Embree (trimesh + embreex) or a vectorised NumPy BVH.

Both backends answer the same question for batches of rays: which triangle does each ray hit
first, and at what distance (``-1`` / ``inf`` for a miss). Triangles are two-sided. Distances
are recomputed in float64 from the hit triangle's plane (Embree works in float32).

The NumPy BVH is the fallback when embreex is not installed: a median-split bounding-volume
hierarchy traversed with one small stack per ray, all rays of a chunk stepping together, so
that memory stays bounded whatever the batch size (10⁴–10⁵ rays/s — use Embree for real
work). Select a backend with :func:`make_caster` or the environment variable
``RADTREE_RAY_BACKEND`` = ``embree`` | ``numpy-bvh``.
"""

from __future__ import annotations

import os
import threading
from concurrent.futures import ThreadPoolExecutor
from typing import Protocol

import numpy as np

from radtree.engines.common.kernel import kernel, triangle_rows

BACKENDS = ("embree", "numpy-bvh")


class RayCaster(Protocol):
    name: str
    rays_cast: int  # rays queried so far (statistics)

    def first_hit(self, origins: np.ndarray, directions: np.ndarray, parallel: bool = True
                  ) -> tuple[np.ndarray, np.ndarray]:
        """(triangle index or -1, distance or inf) per ray; directions must be unit vectors.

        ``parallel=False``: answer in the calling thread (a caller that is itself one of
        several worker threads)."""
        ...


def embree_available() -> bool:
    try:
        import embreex  # noqa: F401
        from trimesh.ray import ray_pyembree  # noqa: F401
    except ImportError:
        return False
    return True


def plane_distance(tris_v0: np.ndarray, normals: np.ndarray, centroids: np.ndarray,
                    origins: np.ndarray, directions: np.ndarray, idx: np.ndarray,
                    n: np.ndarray | None = None, denom: np.ndarray | None = None) -> np.ndarray:
    """Distance along each ray to the plane of its hit triangle (float64; a ray parallel to
    the plane gets the distance of the triangle's centroid along it). ``n``, ``denom``: the
    hit triangles' normals and direction · normal when already at hand (not modified)."""
    if n is None:
        n = np.take(normals, idx, axis=0)
    if denom is None:
        denom = np.einsum("ij,ij->i", directions, n)
    v = np.take(tris_v0, idx, axis=0)
    v -= origins
    num = np.einsum("ij,ij->i", v, n)
    grazing = np.flatnonzero(np.abs(denom) < 1e-12)
    if len(grazing):
        denom = denom.copy()
    with np.errstate(divide="ignore", invalid="ignore"):
        if len(grazing):
            denom[grazing] = 1.0
        t = num / denom
    if len(grazing):
        g = idx[grazing]
        t[grazing] = np.einsum("ij,ij->i", centroids[g] - origins[grazing],
                               directions[grazing])
    return np.maximum(t, 0.0, out=t)


class EmbreeCaster:
    """trimesh's ``RayMeshIntersector`` (embreex) with the batch split over worker threads.

    Each thread converts its chunk of rays exactly as ``RayMeshIntersector.intersects_first``
    does (float32, directions re-unitised, shifted and scaled into trimesh's Embree frame),
    queries Embree (which releases the GIL) and computes the float64 plane distances of its
    hits, so that only the result arrays are assembled in the calling thread.
    """

    name = "embree"

    def __init__(self, vertices: np.ndarray, faces: np.ndarray, workers: int = 2,
                 chunk: int = 1 << 17):
        import trimesh
        from trimesh.ray.ray_pyembree import RayMeshIntersector

        self.mesh = trimesh.Trimesh(vertices=vertices, faces=faces, process=False,
                                    validate=False)
        self._intersector = RayMeshIntersector(self.mesh)
        tris = np.asarray(vertices, float)[np.asarray(faces)]
        self._v0 = np.ascontiguousarray(tris[:, 0])
        self._centroids = tris.mean(axis=1)
        self._normals = _unit_normals(tris)
        self._rows = triangle_rows(self._normals, self._v0)  # the C kernel's distances
        self.workers = max(1, int(workers))
        self.chunk = chunk
        self._pool = ThreadPoolExecutor(self.workers) if self.workers > 1 else None
        self.rays_cast = 0
        self._count_lock = threading.Lock()
        self._rows32: dict[bytes, np.ndarray] = {}  # float32 unit row of each point sun
        # build the Embree scene now (trimesh builds it lazily on first query)
        self._intersector.intersects_first(np.zeros((1, 3)), np.array([[0.0, 0.0, 1.0]]))
        self._embree = self._intersector._scene  # trimesh's scaled Embree scene
        self._origin_t = np.asarray(self._embree.origin, np.float64)[:, None]  # (3, 1)
        # the frame for the C kernel: origin (3) and scale, float64
        self.frame = np.array([*self._origin_t[:, 0], self._embree.scale], np.float64)

    def directions32(self, d: np.ndarray) -> np.ndarray:
        """Directions ``d`` (n, 3) as the float32 unit rows ``intersects_first`` makes; one
        direction (a broadcast row: the point sun) is converted once and handed to Embree as
        that broadcast row."""
        if d.ndim == 2 and d.strides[0] == 0 and len(d):  # one direction (a point sun)
            key = d[0].tobytes()
            row = self._rows32.get(key)
            if row is None:
                if len(self._rows32) > 256:
                    self._rows32.clear()
                row = self._rows32[key] = _unit32(np.array(d[:1], dtype=np.float32))
            return np.broadcast_to(row, d.shape)
        return _unit32(np.array(d, dtype=np.float32))

    def _query(self, o_t: np.ndarray, d: np.ndarray) -> np.ndarray:
        """Triangle index per ray (int32, -1: miss) of origins ``o_t`` (3, n) — one row per
        axis, or the transpose of (n, 3) rows — and directions ``d`` (n, 3): the arithmetic of
        ``RayMeshIntersector.intersects_first`` (identical float32 inputs to Embree) without
        its per-call overhead, on rows of all rays (a (3, n) array, handed to Embree as its
        transpose; with the C kernel converted in one pass into an (n, 3) array, the same
        float32 numbers)."""
        d32 = self.directions32(d)
        k = kernel()
        if k is not None:
            o32 = np.empty((o_t.shape[1], 3), np.float32)
            k.frame(o_t, self.frame, o32)
            return self._run(o32, d32)
        o32 = np.array(o_t, dtype=np.float32, order="C")
        shifted = np.subtract(o32, self._origin_t, dtype=np.float64)  # exact
        # × scale in float64, rounded to float32 as it is stored (one pass, the same numbers)
        return self._run(np.multiply(shifted, self._embree.scale, out=o32,
                                     casting="same_kind").T, d32)

    def _run(self, o32: np.ndarray, d32: np.ndarray) -> np.ndarray:
        """Embree's answer (triangle per ray, int32) for float32 rays already in its frame: the
        one place the caster calls Embree."""
        return self._embree.scene.run(o32, d32)

    def query_frame(self, o32: np.ndarray, d32: np.ndarray, parallel: bool = True
                    ) -> np.ndarray:
        """:meth:`query` of rays already converted for Embree: origins ``o32`` (n, 3) in its
        float32 frame (the C kernel writes them with the next origins; ``frame`` holds the
        origin and scale of that frame) and float32 unit directions ``d32`` (n, 3, or one
        broadcast row) from :meth:`directions32`."""
        n = len(o32)
        if n == 0:
            return np.zeros(0, np.int32)
        parts = self._parts(n, parallel)
        if parts is not None and self._pool is not None:
            return np.concatenate(list(self._pool.map(
                lambda s: self._run(o32[s], d32[s]), parts)))
        return self._run(o32, d32)

    def query(self, origins_t: np.ndarray, directions: np.ndarray, parallel: bool = True
              ) -> np.ndarray:
        """Triangle index per ray (int32, -1: miss), no distances (split over the threads);
        ``origins_t``: (3, n), one row per axis."""
        n = origins_t.shape[1]
        if n == 0:
            return np.zeros(0, np.int32)
        parts = self._parts(n, parallel)
        if parts is not None and self._pool is not None:
            return np.concatenate(list(self._pool.map(
                lambda s: self._query(origins_t[:, s], directions[s]), parts)))
        return self._query(origins_t, directions)

    def _chunk(self, o: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        k = kernel()
        if k is not None and o.dtype == np.float64 and d.dtype == np.float64:
            tri = self._query(o.T, d)
            idx, t = np.empty(len(o), np.int64), np.empty(len(o))
            k.distances(tri, o, d, self._rows, self._centroids, idx, t)  # plane_distance's
            return idx, t
        idx = self._query(o.T, d).astype(np.int64)
        t = np.full(len(o), np.inf)
        hit = (idx >= 0).nonzero()[0]
        if len(hit):
            dh = (d.take(hit, axis=0) if d.strides[0] else
                  np.broadcast_to(d[0], (len(hit), 3)))
            t[hit] = plane_distance(self._v0, self._normals, self._centroids,
                                    o.take(hit, axis=0), dh, idx[hit])
        return idx, t

    def _parts(self, n: int, parallel: bool) -> list[slice] | None:
        with self._count_lock:
            self.rays_cast += n
        if parallel and self._pool is not None and n >= 2048:
            step = min(self.chunk, -(-n // self.workers))
            return [slice(i, min(i + step, n)) for i in range(0, n, step)]
        return None

    def first_hit(self, origins: np.ndarray, directions: np.ndarray, parallel: bool = True
                  ) -> tuple[np.ndarray, np.ndarray]:
        n = len(origins)
        if n == 0:
            return np.zeros(0, np.int64), np.zeros(0)
        parts = self._parts(n, parallel)
        if parts is not None and self._pool is not None:
            res = list(self._pool.map(lambda s: self._chunk(origins[s], directions[s]), parts))
            return np.concatenate([r[0] for r in res]), np.concatenate([r[1] for r in res])
        return self._chunk(origins, directions)


def hit_triangles(caster: RayCaster, origins_t: np.ndarray, directions: np.ndarray,
                  parallel: bool = True) -> tuple[np.ndarray, np.ndarray | None]:
    """The triangle each ray hits first (-1: miss) and, from casters other than Embree, the
    distance; Embree's distances are the plane distances (:func:`plane_distance`), which the
    caller computes for the hits it needs them for (``None`` here). ``origins_t``: the rays'
    origins as a (3, n) array, one row per axis; ``directions``: (n, 3)."""
    if isinstance(caster, EmbreeCaster):
        return caster.query(origins_t, directions, parallel), None
    return caster.first_hit(np.ascontiguousarray(origins_t.T), directions, parallel)


_TOL_ZERO = 1e-13  # trimesh.util.TOL_ZERO: unitize's zero threshold


def _unit32(d32: np.ndarray) -> np.ndarray:
    """float32 unit rows exactly as ``RayMeshIntersector.intersects_first`` makes them
    (``trimesh.util.unitize`` then float32), without its ``np.dot(v * v, [1, 1, 1])``: that
    product goes to BLAS, whose threads then spin beside the engine's (measured: 3.3 CPU-s
    wasted in a 5 s trace of 7 hours on one thread). The float32 squares are summed in
    float64, where the order of the sum changed no float32 result on 4 M rows whose
    components span five decades (tests/test_numpy_rows.py compares with trimesh)."""
    d32 = np.asarray(d32)
    sq = np.multiply(d32, d32).astype(np.float64)
    norm = sq[:, 0] + sq[:, 1]
    norm += sq[:, 2]
    np.sqrt(norm, out=norm)
    valid = norm > _TOL_ZERO
    norm[valid] **= -1
    return np.asarray(d32 * norm.reshape((-1, 1)), dtype=np.float32)


def _unit_normals(tris: np.ndarray) -> np.ndarray:
    n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    length = np.linalg.norm(n, axis=1)
    bad = length < 1e-300
    n[bad] = (0.0, 0.0, 1.0)
    length[bad] = 1.0
    return n / length[:, None]


class BVHCaster:
    """Vectorised NumPy BVH (median split, ``leaf_size`` triangles per leaf).

    Traversal is the classic stack-based one, run for ``ray_chunk`` rays at once: every ray
    owns a small stack (tree depth + 2 entries), each step pops one node per active ray,
    tests leaves' triangles or pushes the children whose boxes the ray enters (the nearer
    one on top, so the closest hits are found first and prune the rest). Memory is bounded by
    ``ray_chunk`` × (depth + 2) stack entries plus per-step arrays of ``ray_chunk`` rows.
    """

    name = "numpy-bvh"

    def __init__(self, vertices: np.ndarray, faces: np.ndarray, leaf_size: int = 4,
                 ray_chunk: int = 32768):
        tris = np.asarray(vertices, float)[np.asarray(faces)]
        self.n_tris = len(tris)
        self.leaf_size = leaf_size
        self.ray_chunk = ray_chunk
        self._v0 = tris[:, 0].copy()
        self._e1 = tris[:, 1] - tris[:, 0]
        self._e2 = tris[:, 2] - tris[:, 0]
        self._build(tris)
        self.rays_cast = 0

    def _build(self, tris: np.ndarray) -> None:
        m = len(tris)
        lo_t, hi_t = tris.min(axis=1), tris.max(axis=1)
        cent = tris.mean(axis=1)
        order = np.arange(m)
        lo: list[np.ndarray] = []
        hi: list[np.ndarray] = []
        left: list[int] = []
        right: list[int] = []
        start: list[int] = []
        count: list[int] = []
        depth = 0

        def new_node(s: int, e: int) -> int:
            sub = order[s:e]
            lo.append(lo_t[sub].min(axis=0) if e > s else np.full(3, np.inf))
            hi.append(hi_t[sub].max(axis=0) if e > s else np.full(3, -np.inf))
            left.append(-1)
            right.append(-1)
            start.append(s)
            count.append(e - s)
            return len(lo) - 1

        stack = [(new_node(0, m), 0, m, 0)]
        while stack:
            node, s, e, level = stack.pop()
            depth = max(depth, level)
            if e - s <= self.leaf_size:
                continue
            sub = order[s:e]
            c = cent[sub]
            axis = int(np.argmax(c.max(axis=0) - c.min(axis=0)))
            mid = (e - s) // 2
            part = np.argpartition(c[:, axis], mid)
            order[s:e] = sub[part]
            ln = new_node(s, s + mid)
            rn = new_node(s + mid, e)
            left[node], right[node] = ln, rn
            count[node] = 0
            stack.append((ln, s, s + mid, level + 1))
            stack.append((rn, s + mid, e, level + 1))
        self._lo = np.array(lo)
        self._hi = np.array(hi)
        self._left = np.array(left, np.int64)
        self._right = np.array(right, np.int64)
        self._start = np.array(start, np.int64)
        self._count = np.array(count, np.int64)
        self._order = order
        self.n_nodes = len(lo)
        self.depth = depth

    def _triangles(self, o: np.ndarray, d: np.ndarray, tri: np.ndarray) -> np.ndarray:
        """Möller–Trumbore for ray/triangle pairs; distance or inf (two-sided)."""
        e1, e2 = self._e1[tri], self._e2[tri]
        p = np.cross(d, e2)
        det = np.einsum("ij,ij->i", e1, p)
        ok = np.abs(det) > 1e-14
        inv = 1.0 / np.where(ok, det, 1.0)
        s = o - self._v0[tri]
        u = np.einsum("ij,ij->i", s, p) * inv
        q = np.cross(s, e1)
        v = np.einsum("ij,ij->i", d, q) * inv
        t = np.einsum("ij,ij->i", e2, q) * inv
        ok &= (u >= 0.0) & (v >= 0.0) & (u + v <= 1.0) & (t > 0.0)
        return np.where(ok, t, np.inf)

    def _boxes(self, o: np.ndarray, inv: np.ndarray, nd: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray]:
        """Entry distance into each node's box and whether the ray enters it at all."""
        t1 = (self._lo[nd] - o) * inv
        t2 = (self._hi[nd] - o) * inv
        tmin = np.maximum(np.minimum(t1, t2).max(axis=1), 0.0)
        tmax = np.maximum(t1, t2).min(axis=1)
        return tmin, tmax >= tmin

    def first_hit(self, origins: np.ndarray, directions: np.ndarray, parallel: bool = True
                  ) -> tuple[np.ndarray, np.ndarray]:
        n = len(origins)
        self.rays_cast += n
        best_t = np.full(n, np.inf)
        best_tri = np.full(n, -1, np.int64)
        if n == 0 or self.n_tris == 0:
            return best_tri, best_t
        d_safe = np.where(np.abs(directions) < 1e-15, 1e-15, directions)
        inv_d = 1.0 / d_safe
        width = self.depth + 3
        for c0 in range(0, n, self.ray_chunk):
            rays = np.arange(c0, min(n, c0 + self.ray_chunk))
            k = len(rays)
            node_stack = np.zeros((k, width), np.int64)
            tmin_stack = np.zeros((k, width))
            sp = np.zeros(k, np.int64)
            t0, hit0 = self._boxes(origins[rays], inv_d[rays], np.zeros(k, np.int64))
            tmin_stack[:, 0] = t0
            sp[hit0] = 1
            act = np.flatnonzero(hit0)  # local indices of rays with work left
            while len(act):
                sp[act] -= 1
                popped = act
                nd = node_stack[act, sp[act]]
                tn = tmin_stack[act, sp[act]]
                g = rays[act]
                live = tn < best_t[g]
                act, nd, g = act[live], nd[live], g[live]
                leaf = self._left[nd] < 0
                if leaf.any():
                    la, ln = act[leaf], nd[leaf]
                    cnt = self._count[ln]
                    total = int(cnt.sum())
                    if total:
                        rr = np.repeat(rays[la], cnt)
                        offs = np.arange(total) - np.repeat(np.cumsum(cnt) - cnt, cnt)
                        tri = self._order[np.repeat(self._start[ln], cnt) + offs]
                        t = self._triangles(origins[rr], directions[rr], tri)
                        hit = t < best_t[rr]
                        rr, t, tri = rr[hit], t[hit], tri[hit]
                        if len(rr):
                            np.minimum.at(best_t, rr, t)
                            win = t == best_t[rr]
                            best_tri[rr[win]] = tri[win]
                inner = ~leaf
                if inner.any():
                    ia, inn, ig = act[inner], nd[inner], g[inner]
                    o, inv = origins[ig], inv_d[ig]
                    lc, rc = self._left[inn], self._right[inn]
                    tl, hl = self._boxes(o, inv, lc)
                    tr, hr = self._boxes(o, inv, rc)
                    bt = best_t[ig]
                    hl &= tl < bt
                    hr &= tr < bt
                    near_left = tl <= tr
                    # push the far child first, then the near one (popped first)
                    far_n = np.where(near_left, rc, lc)
                    far_t = np.where(near_left, tr, tl)
                    far_h = np.where(near_left, hr, hl)
                    near_n = np.where(near_left, lc, rc)
                    near_t = np.where(near_left, tl, tr)
                    near_h = np.where(near_left, hl, hr)
                    for nn, tt, hh in ((far_n, far_t, far_h), (near_n, near_t, near_h)):
                        a = ia[hh]
                        node_stack[a, sp[a]] = nn[hh]
                        tmin_stack[a, sp[a]] = tt[hh]
                        sp[a] += 1
                act = popped[sp[popped] > 0]
        return best_tri, best_t


class NullCaster:
    """No geometry: every ray misses."""

    name = "none"
    rays_cast = 0

    def first_hit(self, origins: np.ndarray, directions: np.ndarray, parallel: bool = True
                  ) -> tuple[np.ndarray, np.ndarray]:
        n = len(origins)
        self.rays_cast += n
        return np.full(n, -1, np.int64), np.full(n, np.inf)


def any_hit(caster: RayCaster, origins: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """Whether each ray hits anything (no distances: Embree's occlusion query, split over
    the caster's threads; other casters: ``first_hit``)."""
    if not isinstance(caster, EmbreeCaster):
        return caster.first_hit(origins, directions)[0] >= 0
    n = len(origins)
    caster.rays_cast += n

    def query(s: slice) -> np.ndarray:
        return np.asarray(caster._intersector.intersects_any(origins[s], directions[s]), bool)

    step = min(caster.chunk, max(1, -(-n // caster.workers)))
    parts = [slice(i, min(i + step, n)) for i in range(0, n, step)]
    if caster._pool is None or len(parts) == 1:
        return np.concatenate([query(s) for s in parts]) if parts else np.zeros(0, bool)
    return np.concatenate(list(caster._pool.map(query, parts)))


def make_caster(vertices: np.ndarray, faces: np.ndarray, backend: str = "auto",
                workers: int = 2) -> RayCaster:
    """A first-hit ray caster for a triangle soup: Embree when available (``auto``)."""
    if len(faces) == 0:
        return NullCaster()
    if backend == "auto":
        backend = os.environ.get("RADTREE_RAY_BACKEND", "auto")
    if backend == "auto":
        backend = "embree" if embree_available() else "numpy-bvh"
    if backend not in BACKENDS:
        raise ValueError(f"ray backend must be one of {BACKENDS} or 'auto', got {backend!r}")
    if backend == "embree":
        if not embree_available():
            raise ValueError("the embree ray backend needs the 'embreex' package")
        return EmbreeCaster(vertices, faces, workers=workers)
    return BVHCaster(vertices, faces)

