"""The built-in Monte Carlo engine: illuminance at sensor points by vectorised path tracing.

What it computes, per sensor (a point with a normal, like ``rtrace -I``)::

    E = E_sun,direct + ∫_hemisphere L(ω) cos θ dω

with cosine-weighted hemisphere sampling at the sensor (one path per sample: the per-path
estimate is ``E_sun,direct + π · L(path)``; the reported standard error is the sample standard
deviation of those estimates / √n).

Light sources and physics, chosen to behave like Radiance:

* **Sun** — collimated, of direct normal illuminance ``state.direct_normal_lux`` from
  ``state.sun.vector`` (a point sun by default, like ``rtrace -dj 0``; the 0.533° disc can be
  sampled with ``TraceOptions(sun_disc=True)``). It is reached only by next-event estimation:
  at the sensor and at every diffuse vertex a shadow ray is cast towards the sun, and it passes
  only the *specular* part of transmissive materials (``Trans``: T_s; ``Glass``: its angular
  transmission; ``Hole`` meshes are absent). Rays that happen to point at the sun see no sun
  (as Radiance's ambient rays ignore ``light`` sources), so nothing is counted twice.
* **Sky** — rays escaping upwards see ``radtree.light.sky.sky_luminance`` (uniform, cosine,
  CIE overcast) or the Perez sky of :func:`radtree.light.perez.perez_sky` (the same ten
  ``perezlum.cal`` parameters gendaylit prints). Rays escaping downwards see the distant ground:
  ``state.ground_luminance`` for the analytic skies and "none", and ``perezlum.cal``'s value
  below the horizon (≈ gendaylit's ground brightness) for Perez — exactly the glows the Radiance
  engine writes. No ground glow when ``state.ground_glow`` is False.
* **Materials** (all surfaces two-sided) — ``Plastic``: Lambertian reflectance ρ(1 − spec) plus,
  when spec > 0, a mirror reflection of weight spec (roughness ignored); the ground material
  takes ``state.ground_reflectance``. ``Trans``: Lambertian reflection R, Lambertian
  transmission T_d into the other side, undeviated specular transmission T_s. ``Glass``:
  specular only, with Radiance's angular ``glass`` formulas (Fresnel at n = 1.52 with the
  transmissivity along the refracted path, multiple internal reflections): transmission T(θ)
  and mirror reflection R(θ) (≈ 8 % at normal incidence).
* **Bounces** — ``params.max_bounces`` counts diffuse segments exactly like ``rtrace -ab``:
  the sensor's sample is bounce 1, the surface at the end of the last allowed segment still
  gets its direct sun but no further diffuse ray. Specular events (T_s, glass, mirror) do not
  count as bounces (capped separately). Path weights are multiplied by the surface's total
  reflectance + transmittance and Russian roulette starts below ``roulette_weight`` (0.05).

Rays are processed in batches of at most ``batch_paths`` paths (arrays of that length, one
first-hit query per bounce plus the shadow queries), never a Python loop per ray.
"""

from __future__ import annotations

import hashlib
import math
import threading
import weakref
import zlib
from dataclasses import dataclass

import numpy as np

from radtree.config import EngineParams
from radtree.engines.base import GridResult
from radtree.engines.numpy.raycast import RayCaster, embree_available, make_caster
from radtree.engines.numpy.sampling import cosine_hemisphere, mirror, uniform_cone
from radtree.errors import EngineError
from radtree.light.sky import SkyState, sky_luminance
from radtree.light.sun import SUN_HALF_ANGLE_DEG
from radtree.optics import Glass, Hole, Plastic, Trans
from radtree.scene import Scene, SensorGrid

ENGINE_NAME = "numpy"
GLASS_INDEX = 1.52  # Radiance's refractive index of glass
SHADOW_ROULETTE = 0.02  # shadow-ray transmittance below which Russian roulette starts


@dataclass(frozen=True)
class TraceOptions:
    """Settings of the Monte Carlo engine that are not in :class:`EngineParams`."""

    backend: str = "auto"  # "auto" | "embree" | "numpy-bvh"
    sun_disc: bool = False  # sample the 0.533° sun disc (penumbrae) instead of a point sun
    roulette_weight: float = 0.05  # Russian roulette below this path weight
    batch_paths: int = 1 << 18  # paths per batch (bounded memory)
    max_specular: int = 32  # specular events per path
    max_shadow_layers: int = 64  # transmissive surfaces a shadow ray may cross
    epsilon: float | None = None  # origin offset (m); None = 2e-6 × scene size, ≥ 1e-5


DEFAULT_OPTIONS = TraceOptions()


def describe(backend: str = "auto") -> str:
    """Which ray backend the engine uses: ``embree`` (trimesh + embreex) or ``numpy-bvh``."""
    import os

    chosen = backend if backend != "auto" else os.environ.get("RADTREE_RAY_BACKEND", "auto")
    if chosen == "auto":
        chosen = "embree" if embree_available() else "numpy-bvh"
    if chosen == "embree":
        import trimesh

        return f"numpy Monte Carlo engine, ray backend embree (trimesh {trimesh.__version__} + embreex)"
    return "numpy Monte Carlo engine, ray backend numpy-bvh (vectorised NumPy BVH)"


# --------------------------------------------------------------------------- geometry + optics


class Geometry:
    """All light-interacting triangles of a scene, with their material index and ray caster."""

    def __init__(self, scene: Scene, backend: str, workers: int):
        meshes = scene.solid_meshes()
        self.material_names = sorted({m.material for m in meshes})
        mat_index = {n: i for i, n in enumerate(self.material_names)}
        verts, faces, tri_mat, offset = [], [], [], 0
        for m in meshes:
            if m.n_triangles == 0:
                continue
            verts.append(m.vertices)
            faces.append(m.faces + offset)
            tri_mat.append(np.full(m.n_triangles, mat_index[m.material], np.int64))
            offset += len(m.vertices)
        self.vertices = np.vstack(verts) if verts else np.zeros((0, 3))
        self.faces = np.vstack(faces) if faces else np.zeros((0, 3), np.int64)
        self.tri_material = np.concatenate(tri_mat) if tri_mat else np.zeros(0, np.int64)
        tris = self.vertices[self.faces]
        n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]) if len(tris) else \
            np.zeros((0, 3))
        length = np.linalg.norm(n, axis=1)
        bad = length < 1e-300
        n[bad] = (0.0, 0.0, 1.0)
        length[bad] = 1.0
        self.normals = n / length[:, None]
        pts = [self.vertices] + [g.points for g in scene.grids.values()]
        allp = np.vstack(pts)
        self.size = float(np.ptp(allp, axis=0).max()) if len(allp) else 1.0
        self.caster: RayCaster = make_caster(self.vertices, self.faces, backend, workers)


_GEOMETRY_CACHE: dict[int, tuple[weakref.ref, str, Geometry]] = {}
_GEOMETRY_LOCK = threading.Lock()


def _fingerprint(scene: Scene, backend: str, workers: int) -> str:
    h = hashlib.blake2b(digest_size=16)
    h.update(f"{backend}|{workers}".encode())
    for m in scene.solid_meshes():
        h.update(f"{m.name}|{m.material}|{m.vertices.shape}|{m.faces.shape}".encode())
        h.update(np.ascontiguousarray(m.vertices).tobytes())
        h.update(np.ascontiguousarray(m.faces).tobytes())
    for g in scene.grids.values():
        h.update(np.ascontiguousarray(g.points).tobytes())
    return h.hexdigest()


def scene_geometry(scene: Scene, backend: str, workers: int) -> Geometry:
    """The scene's triangles and ray caster, cached across hours of the same scene.

    Thread-safe: the scenario runner traces several hours of one scene in parallel threads
    (they then share one ray caster; Embree queries are thread-safe).
    """
    key = id(scene)
    fp = _fingerprint(scene, backend, workers)
    with _GEOMETRY_LOCK:
        hit = _GEOMETRY_CACHE.get(key)
        if hit is not None and hit[0]() is scene and hit[1] == fp:
            return hit[2]
        geo = Geometry(scene, backend, workers)
        for k in [k for k, v in _GEOMETRY_CACHE.items() if v[0]() is None]:
            del _GEOMETRY_CACHE[k]
        _GEOMETRY_CACHE[key] = (weakref.ref(scene), fp, geo)
        return geo


@dataclass
class Optics:
    """Per-material coefficients (arrays indexed by material index)."""

    rd: np.ndarray  # diffuse reflectance
    td: np.ndarray  # diffuse transmittance
    ts: np.ndarray  # specular (undeviated) transmittance
    rm: np.ndarray  # mirror reflectance (plastic specularity)
    glass_tn: np.ndarray  # glass transmissivity (NaN = not glass)

    @property
    def any_specular_pass(self) -> bool:
        return bool(np.any(self.ts > 0) or np.any(np.isfinite(self.glass_tn)))


def scene_optics(scene: Scene, state: SkyState, names: list[str]) -> Optics:
    k = len(names)
    rd, td, ts, rm = np.zeros(k), np.zeros(k), np.zeros(k), np.zeros(k)
    tn = np.full(k, np.nan)
    for i, name in enumerate(names):
        m = scene.materials[name]
        if isinstance(m, Plastic):
            rho = state.ground_reflectance if name == scene.ground_material else m.reflectance
            rd[i] = rho * (1.0 - m.specularity)
            rm[i] = m.specularity
        elif isinstance(m, Trans):
            rd[i], td[i], ts[i] = m.reflectance, m.diffuse_transmittance, m.specular_transmittance
        elif isinstance(m, Glass):
            tn[i] = m.transmissivity
        elif isinstance(m, Hole):  # pragma: no cover - holes are removed with solid_meshes()
            ts[i] = 1.0
        else:  # pragma: no cover
            raise EngineError(f"material '{name}' of type {type(m).__name__} is not supported "
                              "by the in-process engines (a BSDF crown, [tree] representation"
                              " = \"bsdf\", is Radiance only: use --engine radiance)")
    return Optics(rd, td, ts, rm, tn)


def glass_coefficients(cos_i: np.ndarray, transmissivity: np.ndarray
                       ) -> tuple[np.ndarray, np.ndarray]:
    """Transmittance and reflectance of Radiance ``glass`` at incidence cosines ``cos_i``.

    Fresnel reflection (both polarisations, n = 1.52), the transmissivity applied along the
    refracted path (tn^(1/cos θ_t)) and the infinite series of internal reflections — the
    formulas of Radiance's ``m_glass``.
    """
    c = np.clip(np.abs(cos_i), 1e-6, 1.0)
    n = GLASS_INDEX
    cos2 = np.sqrt((1.0 - 1.0 / (n * n)) + c * c / (n * n))
    d = np.power(transmissivity, 1.0 / cos2)
    r1e = ((c - n * cos2) / (c + n * cos2)) ** 2
    r1m = ((1.0 / c - n / cos2) / (1.0 / c + n / cos2)) ** 2
    t = (0.5 * (1 - r1e) ** 2 * d / (1 - r1e * r1e * d * d)
         + 0.5 * (1 - r1m) ** 2 * d / (1 - r1m * r1m * d * d))
    d2 = d * d
    r = (0.5 * r1e * (1 + (1 - 2 * r1e) * d2) / (1 - r1e * r1e * d2)
         + 0.5 * r1m * (1 + (1 - 2 * r1m) * d2) / (1 - r1m * r1m * d2))
    return t, r


class Environment:
    """Luminance (cd/m²) of whatever an escaping ray sees: sky above, distant ground below."""

    def __init__(self, state: SkyState):
        self.state = state
        self.perez = None
        if state.sky_model == "perez":
            from radtree.light.perez import perez_sky

            self.perez = perez_sky(state)
        self.ground = state.ground_luminance

    def __call__(self, d: np.ndarray) -> np.ndarray:
        dz = d[:, 2]
        up = dz > 0.0
        if self.perez is not None:
            L = self.perez.luminance(d)
            return np.where(up | self.state.ground_glow, L, 0.0)
        return np.where(up, sky_luminance(self.state, dz), self.ground)


# --------------------------------------------------------------------------- the tracer


class _Tracer:
    def __init__(self, geo: Geometry, optics: Optics, state: SkyState, params: EngineParams,
                 opts: TraceOptions):
        self.geo = geo
        self.caster = geo.caster
        self.opt = optics
        self.env = Environment(state)
        self.state = state
        self.max_bounces = int(params.max_bounces)
        self.opts = opts
        self.eps = opts.epsilon if opts.epsilon is not None else max(1e-5, 2e-6 * geo.size)
        self.sun_on = state.sun_on
        self.dni = float(state.direct_normal_lux)
        self.sun = np.asarray(state.sun.vector, float)
        self.sun = self.sun / np.linalg.norm(self.sun)

    # -- sun
    def sun_directions(self, k: int, rng: np.random.Generator) -> np.ndarray:
        if self.opts.sun_disc:
            return uniform_cone(self.sun, math.radians(SUN_HALF_ANGLE_DEG), k, rng)
        return np.broadcast_to(self.sun, (k, 3))

    def shadow(self, origins: np.ndarray, dirs: np.ndarray,
               rng: np.random.Generator | None = None) -> np.ndarray:
        """Transmittance towards the sun: 1 if free, product of specular passes, else 0.

        With ``rng``, faint shadow rays are continued by Russian roulette (unbiased); without,
        the product is exact (the sensors' own direct sun).
        """
        k = len(origins)
        vis = np.ones(k)
        idx = np.arange(k)
        o = np.array(origins, float)
        d = np.array(dirs, float)
        passes = self.opt.any_specular_pass
        for _ in range(self.opts.max_shadow_layers):
            tri, t = self.caster.first_hit(o, d)
            hit = tri >= 0
            if not hit.any():
                return vis
            idx, o, d, tri, t = idx[hit], o[hit], d[hit], tri[hit], t[hit]
            if not passes:
                vis[idx] = 0.0
                return vis
            mat = self.geo.tri_material[tri]
            ng = self.geo.normals[tri]
            cosd = np.einsum("ij,ij->i", d, ng)
            f = self.opt.ts[mat].copy()
            glass = np.isfinite(self.opt.glass_tn[mat])
            if glass.any():
                f[glass] = glass_coefficients(cosd[glass], self.opt.glass_tn[mat][glass])[0]
            vis[idx] *= f
            # Russian roulette on faint shadow rays (unbiased: survivors are promoted)
            v = vis[idx]
            faint = (v > 0) & (v < SHADOW_ROULETTE)
            if rng is not None and faint.any():
                keep = rng.random(int(faint.sum())) * SHADOW_ROULETTE < v[faint]
                v[faint] = np.where(keep, SHADOW_ROULETTE, 0.0)
                vis[idx] = v
            go = v > 0
            nf = np.where((cosd < 0)[:, None], ng, -ng)
            o = (o + t[:, None] * d - nf * self.eps)[go]
            idx, d = idx[go], d[go]
            if len(idx) == 0:
                return vis
        vis[idx] = 0.0
        return vis

    def sensor_sun(self, points: np.ndarray, normals: np.ndarray, dirs: np.ndarray | None = None,
                   rng: np.random.Generator | None = None) -> np.ndarray:
        """Direct sun illuminance on sensors (shadow rays start exactly at the points)."""
        k = len(points)
        out = np.zeros(k)
        if not self.sun_on or k == 0:
            return out
        if dirs is None:
            dirs = np.broadcast_to(self.sun, (k, 3))
        cos = np.einsum("ij,ij->i", normals, dirs)
        need = cos > 0
        if need.any():
            out[need] = self.dni * cos[need] * self.shadow(points[need], dirs[need], rng)
        return out

    # -- paths
    def paths(self, points: np.ndarray, normals: np.ndarray, rng: np.random.Generator
              ) -> np.ndarray:
        """Radiance (cd/m²) seen along one cosine-sampled direction from each sensor sample."""
        k = len(points)
        acc = np.zeros(k)
        alive = np.arange(k)
        o = np.array(points, float)
        d = cosine_hemisphere(np.asarray(normals, float), rng)
        beta = np.ones(k)
        depth = np.ones(k, np.int64)
        nspec = np.zeros(k, np.int64)
        geo, opt, eps = self.geo, self.opt, self.eps
        thr = self.opts.roulette_weight
        while len(alive):
            tri, t = self.caster.first_hit(o, d)
            miss = tri < 0
            if miss.any():
                acc[alive[miss]] += beta[miss] * self.env(d[miss])
                hit = ~miss
                alive, o, d, beta, depth, nspec, tri, t = (
                    alive[hit], o[hit], d[hit], beta[hit], depth[hit], nspec[hit], tri[hit],
                    t[hit])
                if len(alive) == 0:
                    break
            p = o + t[:, None] * d
            ng = geo.normals[tri]
            cosd = np.einsum("ij,ij->i", d, ng)
            front = cosd < 0
            nf = np.where(front[:, None], ng, -ng)  # normal on the side the ray came from
            mat = geo.tri_material[tri]
            rd, td = opt.rd[mat], opt.td[mat]

            # next-event estimation towards the sun
            if self.sun_on:
                sd = self.sun_directions(len(alive), rng)
                cs = np.einsum("ij,ij->i", nf, sd)
                f = np.where(cs > 0, rd * cs, -td * cs) / math.pi
                need = f > 0
                if need.any():
                    so = p[need] + nf[need] * (eps * np.sign(cs[need]))[:, None]
                    vis = self.shadow(so, sd[need], rng)
                    acc[alive[need]] += beta[need] * self.dni * f[need] * vis

            # scattering events: diffuse reflect, diffuse transmit, specular transmit, mirror
            coef = np.stack([rd, td, opt.ts[mat], opt.rm[mat]], axis=1)
            glass = np.isfinite(opt.glass_tn[mat])
            if glass.any():
                tg, rg = glass_coefficients(cosd[glass], opt.glass_tn[mat][glass])
                coef[glass, 2] = tg
                coef[glass, 3] = rg
            coef[:, :2] *= (depth < self.max_bounces)[:, None]
            coef[:, 2:] *= (nspec < self.opts.max_specular)[:, None]
            total = coef.sum(axis=1)
            beta = beta * total
            u = rng.random(len(alive))
            low = beta < thr
            survive = (total > 0) & (~low | (u * thr < beta))
            beta = np.where(low, thr, beta)
            cum = np.cumsum(coef, axis=1)
            pick = rng.random(len(alive)) * total
            ev = np.minimum((pick[:, None] >= cum).sum(axis=1), 3)

            alive, p, d, nf, beta, depth, nspec, ev = (
                alive[survive], p[survive], d[survive], nf[survive], beta[survive],
                depth[survive], nspec[survive], ev[survive])
            if len(alive) == 0:
                break
            new_d = d.copy()
            side = np.ones(len(alive))  # +1: leave on the incoming side, -1: cross
            diff_r, diff_t = ev == 0, ev == 1
            diffuse = diff_r | diff_t
            if diffuse.any():
                axis = np.where(diff_r[diffuse, None], nf[diffuse], -nf[diffuse])
                new_d[diffuse] = cosine_hemisphere(axis, rng)
            spec_t, mir = ev == 2, ev == 3
            if mir.any():
                new_d[mir] = mirror(d[mir], nf[mir])
            side[diff_t | spec_t] = -1.0
            o = p + nf * (eps * side)[:, None]
            d = new_d
            depth = depth + diffuse
            nspec = nspec + (spec_t | mir)
        return acc


# --------------------------------------------------------------------------- public API


def _grid_seed(seed: int, name: str) -> np.random.Generator:
    return np.random.default_rng(np.random.SeedSequence([int(seed) & 0xFFFFFFFF,
                                                         zlib.crc32(name.encode())]))


def _trace_grid(tracer: _Tracer, grid: SensorGrid, n_paths: int, rng: np.random.Generator
                ) -> GridResult:
    pts, nrm = grid.points, grid.normals
    n_s = len(grid)
    disc = tracer.opts.sun_disc
    direct = np.zeros(n_s) if disc else tracer.sensor_sun(pts, nrm)
    if tracer.max_bounces <= 0 and not disc:
        return GridResult(direct, np.zeros(n_s))
    n_paths = max(1, int(n_paths))
    total = n_s * n_paths
    count = np.zeros(n_s)
    mean = np.zeros(n_s)
    m2 = np.zeros(n_s)
    batch = max(1, int(tracer.opts.batch_paths))
    for start in range(0, total, batch):
        pid = np.arange(start, min(total, start + batch))
        sensor = pid // n_paths
        x = np.zeros(len(pid))
        if tracer.max_bounces > 0:
            x += math.pi * tracer.paths(pts[sensor], nrm[sensor], rng)
        if disc:
            x += tracer.sensor_sun(pts[sensor], nrm[sensor],
                                   tracer.sun_directions(len(pid), rng), rng)
        # merge the batch's per-sensor mean and M2 (Chan et al.)
        cb = np.bincount(sensor, minlength=n_s).astype(float)
        sb = np.bincount(sensor, x, minlength=n_s)
        has = cb > 0
        mb = np.where(has, sb / np.where(has, cb, 1.0), 0.0)
        m2b = np.bincount(sensor, (x - mb[sensor]) ** 2, minlength=n_s)
        n_new = count + cb
        delta = mb - mean
        with np.errstate(invalid="ignore", divide="ignore"):
            mean = np.where(has, mean + delta * cb / np.where(has, n_new, 1.0), mean)
            m2 = np.where(has, m2 + m2b + delta ** 2 * count * cb / np.where(has, n_new, 1.0),
                          m2)
        count = n_new
    var = m2 / np.maximum(count - 1.0, 1.0)
    stderr = np.sqrt(np.maximum(var, 0.0) / count)
    return GridResult(direct + mean, stderr)


def trace(scene: Scene, state: SkyState, params: EngineParams, grids: list[str] | None = None,
          seed: int | None = None, options: TraceOptions = DEFAULT_OPTIONS
          ) -> dict[str, GridResult]:
    """:func:`trace_hour` with explicit :class:`TraceOptions`."""
    names = list(scene.grids) if grids is None else list(grids)
    missing = [g for g in names if g not in scene.grids]
    if missing:
        raise EngineError(f"unknown sensor grid(s): {', '.join(missing)}")
    if params.rays < 1:
        raise EngineError(f"engine.rays must be ≥ 1, got {params.rays}")
    seed = params.seed if seed is None else seed
    geo = scene_geometry(scene, options.backend, int(getattr(params, "workers", 2) or 1))
    tracer = _Tracer(geo, scene_optics(scene, state, geo.material_names), state, params, options)
    return {name: _trace_grid(tracer, scene.grids[name], params.rays, _grid_seed(seed, name))
            for name in names}


def trace_hour(scene: Scene, state: SkyState, params: EngineParams,
               grids: list[str] | None = None, seed: int | None = None
               ) -> dict[str, GridResult]:
    """Illuminance (lux) and its Monte Carlo standard error per sensor of each grid, one hour.

    ``params.rays`` paths per sensor, ``params.max_bounces`` diffuse bounces (like ``-ab``),
    ``seed`` (default ``params.seed``): the same seed gives identical numbers; each grid draws
    from its own stream (seed, grid name), so a grid's values do not depend on which other
    grids are traced.
    """
    return trace(scene, state, params, grids, seed, DEFAULT_OPTIONS)
