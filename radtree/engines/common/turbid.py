"""Free paths through turbid-medium crowns (:mod:`radtree.media`) for the NumPy engine and
the forward light tracer (:mod:`radtree.engines.forward.tracer`: the same collisions and leaf
events from its generator, the absorbed flux booked to the leaf material).

Which crowns a ray crosses: every crown's bounding box (12 triangles, 1–5 cm larger than the
spheroid, the margin differing from crown to crown) is a proxy mesh in its own ray caster
(Embree when available; :mod:`radtree.engines.common.boxes`); the faces a ray crosses name
the candidate crowns (:meth:`MediumTracer.crossings`: repeated first-hit queries until the ray
leaves the last box or passes its end), then the exact spheroid interval, cut by
the crown's half-spaces, is solved per (ray, crown) pair. Memory: O(crowns + rays in a batch),
whatever the leaf count.

Collisions (:meth:`MediumTracer.collide`). In crown c the leaves that change a ray's direction
are met at the rate σ_c = u_c · G·Ω_c(|Ω_z|) · (1 − T_s): leaves passing the ray undeviated
(the leaf's specular share T_s) thin the Poisson process of leaves met and leave the ray
unchanged, so they are folded into the rate (the same law as explicit slats, whose T_s
crossings go straight on). Crowns overlap freely: the superposed media's first collision is the
minimum of each crown's own exponential free path (τ_c = −ln(1 − ξ_c), t = t_in + τ_c/σ_c),
one uniform per (path, crown) from the path's stream. A collision before the ray's first
surface becomes a leaf event at that point: a leaf normal drawn from the leaf angle
distribution weighted by |n·Ω| (rejection: inclination by the kind's inverse CDF, azimuth
uniform, accepted with probability |n·Ω|), and the bi-Lambertian leaf's events, diffuse
reflection R/(1 − T_s) and diffuse transmission T_d/(1 − T_s) about that normal
(:meth:`MediumTracer.leaf_events`), through the engine's own event machinery.

Shadow rays (:meth:`MediumTracer.transmittance`): the expected transmittance of the media
along the whole ray, exp(−Σ_c σ_c·L_c) (a point estimate, no variance added) — the mean of the
slats' T_s^N over Poisson N.
"""

from __future__ import annotations

import math

import numpy as np

from radtree.engines.common.boxes import BoxProxies, clip_to_planes
from radtree.engines.common.streams import Draws, PathStreams
from radtree.errors import EngineError
from radtree.media import LeafKind, TurbidCrowns
from radtree.optics import Material, Trans

COLLIDE = 5        # stream site of the free-path draws (the loop's own sites are 0–4)
NORMALS = 6        # stream site of the leaf-normal draws
PAIR_SHIFT = 40    # (path, crown) streams: path number + (crown + 1) · 2⁴⁰
MAX_TRIES = 64     # rejection rounds for the leaf normals (then the last draw is kept)


def pair_uniforms(draws: Draws, rows: np.ndarray, crown: np.ndarray) -> np.ndarray:
    """One uniform per (path at ``rows`` of ``draws``, crown) pair: independent across the
    crowns of one path (the path's stream shifted by the crown, :data:`PAIR_SHIFT`)."""
    if isinstance(draws, PathStreams):
        ids = draws.ids.take(rows) + ((crown.astype(np.uint64) + np.uint64(1))
                                      << np.uint64(PAIR_SHIFT))
        return PathStreams(draws.key, ids, draws.tag).random(len(ids))
    return _plain(draws, len(rows))


def _plain(draws: Draws, n: int) -> np.ndarray:
    """``n`` uniforms from a plain generator's :class:`Draws` (one stream in a fixed order)."""
    rng = getattr(draws, "rng", None)
    if rng is None:
        raise EngineError("turbid crowns need per-path streams or a NumPy Generator")
    return np.asarray(rng.random(n))


def leaf_optics(kinds: list[LeafKind], *, materials: dict[str, Material]
                ) -> tuple[np.ndarray, np.ndarray]:
    """Per leaf kind: the share of leaves met that deflect, 1 − T_s, and the deflecting
    events' probabilities (kinds, 2): diffuse reflection R/(1 − T_s), diffuse transmission
    T_d/(1 − T_s); EngineError for a leaf material that is not ``trans`` or passes all."""
    r, td, ts = np.zeros(len(kinds)), np.zeros(len(kinds)), np.zeros(len(kinds))
    for k, kind in enumerate(kinds):
        m = materials.get(kind.material)
        if not isinstance(m, Trans):
            raise EngineError(f"turbid crowns: leaf material '{kind.material}' must be a "
                              f"trans material, got {type(m).__name__}")
        r[k], td[k], ts[k] = m.reflectance, m.diffuse_transmittance, m.specular_transmittance
    if np.any(ts >= 1.0):
        raise EngineError("turbid crowns: leaves with specular transmittance 1 block nothing")
    pass_ = 1.0 - ts
    return pass_, np.stack([r / pass_, td / pass_], 1)


def leaf_normals(kind: np.ndarray, *, kinds: list[LeafKind], d: np.ndarray, draws: Draws
                 ) -> np.ndarray:
    """Normals (k, 3) of the leaves met by rays along ``d``, on the side the rays came from:
    drawn from each ray's leaf kind (``kind`` index into ``kinds``) weighted by |n·Ω|
    (rejection: inclination by the kind's inverse CDF, azimuth uniform, accepted with
    probability |n·Ω|)."""
    k = len(kind)
    normal = np.zeros((k, 3))
    todo = np.arange(k)
    for attempt in range(MAX_TRIES):
        sub = draws.rows(todo, attempt)
        u1, u2, u3 = (sub.random(len(todo)) for _ in range(3))
        theta = np.empty(len(todo))
        kt = kind[todo]
        for j, lk in enumerate(kinds):
            m = kt == j
            if m.any():
                theta[m] = np.interp(u1[m], lk.incl_cdf, lk.incl_edges)
        phi = 2.0 * math.pi * u2
        st = np.sin(theta)
        n = np.stack([st * np.cos(phi), st * np.sin(phi), np.cos(theta)], 1)
        normal[todo] = n
        ok = u3 < np.abs(np.einsum("ij,ij->i", n, d[todo]))
        todo = todo[~ok]
        if len(todo) == 0:
            break
    flip = np.einsum("ij,ij->i", normal, d) > 0
    normal[flip] *= -1.0
    return normal


def first_hits(ray: np.ndarray, *, which: np.ndarray, tc: np.ndarray, met: np.ndarray,
               dist: np.ndarray) -> None:
    """Superposed media: each ray's nearest collision among its (``ray``, ``which``, distance
    ``tc``) candidates written into ``met`` / ``dist`` (the minimum of independent free
    paths is the first collision in their sum)."""
    order = np.lexsort((tc, ray))
    ray, which, tc = ray[order], which[order], tc[order]
    first = np.ones(len(ray), bool)
    first[1:] = ray[1:] != ray[:-1]
    met[ray[first]] = which[first]
    dist[ray[first]] = tc[first]


class MediumTracer:
    """The media of one scene, ready for the engine's queries (see the module text)."""

    def __init__(self, media: TurbidCrowns, materials: dict[str, Material],
                 backend: str = "auto", workers: int = 1):
        self.media = media
        self.n = len(media)
        half = np.stack([media.a, media.a, media.b], 1)
        self.boxes = BoxProxies(media.centres - half, hi=media.centres + half, backend=backend,
                                workers=workers)
        self.axes = half
        self.pass_, self.events = leaf_optics(media.kinds, materials=materials)

    def corners(self) -> np.ndarray:
        """(8·n, 3) corners of the crowns' proxy boxes (a forward source must enclose them)."""
        return self.boxes.corners

    def material_index(self, crown: np.ndarray, names: list[str]) -> np.ndarray:
        """Index in ``names`` of the leaf material of each crown in ``crown``."""
        table = np.array([names.index(k.material) for k in self.media.kinds], np.int64)
        return table[self.media.kind[crown]]

    # -- which crowns a ray crosses
    def crossings(self, o: np.ndarray, d: np.ndarray, tmax: np.ndarray, parallel: bool = True
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(ray, crown, t_in, t_out) of every crown whose envelope the rays ``o + t d``
        (0 ≤ t ≤ ``tmax``) cross, t in metres along the unit ``d``."""
        ray, crown = self.boxes.candidates(o, d, tmax, parallel)
        if len(ray) == 0:
            return (np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0), np.zeros(0))
        t0, t1 = self._interval(np.asarray(o, float)[ray], np.asarray(d, float)[ray], crown)
        t1 = np.minimum(t1, tmax[ray])
        ok = t1 > t0
        return ray[ok], crown[ok], t0[ok], t1[ok]

    def _interval(self, o: np.ndarray, d: np.ndarray, crown: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray]:
        """[t_in, t_out] of the rays in their crowns' clipped spheroids (t_in ≥ 0; empty:
        t_out ≤ t_in)."""
        ax = self.axes[crown]
        q = (o - self.media.centres[crown]) / ax
        e = d / ax
        a = np.einsum("ij,ij->i", e, e)
        b = np.einsum("ij,ij->i", q, e)
        c = np.einsum("ij,ij->i", q, q) - 1.0
        disc = b * b - a * c
        root = np.sqrt(np.maximum(disc, 0.0))
        t0 = np.maximum((-b - root) / a, 0.0)
        t1 = np.where(disc > 0, (-b + root) / a, -1.0)
        return clip_to_planes(o, d=d, planes=self.media.planes[crown], t0=t0, t1=t1)

    def _sigma(self, d: np.ndarray, crown: np.ndarray) -> np.ndarray:
        """Deflecting collisions per metre, σ_c(1 − T_s), for the pairs' directions ``d``."""
        kind = self.media.kind[crown]
        g = np.empty(len(crown))
        for k, lk in enumerate(self.media.kinds):
            m = kind == k
            if m.any():
                g[m] = lk.g(d[m, 2])
        return self.media.lad[crown] * g * self.pass_[kind]

    # -- the engine's hooks
    def collide(self, o: np.ndarray, d: np.ndarray, t: np.ndarray, draws: Draws,
                parallel: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """(crown met or −1, distance) per ray: the first deflecting leaf before the surface
        at ``t`` (inf: none); ``draws``: the rays' streams at this place."""
        ray, crown, t0, t1 = self.crossings(o, d, t, parallel)
        met = np.full(len(o), -1, np.int64)
        dist = np.array(t, float)
        if len(ray) == 0:
            return met, dist
        sigma = self._sigma(np.asarray(d, float)[ray], crown)
        xi = pair_uniforms(draws, ray, crown)
        with np.errstate(divide="ignore"):
            tc = t0 - np.log1p(-xi) / sigma
        inside = (sigma > 0) & (tc < t1)
        ray, crown, tc = ray[inside], crown[inside], tc[inside]
        if len(ray) == 0:
            return met, dist
        first_hits(ray, which=crown, tc=tc, met=met, dist=dist)
        return met, dist

    def leaf_events(self, crown: np.ndarray, d: np.ndarray, draws: Draws
                    ) -> tuple[np.ndarray, np.ndarray]:
        """For rays along ``d`` that met a leaf of ``crown``: the leaf normal on the side the
        ray came from (k, 3) and the event coefficients (4, k): diffuse reflect, diffuse
        transmit, specular transmit (0: folded into σ), mirror (0)."""
        k = len(crown)
        kind = self.media.kind[crown]
        normal = leaf_normals(kind, kinds=self.media.kinds, d=d, draws=draws)
        coef = np.zeros((4, k))
        coef[:2] = self.events[kind].T
        return normal, coef

    def transmittance(self, o: np.ndarray, d: np.ndarray, parallel: bool = True) -> np.ndarray:
        """exp(−Σ σ_c L_c) along the whole rays ``o + t d`` (t ≥ 0)."""
        d = np.broadcast_to(np.asarray(d, float), np.shape(o))
        ray, crown, t0, t1 = self.crossings(o, np.ascontiguousarray(d),
                                            np.full(len(o), np.inf), parallel)
        tau = np.zeros(len(o))
        if len(ray):
            np.add.at(tau, ray, self._sigma(d[ray], crown) * (t1 - t0))
        return np.exp(-tau)
