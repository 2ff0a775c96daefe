"""The shadow rays of the NumPy engine: transmittance from points towards the sun through the
scene's specular passes (a shadow ray is continued past every surface it crosses, its
transmittance multiplied by the surface's, Russian roulette on faint rays).

The per-crossing arithmetic keeps the rays' origins as a (3, n) array, one row per axis: NumPy
broadcasts over 3-wide rows ((n, 1) × (3,)) several times slower than over long rows, and
gathers 3-wide float64 rows slower than one row per axis. Every number is the one the (n, 3)
arithmetic gives (sums of three products in ``einsum``'s order).
"""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np

from radtree.engines.common.geometry import Geometry, Optics, glass_coefficients
from radtree.engines.common.kernel import kernel, triangle_rows
from radtree.engines.common.raycast import EmbreeCaster, RayCaster, hit_triangles, plane_distance
from radtree.engines.common.streams import Draws, as_draws

SHADOW_ROULETTE = 0.02  # shadow-ray transmittance below which Russian roulette starts


class _Options(Protocol):
    @property
    def max_shadow_layers(self) -> int:
        """Transmissive surfaces a shadow ray may cross."""
        ...


class ShadowTracer(Protocol):
    """What the shadow rays need of the tracer (``engine._Tracer``): the geometry, its ray
    caster, the optics, per-triangle tables (specular transmittance ``tri_ts``; glass; for the
    point sun of each hour state, rows hour × ``n_tri`` + triangle, the cosine sun · normal
    ``sun_cos`` and the origin offset ±ε ``sun_side``) and ``eps`` (m)."""

    geo: Geometry
    caster: RayCaster
    opt: Optics
    eps: float
    n_tri: int
    tri_ts: np.ndarray
    tri_glass: np.ndarray
    tri_glass_tn: np.ndarray
    glass_any: bool
    sun_cos: np.ndarray
    sun_side: np.ndarray
    sun_grazing: bool
    suns: np.ndarray
    tri_pack: np.ndarray | None

    @property
    def opts(self) -> _Options:
        """The trace options (``max_shadow_layers``)."""
        ...


def take(a: np.ndarray, i: np.ndarray) -> np.ndarray:
    """Rows ``a[i]`` of a 2-D array at integer indices (``np.take`` is several times faster
    than fancy indexing on rows)."""
    return np.take(a, i, axis=0)


def rows(d: np.ndarray, sel: np.ndarray | None) -> np.ndarray:
    """``d[sel]`` (``sel``: indices or a mask; None: all rows, copied) — except that a
    broadcast row (stride 0, the point sun's direction) stays a broadcast row."""
    if d.ndim == 2 and d.strides[0] == 0:
        k = len(d) if sel is None else (int(np.count_nonzero(sel)) if sel.dtype == bool
                                        else len(sel))
        return d[:k] if k <= len(d) else np.broadcast_to(d[0], (k, d.shape[1]))
    if sel is None:
        return np.array(d)
    return np.take(d, np.flatnonzero(sel) if sel.dtype == bool else sel, axis=0)


def transmittance(tr: ShadowTracer, origins: np.ndarray, dirs: np.ndarray,
                  rng: Draws | np.random.Generator | None = None, parallel: bool = True,
                  hour: np.ndarray | int | None = None) -> np.ndarray:
    """Transmittance of shadow rays from ``origins`` (k, 3) along ``dirs`` (k, 3, or one
    broadcast row) for the tracer ``tr``: :meth:`_Tracer.shadow`."""
    if (hour is not None and tr.tri_pack is not None
            and not tr.sun_grazing and not tr.glass_any and tr.opt.any_specular_pass
            and isinstance(tr.caster, EmbreeCaster)):
        k_mod = kernel()
        if k_mod is not None and (isinstance(hour, int) or np.asarray(dirs).strides[0] != 0):
            return _transmittance_c(k_mod, tr, origins, dirs, rng, parallel, hour)
    k = len(origins)
    vis = np.ones(k)
    idx = np.arange(k)
    draws = None if rng is None else as_draws(rng)
    # origins as rows of all rays, (3, k): the per-crossing arithmetic on long contiguous
    # rows (NumPy broadcasts over 3-wide rows several times slower)
    o = np.array(np.asarray(origins, float).T, order="C")
    d = rows(np.asarray(dirs, float), None)  # a point sun stays one broadcast row
    passes = tr.opt.any_specular_pass
    geo, ts = tr.geo, tr.tri_ts
    for layer in range(tr.opts.max_shadow_layers):
        tri, t = hit_triangles(tr.caster, o, d, parallel)
        sel = (tri >= 0).nonzero()[0]
        if len(sel) == 0:
            return vis
        tri = tri.take(sel).astype(np.intp, copy=False)  # Embree's are int32
        ih = idx.take(sel)
        if not passes:
            vis[ih] = 0.0
            return vis
        f = ts.take(tri)
        if tr.glass_any:
            glass = tr.tri_glass[tri]
            if glass.any():
                gs, gt = sel[glass], tri[glass]
                cosg = np.einsum("ij,ij->i", rows(d, gs), geo.normals[gt])
                f[glass] = glass_coefficients(cosg, tr.tri_glass_tn[gt])[0]
        v = vis.take(ih)
        v *= f
        vis[ih] = v
        # Russian roulette on faint shadow rays (unbiased: survivors are promoted)
        faint = (v > 0) & (v < SHADOW_ROULETTE)
        if draws is not None and faint.any():
            fi = faint.nonzero()[0]
            keep = (draws.rows(ih.take(fi), layer).random(len(fi)) * SHADOW_ROULETTE
                    < v.take(fi))
            v[faint] = np.where(keep, SHADOW_ROULETTE, 0.0)
            vis[ih] = v
        go = (v > 0).nonzero()[0]
        if len(go) == 0:
            return vis
        # only the rays that go on: their hit points, offset past the surface crossed
        if len(go) < len(v):
            sel, tri, ih = sel[go], tri[go], ih[go]
        idx = ih
        o, d = o.take(sel, axis=1), rows(d, sel)
        if isinstance(hour, np.ndarray):
            hour = hour[sel]
        if hour is None or tr.sun_grazing or t is not None:
            o = crossed(tr, o, d, tri, None if t is None else t[sel])
        else:
            o = crossed_sun(tr, o, d, tri, hour)
    vis[idx] = 0.0
    return vis


def kernel_tables(normals: np.ndarray, v0: np.ndarray, ts: np.ndarray, sun_cos: np.ndarray
                  ) -> np.ndarray:
    """The C kernel's per-triangle rows (n, 8): normal, first vertex, specular transmittance
    and the cosine sun · normal of the first hour state — what a crossing needs, in one
    64-byte row (one cache line where the allocation allows)."""
    pack = triangle_rows(normals, v0)
    pack[:, 6] = ts
    pack[:, 7] = sun_cos[:len(pack)]
    return pack


def _transmittance_c(k_mod: Any, tr: ShadowTracer, origins: np.ndarray, dirs: np.ndarray,
                     rng: Draws | np.random.Generator | None, parallel: bool,
                     hour: np.ndarray | int) -> np.ndarray:
    """:func:`transmittance` towards the point sun through Embree with the C kernel: per
    crossing one Embree query and one pass (``cross``: transmittance products, the rays going
    on, their next origins and float32 copies in Embree's frame), and when some are faint
    the roulette draws in NumPy and a pass over the rays going on (``roulette``). The same
    numbers as the NumPy loop."""
    caster = tr.caster
    assert isinstance(caster, EmbreeCaster)
    draws = None if rng is None else as_draws(rng)
    k = len(origins)
    vis = np.ones(k)
    idx = np.arange(k, dtype=np.int64)
    o = np.array(np.asarray(origins, float).T, order="C")  # (3, k), compacted in place
    o32 = np.empty((k, 3), np.float32)
    k_mod.frame(o, caster.frame, o32)
    d = np.asarray(dirs, float)
    if isinstance(hour, np.ndarray):  # several hour states: each ray towards its own sun
        hours: np.ndarray | None = np.array(hour, dtype=np.int64)
        h0, suns = 0, np.ascontiguousarray(tr.suns, dtype=float)
    else:
        hours, h0, suns = None, int(hour), np.array(d[0], dtype=float)
    pack, sun_cos, n_tri, eps, frame = tr.tri_pack, tr.sun_cos, tr.n_tri, tr.eps, caster.frame
    # float32 unit rows for Embree: one broadcast row for a point sun; with several hour
    # states each state's sun converted once and gathered per ray (``d`` holds those suns)
    suns32 = caster.directions32(tr.suns) if hours is not None else np.empty((0, 3), np.float32)
    d32 = caster.directions32(d) if hours is None else suns32.take(hours, axis=0)
    m = k
    for layer in range(tr.opts.max_shadow_layers):
        if hours is not None and layer:
            d32 = suns32.take(hours[:m], axis=0)
        tri = caster.query_frame(o32[:m], d32[:m], parallel)
        n_hit, m, n_faint = k_mod.cross(tri, idx, vis, SHADOW_ROULETTE, pack, sun_cos, n_tri,
                                        h0, hours, suns, eps, o, frame, o32)
        if n_hit == 0:
            return vis
        if draws is not None and n_faint:
            going = idx[:m]
            faint = going[vis.take(going) < SHADOW_ROULETTE]  # in order, as roulette takes them
            m = k_mod.roulette(idx, vis, hours, o, o32, m,
                               draws.rows(faint, layer).random(n_faint), SHADOW_ROULETTE)
        if m == 0:
            return vis
    vis[idx[:m]] = 0.0
    return vis


def crossed(tr: ShadowTracer, o: np.ndarray, d: np.ndarray, tri: np.ndarray, t: np.ndarray | None
            ) -> np.ndarray:
    """Origins (3, m) of shadow rays continued past the triangles ``tri`` they hit from
    origins ``o`` (3, m) along ``d`` (m, 3): the hit point ``o + t d`` (``t``: the
    distances, m; None: the plane distances) offset by ε to the far side."""
    geo = tr.geo
    oa = np.ascontiguousarray(o.T)
    ng = take(geo.normals, tri)
    cosd = np.einsum("ij,ij->i", d, ng)
    if t is None:
        t = plane_distance(geo.v0, geo.normals, geo.centroids, oa, d, tri, ng, cosd)
    side = np.where(cosd < 0, -tr.eps, tr.eps)
    # o + t d − n_f ε with n_f = ±n_g on the side the ray came from
    step = t[:, None] * (d[0] if d.strides[0] == 0 else d)
    step += oa
    ng *= side[:, None]
    step += ng
    return np.ascontiguousarray(step.T)


def crossed_sun(tr: ShadowTracer, o: np.ndarray, d: np.ndarray, tri: np.ndarray,
                hour: np.ndarray | int) -> np.ndarray:
    """:func:`crossed` towards the point sun of ``hour`` (the state index, one or per ray):
    the same numbers, with the cosines sun · normal and the offsets looked up per triangle
    and every step on rows of all rays (``(a·b)`` summed as ``einsum`` sums 3 terms:
    ``(a₀b₀ + a₂b₂) + a₁b₁``)."""
    geo = tr.geo
    key = tri if isinstance(hour, int) and hour == 0 else tri + hour * tr.n_tri
    ng, v = geo.normals_t.take(tri, axis=1), geo.v0_t.take(tri, axis=1)
    v -= o
    v *= ng
    t = v[0] + v[2]
    t += v[1]
    t /= tr.sun_cos.take(key)
    np.maximum(t, 0.0, out=t)
    # o + t d − n_f ε with n_f = ±n_g on the side the ray came from
    step = np.empty_like(o)
    np.multiply(d[0][:, None] if d.strides[0] == 0 else d.T, t, out=step)
    step += o
    ng *= tr.sun_side.take(key)
    step += ng
    return step
