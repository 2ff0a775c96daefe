"""Small geometry helpers shared by the crown models (local façade frame, metres, radians).

Local coordinates are the façade frame's (u, n, z): u along the façade, n out of the façade
towards the street, z up (see :mod:`radtree.site.frame`). Directions are unit vectors in the
same frame.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

GOLDEN_ANGLE = math.pi * (3.0 - math.sqrt(5.0))


def unit(v: np.ndarray) -> np.ndarray:
    """Rows of ``v`` scaled to unit length."""
    v = np.asarray(v, float)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def triangle_solid_angles(triangles: np.ndarray, point: np.ndarray) -> np.ndarray:
    """Solid angle (sr) of each triangle (M, 3, 3) seen from ``point`` (3,).

    Van Oosterom & Strackee (1983): tan(Ω/2) = |a·(b×c)| / (abc + (a·b)c + (a·c)b + (b·c)a).
    """
    t = np.asarray(triangles, float) - np.asarray(point, float)
    a, b, c = t[:, 0], t[:, 1], t[:, 2]
    la, lb, lc = (np.linalg.norm(x, axis=1) for x in (a, b, c))
    num = np.abs(np.einsum("ij,ij->i", a, np.cross(b, c)))
    den = (la * lb * lc + np.einsum("ij,ij->i", a, b) * lc + np.einsum("ij,ij->i", a, c) * lb
           + np.einsum("ij,ij->i", b, c) * la)
    return 2.0 * np.arctan2(num, den)


def fibonacci_hemisphere(count: int, axis: int = 1) -> np.ndarray:
    """``count`` near-uniform unit directions over the hemisphere whose pole is local axis
    ``axis`` (default 1 = n: the half-space in front of the façade). Equal-area spiral: the
    pole component is uniform in (0, 1), so every point stands for the same solid angle."""
    i = np.arange(count, dtype=float)
    c = (i + 0.5) / count
    s = np.sqrt(1.0 - c * c)
    phi = GOLDEN_ANGLE * i
    other = [k for k in range(3) if k != axis]
    d = np.empty((count, 3))
    d[:, axis] = c
    d[:, other[0]] = s * np.cos(phi)
    d[:, other[1]] = s * np.sin(phi)
    return d


def fibonacci_cosine_directions(count: int, normal: np.ndarray, rotation: float = 0.0) -> np.ndarray:
    """``count`` deterministic cosine-weighted directions about ``normal`` (Malley's method on
    a Fibonacci disk: every direction carries the same weight in an illuminance integral).
    ``rotation`` (rad) turns the pattern about the normal."""
    nrm = unit(np.asarray(normal, float).reshape(3))
    ref = np.array([0.0, 0.0, 1.0]) if abs(nrm[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    e1 = unit(np.cross(ref, nrm))
    e2 = np.cross(nrm, e1)
    i = np.arange(count, dtype=float)
    r = np.sqrt((i + 0.5) / count)
    phi = GOLDEN_ANGLE * i + rotation
    x, y = r * np.cos(phi), r * np.sin(phi)
    z = np.sqrt(np.clip(1.0 - r * r, 0.0, 1.0))
    return x[:, None] * e1 + y[:, None] * e2 + z[:, None] * nrm


def _stitch(a: np.ndarray, a_phi: np.ndarray, b: np.ndarray, b_phi: np.ndarray) -> list[tuple]:
    """Triangles joining two closed rings of vertex indices sorted by angle (zipper merge)."""
    ma, mb = len(a), len(b)
    out: list[tuple] = []
    i = j = 0
    two_pi = 2.0 * math.pi
    while i < ma or j < mb:
        an = a_phi[(i + 1) % ma] + two_pi * ((i + 1) // ma)
        bn = b_phi[(j + 1) % mb] + two_pi * ((j + 1) // mb)
        if j >= mb or (i < ma and an <= bn):
            out.append((a[i % ma], a[(i + 1) % ma], b[j % mb]))
            i += 1
        else:
            out.append((a[i % ma], b[(j + 1) % mb], b[j % mb]))
            j += 1
    return out


@lru_cache(maxsize=16)
def hemisphere_mesh(rings: int) -> tuple[np.ndarray, np.ndarray]:
    """A watertight unit hemisphere around +n (the half n ≥ 0), rim in the plane n = 0.

    ``rings`` rings of equal polar step 90°/rings; ring i carries ≈ 4·rings·sin θ_i vertices,
    so the triangles are close to equal in area. Triangles ≈ 5.1·rings². Returns unit
    vertex directions (V, 3) and faces (F, 3), read-only (cached: shared by every caller).
    """
    if rings < 1:
        raise ValueError("a hemisphere needs at least one ring")
    verts = [np.array([[0.0, 1.0, 0.0]])]
    ring_idx = [np.array([0])]
    ring_phi = [np.array([0.0])]
    start = 1
    for i in range(1, rings + 1):
        theta = 0.5 * math.pi * i / rings
        m = max(3, int(round(4 * rings * math.sin(theta))))
        phi = 2.0 * math.pi * (np.arange(m) + 0.5 * (i % 2)) / m
        st = math.sin(theta)
        ct = 0.0 if i == rings else math.cos(theta)
        verts.append(np.column_stack([st * np.cos(phi), np.full(m, ct), st * np.sin(phi)]))
        ring_idx.append(np.arange(start, start + m))
        ring_phi.append(phi)
        start += m
    faces: list[tuple] = []
    first = ring_idx[1]
    for k in range(len(first)):
        faces.append((0, first[k], first[(k + 1) % len(first)]))
    for i in range(1, rings):
        faces.extend(_stitch(ring_idx[i], ring_phi[i], ring_idx[i + 1], ring_phi[i + 1]))
    v, f = np.vstack(verts), np.asarray(faces, dtype=np.int64)
    v.flags.writeable = f.flags.writeable = False   # cached: shared by every caller
    return v, f


def clip_polygons(polys: np.ndarray, counts: np.ndarray, normal: np.ndarray,
                  offset: float | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Keep the part of each convex planar polygon where normal·x ≥ offset (Sutherland–Hodgman,
    all polygons at once). ``polys`` (n, K, D) holds polygon i in its first ``counts[i]``
    rows (D = 3, or 2 for polygons in a plane's own coordinates); ``offset`` is one number or
    one per polygon (n,). Returns the clipped polygons the same way (n, K', D) with their
    counts. A result of fewer than 3 corners counts 0 (dropped), so later clips leave it
    empty."""
    n, k, dim = polys.shape
    if n == 0:
        return polys, counts
    slot = np.arange(k)
    valid = slot[None, :] < counts[:, None]
    nxt = (slot[None, :] + 1) % np.maximum(counts, 1)[:, None]
    off = np.asarray(offset, dtype=float)
    with np.errstate(invalid="ignore"):   # rows beyond a polygon's count may hold NaN
        d = polys @ normal - (off[:, None] if off.ndim else off)
    q = np.take_along_axis(polys, nxt[:, :, None], axis=1)
    dq = np.take_along_axis(d, nxt, axis=1)
    keep = valid & (d >= 0)
    crossing = valid & ((d >= 0) != (dq >= 0))
    with np.errstate(divide="ignore", invalid="ignore"):   # t is used where crossing only
        t = d / (d - dq)
        cut = polys + t[:, :, None] * (q - polys)
    cand = np.stack([polys, cut], axis=2).reshape(n, 2 * k, dim)
    use = np.stack([keep, crossing], axis=2).reshape(n, 2 * k)
    out_counts = use.sum(axis=1)
    order = np.argsort(~use, axis=1, kind="stable")[:, :max(int(out_counts.max()), 1)]
    out = np.take_along_axis(cand, order[:, :, None], axis=1)
    return out, np.where(out_counts >= 3, out_counts, 0)


def polygons_to_mesh(polygons: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Convex planar polygons → vertices and fan-triangulated faces (polygons of fewer than 3
    corners dropped; triangle ``(0, i, i + 1)`` of each polygon in order)."""
    kept = [p for p in polygons if len(p) >= 3]
    if not kept:
        return np.zeros((0, 3)), np.zeros((0, 3), np.int64)
    return flat_polygons_to_mesh(np.concatenate(kept),
                                 np.fromiter((len(p) for p in kept), np.int64, len(kept)))


def flat_polygons_to_mesh(points: np.ndarray, counts: np.ndarray
                          ) -> tuple[np.ndarray, np.ndarray]:
    """Convex planar polygons given one after another — ``points`` (sum(counts), 3), polygon i
    the next ``counts[i]`` ≥ 3 rows — → the vertices (``points`` itself) and fan-triangulated
    faces, as :func:`polygons_to_mesh`."""
    k = np.asarray(counts, np.int64)
    offset = np.concatenate([[0], np.cumsum(k)[:-1]])
    n_tri = k - 2
    first = np.repeat(offset, n_tri)
    local = ranks_within(n_tri) + 1
    faces = np.column_stack([first, first + local, first + local + 1])
    return points, faces


def ranks_within(sizes: np.ndarray) -> np.ndarray:
    """0, 1, …, sizes[0] − 1, 0, 1, …, sizes[1] − 1, …: each item's place in its group, for
    groups of ``sizes`` items laid one after another."""
    sizes = np.asarray(sizes, np.int64)
    return np.arange(int(sizes.sum())) - np.repeat(np.cumsum(sizes) - sizes, sizes)


def quads_to_mesh(quads: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(k, 4, 3) planar quads (corners in order) → vertices (4k, 3), faces (2k, 3)."""
    k = len(quads)
    base = 4 * np.arange(k)[:, None]
    faces = np.concatenate([base + [0, 1, 2], base + [0, 2, 3]], axis=0)
    return np.asarray(quads, float).reshape(-1, 3), faces.astype(np.int64)


def cylinder_mesh(centre_uv: tuple[float, float], radius: float, z0: float, z1: float,
                  segments: int = 16) -> tuple[np.ndarray, np.ndarray]:
    """Side of a vertical cylinder (no caps) in local coordinates, axis at (u, n)."""
    phi = 2.0 * math.pi * np.arange(segments) / segments
    u = centre_uv[0] + radius * np.cos(phi)
    n = centre_uv[1] + radius * np.sin(phi)
    bottom = np.column_stack([u, n, np.full(segments, z0)])
    top = np.column_stack([u, n, np.full(segments, z1)])
    verts = np.vstack([bottom, top])
    i = np.arange(segments)
    j = (i + 1) % segments
    faces = np.concatenate([np.column_stack([i, j, j + segments]),
                            np.column_stack([i, j + segments, i + segments])])
    return verts, faces.astype(np.int64)
