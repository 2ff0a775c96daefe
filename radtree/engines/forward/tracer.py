"""Forward light tracing: photons from the sun and sky through the scene, tallied on patches.

Same scene, materials and ray caster as the NumPy engine (:mod:`radtree.engines.numpy`): all
surfaces two-sided; ``Plastic`` reflects ρ(1 − spec) Lambertian plus ``spec`` as a mirror (the
ground material takes the hour's reflectance); ``Trans`` reflects R and transmits T_d
Lambertian and T_s undeviated; ``Glass`` transmits T(θ) and mirrors R(θ) (Radiance's formulas).
What a surface does not reflect or transmit is absorbed there.

At every hit a photon of flux w either

* **splits** (``splitting``): one child per event (diffuse reflection, diffuse transmission,
  specular transmission, mirror reflection) carrying w × the event's coefficient; children
  below ``threshold`` × the photon's launched flux are killed (TracePro's behaviour: the
  killed flux is lost, a bias that shrinks with the threshold), or
* takes **one event** chosen ∝ its coefficient and keeps w × (sum of coefficients); below the
  threshold it plays Russian roulette (survives with probability w / (threshold · w₀), then
  carries threshold · w₀): unbiased.

**Splitting near the detectors** (:class:`Splitting`): a diffuse event within ``radius`` of
the target point splits its child into ``factor`` children, each drawing its own direction and
carrying 1/``factor`` of the flux (and of the threshold's reference flux, so roulette does not
undo the split), at most ``levels`` times per lineage: more photons where the detectors can see
them, the expected tally unchanged.

**Roulette after a guided event.** A guided diffuse event (:mod:`.guide`) multiplies the
photon's flux by the Lambertian density over the mixture's, far below 1 for a direction drawn
in the cone towards the detectors (≈ 0.005 from 10 m for a 0.6 m sphere); the photon's
reference flux — the roulette's floor is ``threshold`` × it — is multiplied by the same factor.
Measured on the reference street's free crowns (scenario F at 12:30, one round, every photon's
contribution recorded per launch ring): with the launched flux as the reference, a photon
aimed from the sunlit street at the façade lost 99.5 % of its flux to the guide, fell below the
floor at its first slat and survived the roulette with ~1 % chance carrying the whole floor:
the ten largest of a ring's 146 688 photons made 40 % of its light, kurtosis 18 000, and the
façade mean's error after 15 M photons was 1.8–3 % (32 seeds: z s.d. 1.28). With the
reference following the guide: the ten largest made 3 %, the error of one round fell from 79
to 14 lx (variance ÷ 32). Roulette and splitting then work on the photon's expected
contribution, not on a weight the guide has already rescaled — the condition for them not to
undo importance-sampled directions (Vorba & Křivánek 2016, "Adjoint-driven Russian roulette
and splitting in light transport simulation", ACM TOG 35(4), doi 10.1145/2897824.2925912: a
weight window on weight × adjoint). Any reference keeps the roulette unbiased (a survivor
carries the floor with probability flux / floor); only the variance changes.

Diffuse events per photon are capped at ``max_bounces`` (``-ab``: the diffuse part of a hit
beyond the cap is dropped, like a backward path that may not bounce again) and specular events
at ``max_specular``. Every lumen is accounted for in a :class:`Ledger`: launched = escaped +
absorbed + capped + killed − promoted (roulette survivors' gain), exactly.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from radtree.engines.common.geometry import Geometry, Optics, glass_coefficients
from radtree.engines.common.sampling import cosine_hemisphere, mirror
from radtree.engines.common.streams import GeneratorDraws
from radtree.engines.forward.detectors import PatchDetectors
from radtree.engines.forward.guide import Guide
from radtree.engines.forward.sources import Launch
from radtree.engines.forward.window import WeightWindow


@dataclass
class Ledger:
    """Where the launched flux went (lm). ``absorbed`` per material (the geometry's material
    order); ``escaped_up``/``escaped_down``: photons leaving the scene upwards / downwards."""

    materials: list[str]
    launched: float = 0.0
    escaped_up: float = 0.0
    escaped_down: float = 0.0
    absorbed: np.ndarray = field(default_factory=lambda: np.zeros(0))
    capped: float = 0.0
    killed: float = 0.0
    promoted: float = 0.0

    def __post_init__(self) -> None:
        if len(self.absorbed) != len(self.materials):
            self.absorbed = np.zeros(len(self.materials))

    @property
    def escaped(self) -> float:
        return self.escaped_up + self.escaped_down

    def absorbed_by(self, material: str) -> float:
        return float(self.absorbed[self.materials.index(material)]) \
            if material in self.materials else 0.0

    @property
    def balance(self) -> float:
        """launched − (escaped + absorbed + capped + killed − promoted): 0 up to rounding."""
        return self.launched - (self.escaped + float(self.absorbed.sum()) + self.capped
                                + self.killed - self.promoted)


@dataclass(frozen=True)
class Splitting:
    """Split diffuse children within ``radius`` (m) of ``target`` into ``factor`` (≥ 2), at
    most ``levels`` times per photon lineage."""

    target: np.ndarray
    radius: float
    factor: int
    levels: int = 2


@dataclass
class Photons:
    """A set of photons in flight (struct of arrays)."""

    o: np.ndarray
    d: np.ndarray
    w: np.ndarray        # flux (lm)
    w0: np.ndarray       # launched flux (lm), the threshold's reference
    ndiff: np.ndarray    # diffuse events so far
    nspec: np.ndarray    # specular events so far
    batch: np.ndarray    # batch of the photon (standard errors)
    nsplit: np.ndarray   # splits in its lineage so far
    direct: np.ndarray   # still the sun's direct beam (counted at the points: direct.py)

    def __len__(self) -> int:
        return len(self.w)

    def take(self, m: np.ndarray | slice) -> Photons:
        return Photons(self.o[m], self.d[m], self.w[m], self.w0[m], self.ndiff[m],
                       self.nspec[m], self.batch[m], self.nsplit[m], self.direct[m])

    @staticmethod
    def join(parts: list[Photons]) -> Photons:
        return Photons(*(np.concatenate([getattr(p, f) for p in parts])
                         for f in ("o", "d", "w", "w0", "ndiff", "nspec", "batch",
                                   "nsplit", "direct")))

    @staticmethod
    def start(launch: Launch, batch: np.ndarray, direct: bool = False) -> Photons:
        """Photons of ``launch``; ``direct``: the sun's beam, not tallied on the detectors
        until scattered (its direct light is computed at the sensor points)."""
        k = len(launch.flux)
        z = np.zeros(k, np.int64)
        return Photons(launch.origins, launch.dirs, launch.flux.copy(), launch.flux.copy(),
                       z, z.copy(), batch, z.copy(), np.full(k, bool(direct)))


class ForwardTracer:
    """Transport of photon sets through one scene's geometry with one hour's optics."""

    def __init__(self, geo: Geometry, optics: Optics, detectors: PatchDetectors, batches: int,
                 *, threshold: float, splitting: bool, max_bounces: int, max_specular: int,
                 chunk: int, rng: np.random.Generator, splitting_near: Splitting | None = None,
                 guide: Guide | None = None, escape_axes: np.ndarray | None = None,
                 guided_roulette: bool = True):
        self.geo, self.opt, self.det = geo, optics, detectors
        self.near, self.guide = splitting_near, guide
        self.threshold, self.splitting = float(threshold), bool(splitting)
        self.max_bounces, self.max_specular = int(max_bounces), int(max_specular)
        self.chunk = int(chunk)
        self.rng = rng
        self.eps = max(1e-5, 2e-6 * geo.size)
        self.tally = np.zeros((batches, detectors.count))
        self.ledger = Ledger(list(geo.material_names))
        self.segments = 0
        #: patch crossings tallied and their flux (lm): the weight window's level (window.py)
        self.crossings = 0
        self.crossed_flux = 0.0
        #: the weight window (None: none), set by the run after its first round
        self.window: WeightWindow | None = None
        self.window_splits = 0   # copies the window added
        #: a guided diffuse event scales the photon's reference flux (the roulette's) by the
        #: same factor as its flux (module text, *Roulette after a guided event*)
        self.guided_reference = bool(guided_roulette)
        #: with ``escape_axes`` (batches, 3) unit vectors: per batch, the flux escaping the scene
        #: along its axis (d · axis > 0, lm), and the part still the direct beam
        self.axes = escape_axes
        self.ahead = np.zeros(0 if escape_axes is None else len(escape_axes))
        self.ahead_direct = np.zeros_like(self.ahead)

    def run(self, photons: Photons) -> None:
        """Trace ``photons`` (and every child) until none is left."""
        self.ledger.launched += float(photons.w.sum())
        stack = [photons]
        while stack:
            ph = stack.pop()
            if len(ph) > self.chunk:
                stack.append(ph.take(slice(self.chunk, None)))
                ph = ph.take(slice(0, self.chunk))
            children = self.step(ph)
            if len(children):
                stack.append(children)

    def step(self, ph: Photons) -> Photons:
        """One segment per photon: tally detectors, absorb, scatter; the children. The
        generator's draws come in the loop's order: the turbid crowns' collisions, their leaf
        events, the event picks, the roulette, the new directions."""
        ph, tri, t, met = self._advance(ph)
        if len(ph) == 0:
            return ph
        p, nf, _, coef, mat = self._surface(ph, tri, t, met)
        self._absorb(ph, coef, mat)
        src, ev, cw = self._choose(ph, coef)
        if len(src) == 0:
            return ph.take(np.zeros(0, np.int64))
        return self._children(ph, p, nf, src, ev, cw)

    def _advance(self, ph: Photons
                 ) -> tuple[Photons, np.ndarray, np.ndarray, np.ndarray | None]:
        """The photons' segments to their first hits (or a turbid crown's leaf), tallied on the
        detectors (not the direct beam's); photons leaving the scene are booked and dropped.
        The photons still in the scene, their triangles, distances and leaf indices."""
        geo, led = self.geo, self.ledger
        tri, t = geo.caster.first_hit(ph.o, ph.d)
        met = None
        if geo.media is not None:   # a leaf of a turbid crown first? (engines.common.turbid)
            met, t = geo.media.collide(ph.o, ph.d, t, GeneratorDraws(self.rng))
            tri = np.where(met >= 0, 0, tri)   # a placeholder row, replaced below
        self.segments += len(ph)
        if ph.direct.any():
            seen = ~ph.direct
            n, f = self.det.tally(ph.o[seen], ph.d[seen], t[seen], ph.w[seen], ph.batch[seen],
                                  self.tally)
        else:
            n, f = self.det.tally(ph.o, ph.d, t, ph.w, ph.batch, self.tally)
        self.crossings += n
        self.crossed_flux += f
        miss = tri < 0
        if miss.any() and self.axes is not None:
            gone = ph.take(miss)
            ahead = np.einsum("ij,ij->i", gone.d, self.axes[gone.batch]) > 0
            n = len(self.ahead)
            self.ahead += np.bincount(gone.batch[ahead], gone.w[ahead], minlength=n)
            lit = ahead & gone.direct
            self.ahead_direct += np.bincount(gone.batch[lit], gone.w[lit], minlength=n)
        if miss.any():
            up = ph.d[miss, 2] > 0
            led.escaped_up += float(ph.w[miss][up].sum())
            led.escaped_down += float(ph.w[miss][~up].sum())
            keep = ~miss
            ph, tri, t = ph.take(keep), tri[keep], t[keep]
            met = None if met is None else met[keep]
        return ph, tri, t, met

    def _surface(self, ph: Photons, tri: np.ndarray, t: np.ndarray, met: np.ndarray | None
                 ) -> tuple[np.ndarray, ...]:
        """Hit points, normals on the incoming side, cosines ray · geometric normal, event
        coefficients (k, 4: diffuse R, diffuse T, specular T, mirror; leaf events and glass
        filled in) and material indices of the hits."""
        geo, opt = self.geo, self.opt
        p = ph.o + t[:, None] * ph.d
        ng = geo.normals[tri]
        cosd = np.einsum("ij,ij->i", ph.d, ng)
        nf = np.where((cosd < 0)[:, None], ng, -ng)  # normal on the incoming side
        mat = geo.tri_material[tri]
        coef = np.stack([opt.rd[mat], opt.td[mat], opt.ts[mat], opt.rm[mat]], axis=1)
        if met is not None and geo.media is not None and (met >= 0).any():   # leaf events
            mi = (met >= 0).nonzero()[0]
            nf[mi], leaf = geo.media.leaf_events(met[mi], ph.d[mi], GeneratorDraws(self.rng))
            coef[mi] = leaf.T
            mat[mi] = geo.media.material_index(met[mi], geo.material_names)
        glass = np.isfinite(opt.glass_tn[mat])
        if glass.any():
            tg, rg = glass_coefficients(cosd[glass], opt.glass_tn[mat][glass])
            coef[glass, 2], coef[glass, 3] = tg, rg
        return p, nf, cosd, coef, mat

    def _absorb(self, ph: Photons, coef: np.ndarray, mat: np.ndarray) -> None:
        """Book the flux absorbed per material and the flux of events beyond the bounce
        caps (those events' coefficients set to 0)."""
        led, w = self.ledger, ph.w
        led.absorbed += np.bincount(mat, w * (1.0 - coef.sum(axis=1)),
                                    minlength=len(led.materials))
        no_diff = ph.ndiff >= self.max_bounces
        no_spec = ph.nspec >= self.max_specular
        led.capped += float((w[no_diff] * coef[no_diff, :2].sum(axis=1)).sum()
                            + (w[no_spec] * coef[no_spec, 2:].sum(axis=1)).sum())
        coef[no_diff, :2] = 0.0
        coef[no_spec, 2:] = 0.0

    def _choose(self, ph: Photons, coef: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The events that go on (source photon, event, flux): every event above the flux
        threshold (ray splitting), or one event per photon picked ∝ its coefficient with
        Russian roulette below the threshold."""
        led, w = self.ledger, ph.w
        floor = self.threshold * ph.w0
        if self.splitting:
            ev = np.repeat(np.arange(4)[None, :], len(ph), axis=0).ravel()
            src = np.repeat(np.arange(len(ph)), 4)
            cw = (w[:, None] * coef).ravel()
            live = cw > 0
            ev, src, cw = ev[live], src[live], cw[live]
            dead = cw < floor[src]
            led.killed += float(cw[dead].sum())
            return src[~dead], ev[~dead], cw[~dead]
        total = coef.sum(axis=1)
        cw = w * total
        cum = np.cumsum(coef, axis=1)
        pick = self.rng.random(len(ph)) * total
        ev = np.minimum((pick[:, None] >= cum).sum(axis=1), 3)
        live = cw > 0
        low = live & (cw < floor)
        if low.any():
            win = self.rng.random(int(low.sum())) * floor[low] < cw[low]
            lw = cw[low]
            led.killed += float(lw[~win].sum())
            led.promoted += float((floor[low][win] - lw[win]).sum())
            cw[low] = np.where(win, floor[low], 0.0)
            live &= cw > 0
        return np.flatnonzero(live), ev[live], cw[live]

    def _children(self, ph: Photons, p: np.ndarray, nf: np.ndarray, src: np.ndarray,
                  ev: np.ndarray, cw: np.ndarray) -> Photons:
        """The photons the chosen events send on: split near the target, new directions
        (cosine or guided diffuse, mirror, undeviated), origins off the surface."""
        led = self.ledger
        w0, nsplit = ph.w0[src], ph.nsplit[src]
        if self.near is not None:
            src, ev, cw, w0, nsplit = self._split(p, src, ev, cw, w0, nsplit)
        if self.window is not None:
            src, ev, cw, w0, nsplit = self._windowed(p, src, ev, cw, w0, nsplit)
        d, n = ph.d[src], nf[src]
        new_d = d.copy()
        diff_r, diff_t, spec_t, mir = ev == 0, ev == 1, ev == 2, ev == 3
        diffuse = diff_r | diff_t
        if diffuse.any():
            axis = np.where(diff_r[diffuse, None], n[diffuse], -n[diffuse])
            if self.guide is None:
                new_d[diffuse] = cosine_hemisphere(axis, self.rng)
            else:
                new_d[diffuse], factor = self.guide.directions(p[src][diffuse], axis, self.rng)
                old = cw[diffuse]
                new = old * factor
                led.promoted += float(np.maximum(new - old, 0.0).sum())
                led.killed += float(np.maximum(old - new, 0.0).sum())
                cw = cw.copy()
                cw[diffuse] = new
                if self.guided_reference:   # the roulette's reference follows the weight
                    w0 = w0.copy()
                    w0[diffuse] = w0[diffuse] * factor
        if mir.any():
            new_d[mir] = mirror(d[mir], n[mir])
        side = np.where(diff_t | spec_t, -1.0, 1.0)
        out = Photons(p[src] + n * (self.eps * side)[:, None], new_d, cw, w0,
                      ph.ndiff[src] + diffuse, ph.nspec[src] + (spec_t | mir), ph.batch[src],
                      nsplit, ph.direct[src] & spec_t)
        if self.guide is not None:
            out = out.take(out.w > 0)
        return out if self.window is None else self._aimed(out)

    def _aimed(self, out: Photons) -> Photons:
        """Photons heading at the target sphere above the window's level split into
        identical copies (flux and reference flux divided); they part at their next event."""
        assert self.window is not None
        reps = self.window.aimed_copies(out.o, out.d, out.w)
        if not (reps > 1).any():
            return out
        self.window_splits += int((reps - 1).sum())
        idx = np.repeat(np.arange(len(out)), reps)
        f = np.repeat(1.0 / reps, reps)
        split = out.take(idx)
        split.w, split.w0 = split.w * f, split.w0 * f
        return split

    def _windowed(self, p: np.ndarray, src: np.ndarray, ev: np.ndarray, cw: np.ndarray,
                  w0: np.ndarray, nsplit: np.ndarray) -> tuple[np.ndarray, ...]:
        """Children above the weight window split into copies (flux and reference flux
        divided: the expected tally is unchanged), each to draw its own direction."""
        assert self.window is not None
        reps = self.window.copies(p[src], cw)
        if not (reps > 1).any():
            return src, ev, cw, w0, nsplit
        self.window_splits += int((reps - 1).sum())
        return (np.repeat(src, reps), np.repeat(ev, reps), np.repeat(cw / reps, reps),
                np.repeat(w0 / reps, reps), np.repeat(nsplit, reps))

    def _split(self, p: np.ndarray, src: np.ndarray, ev: np.ndarray, cw: np.ndarray,
               w0: np.ndarray, nsplit: np.ndarray) -> tuple[np.ndarray, ...]:
        """Children of diffuse events near the target, ``factor`` times each (flux and
        reference flux divided: the expected tally is unchanged)."""
        near = self.near
        assert near is not None
        close = np.linalg.norm(p[src] - near.target, axis=1) <= near.radius
        go = close & (ev <= 1) & (nsplit < near.levels)
        if not go.any():
            return src, ev, cw, w0, nsplit
        reps = np.where(go, near.factor, 1)
        f = np.where(go, 1.0 / near.factor, 1.0)
        return (np.repeat(src, reps), np.repeat(ev, reps), np.repeat(cw * f, reps),
                np.repeat(w0 * f, reps), np.repeat(nsplit + go, reps))
