"""The forward engine's settings: one typed, validated dataclass read from ``[engine]``.

Keys of the project's ``[engine]`` table (:class:`radtree.config.EngineParams`): ``photons``
(per hour), ``forward_threshold`` (flux threshold as a fraction of a photon's launched flux, in
(0, 1)), ``forward_splitting`` (true: split every hit into reflected and transmitted children
and kill children below the threshold, as TracePro does — biased low by the flux it kills;
false: one event per hit chosen ∝ its coefficient, Russian roulette below the threshold —
unbiased), ``beam_diameter_m`` (the sun as a collimated beam of that diameter aimed at the
centre of the first sensor grid, and then the only source — no sky, no ground glow, as in the
study; unset = sunlight, sky and ground glow over the whole scene), ``patch_m`` (side of
the square detector around each sensor, m), ``forward_batches`` (independent batches for the
standard error) and ``forward_focus_m`` (a focused launch: start points drawn densest around
the target grid's centre, innermost disc of that radius, m — unbiased, see
:mod:`radtree.engines.forward.strata`; unset = uniform over the launch disc),
``forward_split`` and ``forward_split_radius_m`` (diffuse events within that radius of the
target grid's centre split into that many children, at most twice per photon; 1 = never),
``forward_guide`` and ``forward_guide_radius_m`` (that share of every diffuse event outside a
sphere of that radius around the target grid's centre aims its direction at the sphere, the
flux corrected: :mod:`radtree.engines.forward.guide`; 0 = Lambertian scattering only),
``target_rel_se`` and ``max_photons`` (rounds of ``photons`` added until every traced grid's
mean has that relative standard error, or that many photons:
:mod:`radtree.engines.forward.precision`; unset = one round) and ``forward_direct_sun`` (the
sun's direct beam computed at the sensor points, sun photons tallied only once scattered:
:mod:`radtree.engines.forward.direct`) and ``forward_direct_sky`` (the same for the sky's
unscattered light, estimated at the points: :mod:`radtree.engines.forward.skypoint`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

from radtree.errors import ConfigError

if TYPE_CHECKING:
    from radtree.config import EngineParams


def _bad(field: str, message: str) -> ConfigError:
    return ConfigError(message, field=f"engine.{field}")


@dataclass(frozen=True)
class ForwardSettings:
    """How the forward engine launches, scatters and tallies photons.

    ``photons``: photons per hour (sun and sky together, allotted ∝ their launched flux, so
    every photon starts with the same flux). ``threshold``: relative flux threshold.
    ``splitting``: ray splitting (else Russian roulette). ``beam_diameter_m``: None = the sun
    over the scene's whole bounding sphere. ``patch_m``: detector side (m); a detector tallies
    the flux crossing its square from the sensor's front side; lux = lm / m².
    ``batches``: independent batches (standard error = s.d. of batch means / √batches).
    ``max_bounces``: diffuse scattering events per photon (``-ab``: a backward path with k
    diffuse segments is a photon path with k diffuse events). ``max_specular``: specular events
    per photon. ``chunk``: photons stepped at once (bounded memory). ``seed``: random seed.
    ``focus_m``: innermost radius (m) of the focused launch around the target grid's centre
    (None: start points uniform on the launch disc; ignored with a beam). ``split``: children
    per diffuse event within ``split_radius_m`` (m) of the target grid's centre (1: none).
    ``guide``: share (0 ≤ q < 1) of diffuse directions aimed at the sphere of ``guide_radius_m``
    (m; None: the smallest holding the target grid's patches) around the target grid's centre
    (0: none). ``target_rel_se``: trace further rounds of
    ``photons`` until every grid's mean has this relative standard error (None: one round);
    ``max_photons``: the cap (then a :class:`~radtree.engines.forward.precision.PrecisionWarning`
    with the error reached). ``direct_sun``: the sun's direct beam computed at the sensor points
    and sun photons tallied on the patches only once scattered (:mod:`.direct`; whole-scene
    sun only). ``window``: the weight window's factor (0: none, :mod:`.window`).
    ``guided_roulette``: a guided diffuse event scales the photon's reference flux (the
    roulette's) with its flux (:mod:`.tracer`, *Roulette after a guided event*; False: the
    reference stays the launched flux, as before 2026-12-07 — kept for comparisons only).
    ``direct_sky``: the unscattered sky (and ground glow) estimated at the sensor points from
    ``sky_rays`` directions per sensor, batch and stage, sky photons tallied on the patches
    only once scattered (:mod:`.skypoint`; whole-scene sun and sky only). ``stages``: every
    round traced in that many equal stages, the focused launch's rings allotted again before
    each from all photons so far (:mod:`.strata`, *Re-allocation*; 1: the round at once; a
    uniform launch or a beam, without rings, traces its rounds at once).
    """

    photons: int = 1_000_000
    threshold: float = 0.05
    splitting: bool = False
    beam_diameter_m: float | None = None
    patch_m: float = 0.5
    batches: int = 16
    max_bounces: int = 8
    max_specular: int = 32
    chunk: int = 1 << 17
    seed: int = 1
    focus_m: float | None = None
    split: int = 1
    split_radius_m: float = 2.0
    guide: float = 0.0
    guide_radius_m: float | None = 2.0
    target_rel_se: float | None = None
    max_photons: int = 64_000_000
    direct_sun: bool = False
    window: float = 0.0
    guided_roulette: bool = True
    direct_sky: bool = False
    sky_rays: int = 32
    stages: int = 1

    def __post_init__(self) -> None:
        if isinstance(self.photons, bool) or not isinstance(self.photons, int) or self.photons < 1:
            raise _bad("photons", f"must be a whole number ≥ 1, got {self.photons!r}")
        if not isinstance(self.threshold, int | float) or not 0.0 < self.threshold < 1.0:
            raise _bad("forward_threshold", "must be strictly between 0 and 1 (a fraction of the "
                       f"launched flux), got {self.threshold!r}")
        if not isinstance(self.splitting, bool):
            raise _bad("forward_splitting", f"must be true or false, got {self.splitting!r}")
        d = self.beam_diameter_m
        if d is not None and (not isinstance(d, int | float) or not math.isfinite(d) or d <= 0):
            raise _bad("beam_diameter_m", f"must be > 0 m (or unset for sun over the whole "
                       f"scene), got {d!r}")
        if not isinstance(self.patch_m, int | float) or not math.isfinite(self.patch_m) \
                or self.patch_m <= 0:
            raise _bad("patch_m", f"must be > 0 m, got {self.patch_m!r}")
        if isinstance(self.batches, bool) or not isinstance(self.batches, int) \
                or self.batches < 2:
            raise _bad("forward_batches", f"must be a whole number ≥ 2, got {self.batches!r}")
        if self.photons < self.batches:
            raise _bad("photons", f"{self.photons} photons cannot fill {self.batches} batches")
        f = self.focus_m
        if f is not None and (isinstance(f, bool) or not isinstance(f, int | float)
                              or not math.isfinite(f) or f <= 0):
            raise _bad("forward_focus_m", f"must be > 0 m (or unset for a uniform launch), "
                       f"got {f!r}")
        if isinstance(self.split, bool) or not isinstance(self.split, int) or self.split < 1:
            raise _bad("forward_split", f"must be a whole number ≥ 1, got {self.split!r}")
        r = self.split_radius_m
        if not isinstance(r, int | float) or not math.isfinite(r) or r <= 0:
            raise _bad("forward_split_radius_m", f"must be > 0 m, got {r!r}")
        q = self.guide
        if isinstance(q, bool) or not isinstance(q, int | float) or not 0.0 <= q < 1.0:
            raise _bad("forward_guide", f"must be ≥ 0 and < 1 (a share of the diffuse "
                       f"directions), got {q!r}")
        gr = self.guide_radius_m
        if gr is not None and (not isinstance(gr, int | float) or not math.isfinite(gr)
                               or gr <= 0):
            raise _bad("forward_guide_radius_m", f"must be > 0 m (or unset: the sphere just "
                       f"holding the target grid's patches), got {gr!r}")
        t = self.target_rel_se
        if t is not None and (isinstance(t, bool) or not isinstance(t, int | float)
                              or not 0.0 < t < 1.0):
            raise _bad("target_rel_se", f"must be strictly between 0 and 1 (a relative standard "
                       f"error, e.g. 0.02), or unset for a fixed photon count, got {t!r}")
        m = self.max_photons
        if isinstance(m, bool) or not isinstance(m, int) or m < 1 \
                or (t is not None and m < self.photons):
            raise _bad("max_photons", f"must be a whole number ≥ engine.photons "
                       f"({self.photons}), got {m!r}")
        if not isinstance(self.direct_sun, bool):
            raise _bad("forward_direct_sun", f"must be true or false, got {self.direct_sun!r}")
        if not isinstance(self.direct_sky, bool):
            raise _bad("forward_direct_sky", f"must be true or false, got {self.direct_sky!r}")
        if isinstance(self.sky_rays, bool) or not isinstance(self.sky_rays, int) \
                or self.sky_rays < 1:
            raise _bad("forward_direct_sky", f"sky_rays must be a whole number ≥ 1, got "
                       f"{self.sky_rays!r}")
        k = self.stages
        if isinstance(k, bool) or not isinstance(k, int) or k < 1 \
                or self.photons // k < self.batches:
            raise _bad("forward_stages", f"must be a whole number ≥ 1 that leaves each stage "
                       f"at least {self.batches} photons (one a batch) of the round's "
                       f"{self.photons}, got {k!r}: raise engine.photons or lower "
                       f"engine.forward_stages")
        ww = self.window
        if isinstance(ww, bool) or not isinstance(ww, int | float) or not math.isfinite(ww) \
                or ww < 0:
            raise _bad("forward_window", f"must be ≥ 0 (0: no weight window), got {ww!r}")
        if not isinstance(self.guided_roulette, bool):
            raise _bad("forward_guide", f"guided_roulette must be true or false, got "
                       f"{self.guided_roulette!r}")
        if self.max_bounces < 0 or self.max_specular < 0 or self.chunk < 1:
            raise _bad("max_bounces", "bounce caps must be ≥ 0 and the chunk ≥ 1")

    @classmethod
    def from_params(cls, params: EngineParams, ab: int | None = None) -> ForwardSettings:
        """The settings of a project's ``[engine]`` table (its forward group,
        :class:`radtree.config.engine.ForwardParams`); ``ab`` (the scene's ``-ab``) caps the
        diffuse events (default ``engine.max_bounces``)."""
        f = params.forward
        return cls(photons=f.photons, threshold=f.forward_threshold,
                   splitting=f.forward_splitting, beam_diameter_m=f.beam_diameter_m,
                   patch_m=f.patch_m, batches=f.forward_batches,
                   max_bounces=int(params.numpy.max_bounces if ab is None else ab),
                   seed=int(params.seed), focus_m=f.forward_focus_m,
                   split=f.forward_split, split_radius_m=f.forward_split_radius_m,
                   guide=f.forward_guide, guide_radius_m=f.forward_guide_radius_m,
                   target_rel_se=f.target_rel_se, max_photons=f.max_photons,
                   direct_sun=f.forward_direct_sun, window=f.forward_window,
                   direct_sky=f.forward_direct_sky, stages=f.forward_stages)

    def describe(self) -> str:
        source = ("sun over the whole scene" if self.beam_diameter_m is None
                  else f"sun beam {self.beam_diameter_m:g} m")
        if self.beam_diameter_m is None and self.focus_m is not None:
            source += f", focused launch from {self.focus_m:g} m"
        if self.direct_sun and self.beam_diameter_m is None:
            source += ", direct sun at the points"
        if self.direct_sky and self.beam_diameter_m is None:
            source += ", unscattered sky at the points"
        scatter = "ray splitting" if self.splitting else "Russian roulette"
        if self.split > 1:
            scatter += f", ×{self.split} within {self.split_radius_m:g} m of the target"
        if self.guide > 0:
            radius = ("its patches" if self.guide_radius_m is None
                      else f"{self.guide_radius_m:g} m")
            scatter += f", {self.guide:.0%} of diffuse directions aimed at the target " \
                       f"({radius})"
        count = (f"{self.photons} photons" if self.target_rel_se is None else
                 f"photons in rounds of {self.photons} to a {self.target_rel_se:.1%} standard "
                 f"error of each grid mean (cap {self.max_photons})")
        if self.stages > 1 and self.focus_m is not None and self.beam_diameter_m is None:
            count += f", each round in {self.stages} stages"
        return (f"{count}, {source}, {scatter}, threshold {self.threshold:g}, "
                f"patches {self.patch_m:g} m, {self.batches} batches, seed {self.seed}")
