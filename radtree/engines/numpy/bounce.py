"""One bounce of the NumPy engine's path batch, step by step (:meth:`_Tracer.paths
<radtree.engines.numpy.engine._Tracer.paths>` runs them in a loop).

A :class:`Batch` holds the paths still traced (their origins, directions, weights, diffuse
depth and specular count, hour state) and what they have gathered. Per bounce:

1. :meth:`BounceSteps.hit` — the first surface (or turbid-crown leaf) along each ray; the
   rays that escape see the sky (or the distant ground) and leave the batch;
2. :meth:`BounceSteps.surface` — the hit point, the normal on the side the ray came from and
   the event coefficients (diffuse R, diffuse T, specular T, mirror) of each hit;
3. :meth:`BounceSteps.sun_event` — next-event estimation towards the sun;
4. :meth:`BounceSteps.scatter` — Russian roulette and the next direction of each survivor.

Every random draw is taken at its place — (bounce, site) — from the streams of the paths
still alive (:mod:`radtree.engines.common.streams`), as the loop did in one function: the
numbers are the same to the bit.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from radtree.engines.common.geometry import Geometry, Optics, glass_coefficients
from radtree.engines.common.kernel import kernel
from radtree.engines.common.raycast import RayCaster
from radtree.engines.common.sampling import cosine_rows, mirror, uniform_cone
from radtree.engines.common.streams import Draws
from radtree.engines.numpy.shadow import rows as _rows
from radtree.engines.numpy.shadow import transmittance
from radtree.light.sun import SUN_HALF_ANGLE_DEG

#: ``segments(path, origin, direction, reach)``: told of every ray in path order
Segments = Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray], None]
#: ``escapes(path, direction, throughput)``: told of every path leaving the scene
Escapes = Callable[[np.ndarray, np.ndarray, np.ndarray], None]


def _cumulative(coef: np.ndarray) -> np.ndarray:
    """Running sums (4, k) of the event coefficients (4, k) down the rows (``np.cumsum``
    along the events, in the same order)."""
    cum = np.empty_like(coef)
    cum[0] = coef[0]
    for j in range(1, len(coef)):
        np.add(cum[j - 1], coef[j], out=cum[j])
    return cum


def _event(pick: np.ndarray, cum: np.ndarray) -> np.ndarray:
    """Index (k,) of the event each ``pick`` (k, in [0, total)) falls into, from the running
    sums ``cum`` (4, k): how many running sums are ≤ the pick, at most 3."""
    ev = np.zeros(len(pick), np.int64)
    for row in cum:
        ev += pick >= row
    return np.minimum(ev, 3, out=ev)


@dataclass(slots=True)
class Batch:
    """The paths of one batch still traced: ``alive`` their indices into ``acc`` (radiance
    gathered per path, cd/m²), origins ``o`` and directions ``d`` (k, 3), weights ``beta``,
    diffuse ``depth`` (1 = the sensor's sample) and specular events ``nspec``, hour state
    index ``hour`` (None: one state) and the bounce-order tallies ``orders`` (or None)."""

    acc: np.ndarray
    alive: np.ndarray
    o: np.ndarray
    d: np.ndarray
    beta: np.ndarray
    depth: np.ndarray
    nspec: np.ndarray
    hour: np.ndarray | None
    orders: np.ndarray | None

    def gather(self, rows: np.ndarray, got: np.ndarray, depth: np.ndarray) -> None:
        """Add ``got`` to the paths ``rows`` of the batch (indices into ``acc``) and to the
        column of their bounce order (``depth`` − 1)."""
        self.acc[rows] += got
        if self.orders is not None:
            self.orders[rows, depth - 1] += got


@dataclass(slots=True)
class Hit:
    """What one bounce's rays met: triangle ``tri`` (a placeholder row for a turbid-crown
    leaf), distance ``t``, the turbid crown's leaf index ``met`` (−1: a surface; None: no
    turbid crowns)."""

    tri: np.ndarray
    t: np.ndarray
    met: np.ndarray | None


class BounceSteps:
    """The steps of a bounce, mixed into the tracer (:class:`_Tracer
    <radtree.engines.numpy.engine._Tracer>`), which sets these attributes."""

    caster: RayCaster
    media: Any
    opts: Any
    env: Any
    envs: list[Any]
    geo: Geometry
    opt: Optics
    eps: float
    tri_ts: np.ndarray
    sun_cos: np.ndarray
    sun_side: np.ndarray
    sun_grazing: bool
    n_tri: int
    sun: np.ndarray
    suns: np.ndarray
    dni: float
    dnis: np.ndarray
    sun_on: bool
    max_bounces: int
    tri_pack: np.ndarray | None
    tri_coef_t: np.ndarray
    tri_coefs_flat_t: np.ndarray
    tri_glass: np.ndarray
    tri_glass_tn: np.ndarray
    glass_any: bool

    def sky(self, d: np.ndarray, hour: np.ndarray | None) -> np.ndarray:
        """Luminance seen along escaping directions ``d`` (each path's own hour state)."""
        if hour is None:
            return self.env(d)
        out = np.empty(len(d))
        for h in np.unique(hour):
            m = hour == h
            out[m] = self.envs[h](d[m])
        return out

    def sun_directions(self, k: int, rng: Draws | np.random.Generator) -> np.ndarray:
        if self.opts.sun_disc:
            return uniform_cone(self.sun, math.radians(SUN_HALF_ANGLE_DEG), k, rng)
        return np.broadcast_to(self.sun, (k, 3))

    def shadow(self, origins: np.ndarray, dirs: np.ndarray,
               rng: Draws | np.random.Generator | None = None, parallel: bool = True,
               hour: np.ndarray | int | None = None) -> np.ndarray:
        """Transmittance towards the sun: 1 if free, product of specular passes, else 0.

        With ``rng``, faint shadow rays are continued by Russian roulette (unbiased); without,
        the product is exact (the sensors' own direct sun); ``rng``: one stream per shadow
        ray (:class:`~radtree.engines.common.streams.Draws`, the layer crossed appended to its
        place) or a plain ``Generator``; ``parallel``:
        whether the ray caster may split its queries over threads (not inside a part thread);
        ``hour``: the hour state(s) whose point sun ``dirs`` are (per-triangle tables of the
        cosines and offsets), None for other directions (a sampled sun disc).
        """
        vis = transmittance(self, origins, dirs, rng, parallel, hour)
        if self.media is not None and len(vis):   # the turbid crowns' mean transmittance
            on = (vis > 0).nonzero()[0]
            vis[on] *= self.media.transmittance(origins[on], _rows(dirs, on), parallel)
        return vis

    # -- the steps of one bounce
    def hit(self, b: Batch, rng: Draws, bounce: int, parallel: bool,
            escapes: Escapes | None, segments: Segments | None) -> Hit | None:
        """Step 1: the first hits; escaping paths gather the sky and leave ``b`` (None: no
        path left)."""
        tri, t = self.caster.first_hit(b.o, b.d, parallel)
        met = None
        if self.media is not None:   # a leaf of a turbid crown before the surface?
            met, t = self.media.collide(b.o, b.d, t, rng.rows(b.alive, bounce, 5), parallel)
            tri = np.where(met >= 0, max(self.n_tri - 1, 0), tri)   # a placeholder row
        miss = tri < 0
        if segments is not None:
            segments(b.alive, b.o, b.d, np.where(miss, np.inf, t))
        if miss.any():
            mi = miss.nonzero()[0]
            am, dm, bm = b.alive[mi], b.d.take(mi, axis=0), b.beta[mi]
            if escapes is not None:
                escapes(am, dm, bm)
            b.gather(am, bm * self.sky(dm, None if b.hour is None else b.hour[mi]),
                     b.depth[mi])
            hi = (~miss).nonzero()[0]
            b.alive, b.o, b.d, b.beta, b.depth, b.nspec = (
                b.alive[hi], b.o.take(hi, axis=0), b.d.take(hi, axis=0), b.beta[hi],
                b.depth[hi], b.nspec[hi])
            tri, t = tri[hi], t[hi]
            if met is not None:
                met = met[hi]
            if b.hour is not None:
                b.hour = b.hour[hi]
            if len(b.alive) == 0:
                return None
        return Hit(tri, t, met)

    def surface(self, b: Batch, h: Hit, rng: Draws, bounce: int
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Step 2: hit points ``p``, normals ``nf`` on the side the rays came from, cosines
        ``cosd`` (ray · geometric normal) and event coefficients ``coef`` (4, k)."""
        tri, t, hour = h.tri, h.t, b.hour
        k_mod = kernel() if self.tri_pack is not None else None
        if k_mod is not None and tri.dtype == np.int64:
            # the same numbers in one pass (radtree.engines.common.kernel)
            n_a = len(b.alive)
            p, nf, cosd, coef = (np.empty((n_a, 3)), np.empty((n_a, 3)), np.empty(n_a),
                                 np.empty((4, n_a)))
            k_mod.surface(tri, t, b.o, b.d, self.tri_pack, self.tri_coef_t if hour is None
                          else self.tri_coefs_flat_t, None if hour is None else
                          np.asarray(hour, np.int64), self.n_tri, p, nf, cosd, coef)
        else:
            p = t[:, None] * b.d
            p += b.o
            ng = self.geo.normals.take(tri, axis=0)
            cosd = np.einsum("ij,ij->i", b.d, ng)
            front = cosd < 0
            nf = np.where(front[:, None], ng, -ng)  # normal on the side the ray came from
            # diffuse R, diffuse T, specular T, mirror (a copy, (4, k): one row per event)
            coef = (self.tri_coef_t.take(tri, axis=1) if hour is None else
                    self.tri_coefs_flat_t.take(hour * self.n_tri + tri, axis=1))
        met = h.met
        if met is not None and self.media is not None and (met >= 0).any():
            mi = (met >= 0).nonzero()[0]   # leaf events: drawn normal, leaf optics
            nf[mi], coef[:, mi] = self.media.leaf_events(
                met[mi], b.d.take(mi, axis=0), rng.rows(b.alive.take(mi), bounce, 6))
            cosd[mi] = -1.0
        return p, nf, cosd, coef

    def sun_event(self, b: Batch, p: np.ndarray, nf: np.ndarray, coef: np.ndarray,
                  rng: Draws, bounce: int, parallel: bool, segments: Segments | None) -> None:
        """Step 3: next-event estimation towards the sun from every hit point ``p``."""
        hour, eps = b.hour, self.eps
        rd, td = coef[0], coef[1]
        sd = (self.sun_directions(len(b.alive), rng.rows(b.alive, bounce, 0)) if hour is None
              else self.suns.take(hour, axis=0))
        k_mod = kernel() if self.tri_pack is not None else None
        if k_mod is not None:  # the same numbers in one pass
            n_a = len(b.alive)
            f, ni, so = np.empty(n_a), np.empty(n_a, np.int64), np.empty((n_a, 3))
            m = k_mod.nee(nf, sd, rd, td, self.dnis if hour is not None else None,
                          None if hour is None else np.asarray(hour, np.int64), eps,
                          p, f, ni, so)
            ni, so = ni[:m], so[:m]
        else:
            cs = np.einsum("ij,ij->i", nf, sd)
            f = np.where(cs > 0, rd * cs, -td * cs) / math.pi
            if hour is not None:
                f *= self.dnis[hour]   # 0 where that hour's sun is off
            ni = (f > 0).nonzero()[0]
            if len(ni):
                so = nf.take(ni, axis=0)
                so *= (eps * np.sign(cs[ni]))[:, None]
                so += p.take(ni, axis=0)
        if len(ni):
            vis = self.shadow(so, _rows(sd, ni), rng.rows(b.alive.take(ni), bounce, 1),
                              parallel,
                              None if self.opts.sun_disc else
                              0 if hour is None else hour[ni])
            if segments is not None:
                segments(b.alive.take(ni), so, _rows(sd, ni), np.full(len(ni), np.inf))
            got = b.beta[ni] * (self.dni if hour is None else 1.0) * f[ni] * vis
            b.gather(b.alive[ni], got, b.depth[ni])

    def scatter(self, b: Batch, h: Hit, p: np.ndarray, nf: np.ndarray, cosd: np.ndarray,
                coef: np.ndarray, rng: Draws, bounce: int) -> bool:
        """Step 4: the event of each path (diffuse reflect, diffuse transmit, specular
        transmit, mirror), Russian roulette below ``roulette_weight``, the survivors' next
        origins and directions in ``b``; False when no path survives."""
        tri, met = h.tri, h.met
        if self.glass_any:
            glass = self.tri_glass[tri] if met is None else self.tri_glass[tri] & (met < 0)
            if glass.any():
                tg, rg = glass_coefficients(cosd[glass], self.tri_glass_tn[tri][glass])
                coef[2, glass] = tg
                coef[3, glass] = rg
        coef[:2] *= b.depth < self.max_bounces
        coef[2:] *= b.nspec < self.opts.max_specular
        cum = _cumulative(coef)   # the last row: the total, summed in order
        total = cum[3]
        thr = self.opts.roulette_weight
        beta = b.beta * total
        u = rng.rows(b.alive, bounce, 2).random(len(b.alive))
        low = beta < thr
        survive = (total > 0) & (~low | (u * thr < beta))
        beta = np.where(low, thr, beta)
        pick = rng.rows(b.alive, bounce, 3).random(len(b.alive)) * total
        ev = _event(pick, cum)
        alive, d, depth, nspec = b.alive, b.d, b.depth, b.nspec
        si = survive.nonzero()[0]
        if len(si) < len(alive):
            alive, p, d, nf, beta, depth, nspec, ev = (
                alive[si], p.take(si, axis=0), d.take(si, axis=0), nf.take(si, axis=0),
                beta[si], depth[si], nspec[si], ev[si])
            if b.hour is not None:
                b.hour = b.hour[si]
        b.alive, b.beta = alive, beta
        if len(alive) == 0:
            return False
        new_d = d.copy()
        side = np.ones(len(alive))  # +1: leave on the incoming side, -1: cross
        diff_r, diff_t = ev == 0, ev == 1
        diffuse = diff_r | diff_t
        if diffuse.any():
            di = diffuse.nonzero()[0]
            axis = np.empty((3, len(di)))  # ±n_f, one row per axis
            np.multiply(nf.take(di, axis=0).T, np.where(diff_r[di], 1.0, -1.0), out=axis)
            new_d[di] = cosine_rows(axis, rng.rows(alive.take(di), bounce, 4)).T
        spec_t, mir = ev == 2, ev == 3
        if mir.any():
            new_d[mir] = mirror(d[mir], nf[mir])
        side[diff_t | spec_t] = -1.0
        nf *= (self.eps * side)[:, None]
        nf += p
        b.o, b.d = nf, new_d
        b.depth = depth + diffuse
        b.nspec = nspec + (spec_t | mir)
        return True
