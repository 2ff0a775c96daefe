"""One hour of forward light tracing: sources, transport, detectors → lux per sensor.

:func:`trace_forward` returns the illuminance of every traced grid (lux = tallied lm / patch
area, mean of all photons; standard error = s.d. of the batch estimates / √their number) with
the hour's :class:`~radtree.engines.forward.tracer.Ledger` and counters. Photons are traced in
rounds of ``settings.photons`` (``settings.batches`` batches each); with
``settings.target_rel_se`` rounds are added until every grid's mean reaches it or
``settings.max_photons`` (:mod:`radtree.engines.forward.precision`; a first round that misses
the target only sizes the run and is not counted). The unscattered sun and sky are counted
at the sensor points instead of on the patches when the settings ask for it
(:mod:`.direct`, :mod:`.skypoint`): the sun's exactly, the sky's estimated afresh for every
batch of every round.
"""

from __future__ import annotations

import time
import zlib
from dataclasses import dataclass
from typing import Any

import numpy as np

from radtree.engines.base import GridResult
from radtree.engines.common.geometry import Environment, scene_geometry, scene_optics
from radtree.engines.forward.detectors import PatchDetectors
from radtree.engines.forward.direct import direct_sun
from radtree.engines.forward.guide import Guide
from radtree.engines.forward.precision import Budget, worst_relative_se
from radtree.engines.forward.settings import ForwardSettings
from radtree.engines.forward.skypoint import direct_sky
from radtree.engines.forward.sources import EnvironmentSource, SunSource, bounding_sphere
from radtree.engines.forward.strata import (
    PILOT,
    Stratum,
    allocate,
    pilot,
    predicted_crossings,
    reallocate,
    ring_edges,
    trace_strata,
)
from radtree.engines.forward.tracer import ForwardTracer, Ledger, Photons, Splitting
from radtree.engines.forward.window import WeightWindow, window_level
from radtree.errors import ConfigError, EngineError
from radtree.light.sky import SkyState
from radtree.scene import Scene


@dataclass
class ForwardResult:
    """Lux per grid, where the flux went, and what it cost. ``batches[grid]``: (batches,
    sensors) lux of each independent batch (each batch's tally scaled to all photons)."""

    grids: dict[str, GridResult]
    ledger: Ledger
    photons: int           # photons counted (every counted round; pilot, sizing round not)
    segments: int
    seconds: float
    batches: dict[str, np.ndarray]
    #: the stratified launch's rings (None: uniform launch) and the pilot's photons
    strata: list[Stratum] | None = None
    pilot_photons: int = 0
    #: rounds of ``settings.photons`` traced (more than 1: the precision target asked for
    #: more), and the :class:`PrecisionWarning` text when the photon cap stopped the run
    rounds: int = 1
    warning: str | None = None
    #: photons of the sizing round (traced, steering the strata, not counted; 0: none)
    sizing_photons: int = 0
    #: the weight window's level (lm; None: no window opened) and the copies it added
    window_level: float | None = None
    window_splits: int = 0

    def grid_mean(self, grid: str) -> tuple[float, float]:
        """Mean lux over the grid's sensors and its standard error from the batches (patches
        that overlap share photons: their errors are correlated, so the batches, not the
        per-sensor errors, give the mean's error)."""
        per_batch = self.batches[grid].mean(axis=1)
        return float(self.grids[grid].lux.mean()), float(
            per_batch.std(ddof=1) / np.sqrt(len(per_batch)))


def target_grid(scene: Scene) -> str:
    """The grid a sun beam is aimed at: ``facade`` when the scene has one, else the first."""
    return "facade" if "facade" in scene.grids else next(iter(scene.grids))


def check_beam(scene: Scene, state: SkyState, settings: ForwardSettings) -> None:
    """Raise one :class:`ConfigError` (field ``engine.beam_diameter_m``) when the sun beam,
    aimed at the centre of the target grid along the hour's sun, misses one of its sensors."""
    if settings.beam_diameter_m is None or not state.sun_on:
        return
    name = target_grid(scene)
    pts = scene.grids[name].points
    sun = np.asarray(state.sun.vector, float)
    src = SunSource(sun, state.direct_normal_lux, pts.mean(axis=0), 1.0, 1.0)
    need = float(src.distance_to_axis(pts).max())
    if need > settings.beam_diameter_m / 2.0:
        raise ConfigError(
            f"the {settings.beam_diameter_m:g} m sun beam aimed at the centre of grid '{name}' "
            f"misses its sensors at {state.time} (the farthest is {need:.3f} m from the beam "
            f"axis: a diameter ≥ {2 * need:.3f} m is needed)", field="engine.beam_diameter_m")


def sun_source(scene: Scene, state: SkyState, settings: ForwardSettings, sphere
               ) -> SunSource:
    """The hour's sun: over the whole bounding sphere, or the beam aimed at the target grid's
    centre (every sensor of that grid must lie inside the beam: :func:`check_beam`)."""
    sun = np.asarray(state.sun.vector, float)
    if settings.beam_diameter_m is None:
        return SunSource(sun, state.direct_normal_lux, sphere.centre, sphere.radius,
                         sphere.radius + 1.0)
    check_beam(scene, state, settings)
    target = scene.grids[target_grid(scene)].points.mean(axis=0)
    dist = float(np.linalg.norm(target - sphere.centre)) + sphere.radius + 1.0
    return SunSource(sun, state.direct_normal_lux, target, settings.beam_diameter_m / 2.0, dist)


@dataclass(frozen=True)
class _Hour:
    """One hour's forward trace, planned: the grids ``names``, geometry and optics, patch
    detectors, bounding sphere, sources (``direct``: the indices whose unscattered light is
    counted at the points, not on the patches; ``sun_direct``, ``sky``: the sun's beam and the
    environment source counted there), the random generator, the target grid's centre (m) and the variance reduction
    near it (splitting, guiding)."""

    scene: Scene
    state: SkyState
    settings: ForwardSettings
    names: list[str]
    geo: Any
    optics: Any
    det: PatchDetectors
    sphere: Any
    sources: list
    direct: frozenset[int]
    sun_direct: bool
    sky: EnvironmentSource | None
    rng: np.random.Generator
    target: np.ndarray
    near: Splitting | None
    guide: Guide | None
    reach: float   # radius (m) of the sphere around ``target`` the guide and window aim at


def _plan(scene: Scene, state: SkyState, settings: ForwardSettings, grids: list[str] | None,
          *, backend: str, workers: int, label: str | None) -> _Hour:
    """The hour's :class:`_Hour`: detectors on ``grids``, the sources (the sun, and without a
    beam the sky and ground glow), the generator seeded by the seed and the hour's label."""
    names = list(scene.grids) if grids is None else list(grids)
    missing = [g for g in names if g not in scene.grids]
    if missing:
        raise EngineError(f"unknown sensor grid(s): {', '.join(missing)}")
    geo = scene_geometry(scene, backend, workers)
    det = PatchDetectors({n: scene.grids[n] for n in names}, settings.patch_m)
    pts = np.vstack([geo.vertices, det.corners().reshape(-1, 3),
                     *([] if geo.media is None else [geo.media.corners()])])
    sphere = bounding_sphere(pts)
    sources: list = []
    direct: set[int] = set()
    sky: EnvironmentSource | None = None
    whole = settings.beam_diameter_m is None
    if state.sun_on:
        sources.append(sun_source(scene, state, settings, sphere))
        if settings.direct_sun and whole:
            direct.add(0)  # the sun's beam at the points, not on the patches
    if whole:  # a beam is the study's only source: no sky, no glow
        env = EnvironmentSource(Environment(state), sphere)
        if env.cdf is not None and env.flux > 0:
            sources.append(env)
            if settings.direct_sky:   # the unscattered sky at the points (skypoint.py)
                direct.add(len(sources) - 1)
                sky = env
    rng = np.random.default_rng(np.random.SeedSequence(
        [int(settings.seed) & 0xFFFFFFFF, zlib.crc32((label or state.label).encode())]))
    optics = scene_optics(scene, state, geo.material_names)
    aim = target_grid(scene) if target_grid(scene) in names else names[0]
    target = scene.grids[aim].points.mean(axis=0)
    near = (Splitting(target, settings.split_radius_m, settings.split)
            if settings.split > 1 else None)
    radius = settings.guide_radius_m
    if radius is None:  # the sphere just holding the target grid's patches
        corners = det.corners()[det.slices[aim]].reshape(-1, 3)
        radius = float(np.linalg.norm(corners - target, axis=1).max())
    guide = Guide(target, radius, settings.guide) if settings.guide > 0 else None
    return _Hour(scene, state, settings, names, geo, optics, det, sphere, sources,
                 frozenset(direct), bool(state.sun_on and 0 in direct), sky, rng, target, near,
                 guide, radius)


def _tracer(h: _Hour, batches: int) -> ForwardTracer:
    s = h.settings
    return ForwardTracer(h.geo, h.optics, h.det, batches, threshold=s.threshold,
                         splitting=s.splitting, max_bounces=s.max_bounces,
                         max_specular=s.max_specular, chunk=s.chunk, rng=h.rng,
                         splitting_near=h.near, guide=h.guide,
                         guided_roulette=s.guided_roulette)


def _focus(h: _Hour) -> tuple[list[Stratum] | None, int, int]:
    """The focused launch's rings, their photons allotted by a pilot run (None without a
    focus, with a beam or without sources), the pilot's photons and segments."""
    s, b = h.settings, h.settings.batches
    if s.focus_m is None or s.beam_diameter_m is not None or not h.sources:
        return None, 0, 0
    edges = ring_edges(float(s.focus_m),
                       h.sphere.radius + float(np.linalg.norm(h.target - h.sphere.centre)))
    strata = [Stratum(i, a, b_) for i in range(len(h.sources))
              for a, b_ in zip(edges[:-1], edges[1:])]
    per_ring = max(64, int(PILOT * s.photons / len(strata)))
    scout = _tracer(h, 1)
    pilot(h.sources, strata, h.target, scout, per_ring, h.rng, h.direct)
    n_pilot = per_ring * len(strata)
    allocate(strata, max(s.photons - n_pilot, b * len(strata)) // s.stages, b)
    return strata, n_pilot, scout.segments


def _window_from_pilot(h: _Hour, tracer: ForwardTracer, strata: list[Stratum] | None) -> None:
    """The weight window opened before the first round, its level from the pilot's patch
    crossings as the first round's allocation will make them
    (:func:`~radtree.engines.forward.strata.predicted_crossings`): every round, the sizing
    round included, then traces with it (without crossings in the pilot: after the first
    round, :func:`_open_window`)."""
    if strata is None or h.settings.window <= 0:
        return
    crossings, flux = predicted_crossings(strata)
    level = window_level(h.settings.window, flux, crossings)
    if level is not None:
        tracer.window = WeightWindow(h.target, h.reach, level)


def _at_points(h: _Hour) -> np.ndarray:
    """The sun's direct light at the sensor points (lux; zeros when it is not counted there)."""
    out = np.zeros(h.det.count)
    if h.sun_direct:
        sun = np.asarray(h.state.sun.vector, float)
        for name in h.names:
            out[h.det.slices[name]] = direct_sun(h.geo, h.optics, h.scene.grids[name], sun,
                                                 h.state.direct_normal_lux)
    return out


def _sky_rows(h: _Hour) -> np.ndarray | None:
    """(batches, detectors) estimates of the unscattered sky at the sensor points (lux), each
    batch from its own directions (:mod:`radtree.engines.forward.skypoint`); None: not
    counted there."""
    if h.sky is None:
        return None
    s = h.settings
    rows = np.zeros((s.batches, h.det.count))
    for name in h.names:
        rows[:, h.det.slices[name]] = direct_sky(h.geo, h.optics, h.scene.grids[name], h.sky,
                                                 s.sky_rays, s.batches, h.rng)
    return rows


def _round(h: _Hour, tracer: ForwardTracer, strata: list[Stratum] | None,
           at_points: np.ndarray, photons: int) -> tuple[int, np.ndarray]:
    """One round (or stage) of photons into a fresh tally: its photons and (batches,
    detectors) lux of each batch; ``photons``: of the uniform launch (the focused launch's
    are the strata's)."""
    s, b = h.settings, h.settings.batches
    tracer.tally = np.zeros((b, h.det.count))
    if strata is not None:
        trace_strata(h.sources, strata, h.target, tracer, s.chunk, b, h.rng, h.direct)
        n = sum(st.photons for st in strata)
    else:
        counts = _allot(photons, [src.flux for src in h.sources], b)
        for i, (src, n_src) in enumerate(zip(h.sources, counts)):
            per_photon = src.flux / n_src
            for c0 in range(0, n_src, s.chunk):
                k = min(s.chunk, n_src - c0)
                batch = (c0 + np.arange(k)) % b
                tracer.run(Photons.start(src.launch(k, per_photon, h.rng), batch,
                                         i in h.direct))
        n = sum(counts)
    rows = tracer.tally * b / h.det.area
    if h.sun_direct:
        rows += at_points  # the direct sun, exact at the points: the same in every batch
    sky = _sky_rows(h)
    if sky is not None:
        rows += sky        # the unscattered sky at the points: each batch its own estimate
    return n, rows


def _open_window(h: _Hour, tracer: ForwardTracer) -> None:
    """After the hour's first round, when the pilot did not open it (no focused launch, or
    no crossings in the pilot): the weight window for every later round, its level from that
    round's patch crossings (:mod:`radtree.engines.forward.window`)."""
    if tracer.window is not None or h.settings.window <= 0:
        return
    level = window_level(h.settings.window, tracer.crossed_flux, tracer.crossings)
    if level is not None:
        tracer.window = WeightWindow(h.target, h.reach, level)


def _rounds(h: _Hour, tracer: ForwardTracer, strata: list[Stratum] | None
            ) -> tuple[int, np.ndarray, int, str | None, int]:
    """Rounds of ``photons`` until the precision target or the cap
    (:class:`~radtree.engines.forward.precision.Budget`): photons counted, (batches,
    detectors) lux of every counted batch, counted rounds, the warning when the cap stopped
    the run, and the photons of the sizing round (0: the first round met the target, or no
    target). With a target not met by the first round, that round only *sizes* the run (and
    steers the strata): the photons it predicts are traced afresh and counted, so whether the
    run stops early does not depend on the counted photons (precision.py, *Stopping*)."""
    s = h.settings
    at_points = _at_points(h)
    budget = Budget(s.photons, s.target_rel_se, s.max_photons)
    traced, sizing, rows, rounds = 0, 0, [], 0
    # stages re-allot the focused launch's rings (a uniform launch has none: its round at once);
    # a stage's photons: the first round's as _focus allotted them (the pilot's taken off)
    stages = 1 if strata is None else s.stages
    stage = s.photons if strata is None else sum(st.photons for st in strata)
    leg = s.photons
    while leg > 0:
        for _ in range(max(1, leg // s.photons)):
            for _ in range(stages):
                if strata is not None and traced:   # later stages: allotted from all so far
                    reallocate(strata, stage, s.batches)
                n, r = _round(h, tracer, strata, at_points, stage)
                traced += n
                rows.append(r)
                _open_window(h, tracer)
            rounds += 1
            stage = s.photons // stages
        per_batch = np.vstack(rows)
        grid_batches = {name: per_batch[:, h.det.slices[name]].mean(axis=1)
                        for name in h.names}
        rel = worst_relative_se(grid_batches)[1]
        leg = budget.next_leg(traced - sizing, rel, spent=sizing)
        if leg and not sizing and rounds == 1:
            fresh = budget.sized_leg(traced, rel)
            if fresh:   # the first round sized the run: trace the prediction afresh
                sizing, leg, rows, rounds = traced, fresh, [], 0
    return (traced - sizing, per_batch, rounds, budget.warn_if_short(traced, grid_batches),
            sizing)


def trace_forward(scene: Scene, state: SkyState, settings: ForwardSettings,
                  grids: list[str] | None = None, *, backend: str = "auto", workers: int = 2,
                  label: str | None = None) -> ForwardResult:
    """Forward-trace one hour of ``scene`` on ``grids`` (default every grid). Sources: the sun
    over the whole scene plus the sky and the distant ground glow of the hour (as the backward
    engines see them), or — with ``settings.beam_diameter_m`` — the sun beam alone (the
    study's surface source: no sky, no ground glow). Plan (:func:`_plan`), focus
    (:func:`_focus`), rounds (:func:`_rounds`), the result."""
    t0 = time.perf_counter()
    h = _plan(scene, state, settings, grids, backend=backend, workers=workers, label=label)
    tracer = _tracer(h, settings.batches)
    strata, n_pilot, pilot_segments = _focus(h)
    _window_from_pilot(h, tracer, strata)
    counted, per_batch, rounds, warning, sizing = _rounds(h, tracer, strata)
    out, per = {}, {}
    for name in h.names:
        per[name] = per_batch[:, h.det.slices[name]]
        out[name] = GridResult(per[name].mean(axis=0),
                               per[name].std(axis=0, ddof=1) / np.sqrt(len(per[name])))
    return ForwardResult(out, tracer.ledger, counted, tracer.segments + pilot_segments,
                         time.perf_counter() - t0, per, strata, n_pilot, rounds, warning,
                         sizing, None if tracer.window is None else tracer.window.level,
                         tracer.window_splits)


def _allot(photons: int, fluxes: list[float], batches: int) -> list[int]:
    """Photons per source ∝ its flux (equal photon fluxes), at least ``batches`` each."""
    total = sum(fluxes)
    if total <= 0:
        return [batches for _ in fluxes]
    return [max(batches, int(round(photons * f / total))) for f in fluxes]
