"""The built-in Monte Carlo engine: illuminance at sensor points by vectorised path tracing.

What it computes, per sensor (a point with a normal, like ``rtrace -I``)::

    E = E_sun,direct + ∫_hemisphere L(ω) cos θ dω

with cosine-weighted hemisphere sampling at the sensor (one path per sample: the per-path
estimate is ``E_sun,direct + π · L(path)``). With ``engine.sampling = "sobol"`` (default) the
first directions of a sensor's paths are stratified — randomly shifted Sobol' nets in
replicates, the standard error from the spread of the replicate means
(:mod:`radtree.engines.numpy.qmc`); with ``"random"`` they are pseudo-random and the standard
error is the sample standard deviation of the per-path estimates / √n.

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
* **Bounces** — ``params.numpy.max_bounces`` counts diffuse segments exactly like ``rtrace -ab``:
  the sensor's sample is bounce 1, the surface at the end of the last allowed segment still
  gets its direct sun but no further diffuse ray. Specular events (T_s, glass, mirror) do not
  count as bounces (capped separately). Path weights are multiplied by the surface's total
  reflectance + transmittance and Russian roulette starts below ``roulette_weight`` (0.05).

Rays are processed in batches of at most ``batch_paths`` paths (arrays of that length, one
first-hit query per bounce plus the shadow queries), never a Python loop per ray. With
``engine.workers`` > 1 a batch is split into that many parts (of at least ``min_part_paths``;
blocks of ``SPLIT_BLOCK`` paths taken in turn) traced in parallel threads, each running its own
NumPy work and single-threaded Embree queries. Each path draws from its own counter-based stream
(:mod:`radtree.engines.common.streams`), so the parts never wait for each other and the numbers
depend neither on ``workers`` nor on ``batch_paths``.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from radtree.config import EngineParams
from radtree.engines.common.geometry import (
    GLASS_INDEX,
    Environment,
    Geometry,
    Optics,
    glass_coefficients,
    scene_geometry,
    scene_optics,
)
from radtree.engines.common.kernel import describe as kernel_describe
from radtree.engines.common.kernel import kernel
from radtree.engines.common.raycast import embree_available
from radtree.engines.common.sampling import cosine_hemisphere
from radtree.engines.common.streams import (
    FIRST_DIRECTIONS,
    SENSOR_SUN_ROULETTE,
    Draws,
    PathStreams,
    as_draws,
)
from radtree.engines.numpy.bounce import Batch, BounceSteps
from radtree.engines.numpy.shadow import kernel_tables
from radtree.engines.numpy.shadow import rows as _rows
from radtree.light.sky import SkyState

__all__ = ["DEFAULT_OPTIONS", "ENGINE_NAME", "GLASS_INDEX", "Environment", "Geometry", "Optics",
           "TraceOptions", "describe", "glass_coefficients", "scene_geometry", "scene_optics"]

ENGINE_NAME = "numpy"


SPLIT_BLOCK = 256  # consecutive paths a part of a batch split takes in turn


@dataclass(frozen=True)
class TraceOptions:
    """Settings of the Monte Carlo engine that are not in :class:`EngineParams`."""

    backend: str = "auto"  # "auto" | "embree" | "numpy-bvh"
    sun_disc: bool = False  # sample the 0.533° sun disc (penumbrae) instead of a point sun
    roulette_weight: float = 0.05  # Russian roulette below this path weight
    batch_paths: int = 1 << 18  # paths per batch (bounded memory)
    min_part_paths: int = 4096  # a batch is split over the worker threads in parts ≥ this
    max_specular: int = 32  # specular events per path
    max_shadow_layers: int = 64  # transmissive surfaces a shadow ray may cross
    epsilon: float | None = None  # origin offset (m); None = 2e-6 × scene size, ≥ 1e-5


DEFAULT_OPTIONS = TraceOptions()


def describe(backend: str = "auto") -> str:
    """Which ray backend the engine uses: ``embree`` (trimesh + embreex) or ``numpy-bvh``, and
    with Embree which shadow-ray kernel (the compiled one or NumPy: the same numbers)."""
    import os

    chosen = backend if backend != "auto" else os.environ.get("RADTREE_RAY_BACKEND", "auto")
    if chosen == "auto":
        chosen = "embree" if embree_available() else "numpy-bvh"
    if chosen == "embree":
        import trimesh

        return (f"numpy Monte Carlo engine, ray backend embree (trimesh {trimesh.__version__} + "
                f"embreex), {kernel_describe()}")
    return "numpy Monte Carlo engine, ray backend numpy-bvh (vectorised NumPy BVH)"


# --------------------------------------------------------------------------- the tracer


class _Tracer(BounceSteps):
    def __init__(self, geo: Geometry, optics: Optics, state: SkyState, params: EngineParams,
                 opts: TraceOptions, more: Sequence[tuple[SkyState, Optics]] = ()):
        """``more``: further hour states (with their optics) traced in the same batch — path
        arrays then carry each path's state index (0 = ``state``)."""
        self.geo = geo
        self.caster = geo.caster
        self.media = geo.media   # turbid crowns (radtree.engines.common.turbid) or None
        self.opt = optics
        self.env = Environment(state)
        self.state = state
        self.max_bounces = int(params.numpy.max_bounces)
        self.opts = opts
        self.workers = max(1, int(getattr(params, "workers", 2) or 1))
        self.eps = opts.epsilon if opts.epsilon is not None else max(1e-5, 2e-6 * geo.size)
        self.sun_on = state.sun_on
        self.dni = float(state.direct_normal_lux)
        self.sun = np.asarray(state.sun.vector, float)
        self.sun = self.sun / np.linalg.norm(self.sun)
        # per-triangle optics (one gather per query instead of material index + coefficients)
        mat = geo.tri_material
        self.tri_coef = optics.per_triangle(mat)
        self.tri_coef_t = np.ascontiguousarray(self.tri_coef.T)  # (4, n): a row per event
        self.tri_ts = np.ascontiguousarray(self.tri_coef[:, 2])
        self.n_tri = len(mat)
        self.tri_glass_tn = optics.glass_tn[mat]
        self.tri_glass = np.isfinite(self.tri_glass_tn)
        self.glass_any = bool(self.tri_glass.any())
        # several hour states: per-state sun, direct normal lux (0 when the sun is off), sky
        # and per-triangle optics, looked up by each path's state index
        if more:
            states = [state, *(st for st, _ in more)]
            self.envs = [self.env, *(Environment(st) for st, _ in more)]
            self.suns = np.array([np.asarray(st.sun.vector, float) for st in states])
            self.suns /= np.linalg.norm(self.suns, axis=1)[:, None]
            self.dnis = np.array([float(st.direct_normal_lux) if st.sun_on else 0.0
                                  for st in states])
            self.sun_on = any(st.sun_on for st in states)
            self.tri_coefs = np.stack([self.tri_coef, *(o.per_triangle(mat) for _, o in more)])
            # (4, hours × n): column hour × n_tri + tri
            self.tri_coefs_flat_t = np.ascontiguousarray(self.tri_coefs.reshape(-1, 4).T)
        # point sun: per triangle (and hour state) the cosine sun · normal and the origin
        # offset ±ε towards the side a shadow ray leaves, looked up instead of recomputed at
        # every crossing (the same einsum, so the same numbers); rows hour × n_tri + tri
        suns = self.suns if more else self.sun[None, :]
        cos = np.stack([np.einsum("ij,ij->i", np.broadcast_to(sun, geo.normals.shape),
                                  geo.normals) for sun in suns])
        self.sun_cos = cos.reshape(-1)
        self.sun_side = np.where(self.sun_cos < 0, -self.eps, self.eps)
        self.sun_grazing = bool(np.any(np.abs(self.sun_cos) < 1e-12))  # plane_distance's test
        # the C kernel's table (radtree.engines.common.kernel): per triangle its normal, first
        # vertex, specular transmittance and cosine to the first state's sun, one 64-byte row
        self.tri_pack: np.ndarray | None = None
        if kernel() is not None:
            self.tri_pack = kernel_tables(geo.normals, geo.v0, self.tri_ts, self.sun_cos)

    def sensor_sun(self, points: np.ndarray, normals: np.ndarray, dirs: np.ndarray | None = None,
                   rng: Draws | np.random.Generator | None = None, state: int | None = None
                   ) -> np.ndarray:
        """Direct sun illuminance on sensors (shadow rays start exactly at the points);
        ``rng``: the roulette's draws, one stream per point (None: the exact product);
        ``state``: the index of the hour state (several states in one tracer)."""
        k = len(points)
        out = np.zeros(k)
        sun_on, dni, sun = ((self.sun_on, self.dni, self.sun) if state is None else
                            (self.dnis[state] > 0, self.dnis[state], self.suns[state]))
        if not sun_on or k == 0:
            return out
        hour = None
        if dirs is None:
            dirs = np.broadcast_to(sun, (k, 3))
            hour = 0 if state is None else int(state)
        cos = np.einsum("ij,ij->i", normals, dirs)
        need = cos > 0
        if need.any():
            draws = None if rng is None else as_draws(rng).rows(np.flatnonzero(need), *SENSOR_SUN_ROULETTE)
            out[need] = dni * cos[need] * self.shadow(points[need],
                                                      _rows(dirs, need), draws, hour=hour)
        return out

    # -- paths
    def paths(self, points: np.ndarray, normals: np.ndarray, rng: Draws,
              parallel: bool = True, *, dirs: np.ndarray | None = None,
              escapes: Callable[[np.ndarray, np.ndarray, np.ndarray], None] | None = None,
              orders: np.ndarray | None = None, hour: np.ndarray | None = None,
              segments: Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray], None]
              | None = None) -> np.ndarray:
        """Radiance (cd/m²) seen along one cosine-sampled direction from each sensor sample.

        ``rng``: the streams of these paths (:class:`~radtree.engines.common.streams.Draws`);
        every draw is taken at its place in the program — (bounce, site) — from the streams of
        the paths still alive, so a path's numbers do not depend on the others. ``dirs``: the
        first directions instead of the cosine samples about ``normals``; ``escapes(path,
        direction, throughput)`` is told of every path leaving the scene (the transfer of a
        layer, :mod:`radtree.engines.numpy.transfer`). ``orders`` (k, max_bounces): also adds
        each contribution to the column of its bounce order − 1 (the diffuse segments before it,
        as ``-ab`` counts them), so that the cumulative sum over the columns is the trace at
        ``-ab`` 1, 2, … at once (:func:`trace_bounce_ladder`). ``hour``: each path's state
        index when the tracer holds several hour states (:func:`trace_states`).
        ``segments(path, origin, direction, reach)`` is told of every ray in path order — each
        path's segment (``reach`` its length, ∞ when it escapes), then its shadow ray towards
        the sun (``reach`` ∞, blocked or not) — without changing a number
        (the tree attribution, :mod:`radtree.engines.numpy.attribution`)."""
        k = len(points)
        first = (cosine_hemisphere(np.asarray(normals, float),
                                   rng.rows(None, *FIRST_DIRECTIONS)) if dirs is None
                 else np.array(dirs, float))
        b = Batch(np.zeros(k), np.arange(k), np.array(points, float), first, np.ones(k),
                  np.ones(k, np.int64), np.zeros(k, np.int64),
                  # contiguous int64 (the C kernel's surface pass needs it)
                  None if hour is None else np.ascontiguousarray(hour, dtype=np.int64),
                  orders)
        bounce = 0
        while len(b.alive):
            bounce += 1
            h = self.hit(b, rng, bounce, parallel, escapes, segments)
            if h is None:
                break
            p, nf, cosd, coef = self.surface(b, h, rng, bounce)
            if self.sun_on:
                self.sun_event(b, p, nf, coef, rng, bounce, parallel, segments)
            if not self.scatter(b, h, p, nf, cosd, coef, rng, bounce):
                break
        return b.acc

    def paths_split(self, points: np.ndarray, normals: np.ndarray, streams: PathStreams,
                    dirs: np.ndarray | None = None, orders: np.ndarray | None = None,
                    hour: np.ndarray | None = None) -> np.ndarray:
        """:meth:`paths` of a batch, split into ``workers`` parts traced in parallel threads,
        each part's NumPy work and Embree queries on its own core. The parts take blocks of
        ``SPLIT_BLOCK`` consecutive paths in turn (part i: blocks i, i + parts, …), so every
        part gets its share of each sensor and each block a whole stratum of the sensor's
        Sobol' net (every second path alone would give one part the low and the other the high
        zenith angles). ``streams``: the batch's paths' streams; each part draws from its own
        paths' streams, so the results are those of one thread, ``paths(points, normals,
        streams, dirs=dirs)``, and the threads never wait for each other. ``dirs``: the paths'
        first directions (None: cosine samples); ``orders``, ``hour``: as :meth:`paths`."""
        k = len(points)
        parts = min(self.workers, k // self.opts.min_part_paths)
        if parts <= 1:
            return self.paths(points, normals, streams, dirs=dirs, orders=orders, hour=hour)
        block = np.arange(k) // SPLIT_BLOCK % parts
        acc = np.empty(k)
        errors: list[BaseException] = []

        def run(i: int) -> None:
            try:
                rows = (block == i).nonzero()[0]
                own = None if orders is None else orders.take(rows, axis=0)
                acc[rows] = self.paths(points.take(rows, axis=0), normals.take(rows, axis=0),
                                       streams.rows(rows), parallel=False,
                                       dirs=None if dirs is None else dirs.take(rows, axis=0),
                                       orders=own, hour=None if hour is None else hour[rows])
                if orders is not None:
                    orders[rows] = own
            except BaseException as exc:  # re-raised in the calling thread
                errors.append(exc)

        threads = [threading.Thread(target=run, args=(i,), daemon=True) for i in range(parts)]
        for th in threads:
            th.start()
        for th in threads:
            th.join()
        if errors:
            raise errors[0]
        return acc
