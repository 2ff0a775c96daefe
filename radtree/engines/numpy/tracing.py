"""The NumPy engine's entry points: sensor grids traced for one hour (:func:`trace_hour`),
for several hours in the same batches (:func:`trace_states`) or at every ``-ab`` of a ladder
from one trace (:func:`trace_bounce_ladder`). The tracer itself: :mod:`.engine`."""

from __future__ import annotations

import math
import zlib
from collections.abc import Sequence

import numpy as np

from radtree.config import EngineParams
from radtree.engines.base import GridResult
from radtree.engines.common.sampling import cosine_directions as cosine_from
from radtree.engines.common.streams import SUN_DISC, PathStreams, stream_key
from radtree.engines.numpy.engine import (
    DEFAULT_OPTIONS,
    TraceOptions,
    _Tracer,
    scene_geometry,
    scene_optics,
)
from radtree.engines.numpy.qmc import FirstDirections
from radtree.engines.numpy.tally import SensorTally
from radtree.errors import EngineError
from radtree.light.sky import SkyState
from radtree.scene import Scene, SensorGrid
from radtree.sensor_grid import is_dense_grid

__all__ = ["grid_rays", "trace", "trace_bounce_ladder", "trace_hour", "trace_states"]


def _grid_seed(seed: int, name: str) -> np.random.Generator:
    return np.random.default_rng(np.random.SeedSequence([int(seed) & 0xFFFFFFFF,
                                                         zlib.crc32(name.encode())]))


def _trace_grid(tracer: _Tracer, grid: SensorGrid, n_paths: int, rng: np.random.Generator,
                sampling: str = "sobol", ladder: bool = False, n_states: int = 1
                ) -> list[GridResult]:
    """Mean illuminance and standard error per sensor of ``grid`` from ``n_paths`` paths each:
    one result, or with ``ladder`` one per ``-ab`` 1 … ``max_bounces`` (from the same paths,
    each contribution counted from its bounce order on), or with ``n_states`` > 1 one per
    hour state of the tracer (every state's paths in the same batches).

    ``sampling = "sobol"``: first directions from randomly shifted Sobol' nets, standard errors
    from the spread of the replicates (:mod:`radtree.engines.numpy.qmc`); ``"random"``:
    pseudo-random first directions, standard errors from the per-path spread."""
    pts, nrm = grid.points, grid.normals
    disc = tracer.opts.sun_disc
    cols = max(1, tracer.max_bounces) if ladder else 1
    hour_of = None
    if n_states > 1:   # one virtual sensor per state and sensor, state-major
        direct = np.concatenate([tracer.sensor_sun(pts, nrm, state=h) for h in range(n_states)])
        hour_of = np.repeat(np.arange(n_states), len(pts))
        pts, nrm = np.tile(pts, (n_states, 1)), np.tile(nrm, (n_states, 1))
    else:
        direct = np.zeros(len(pts)) if disc else tracer.sensor_sun(pts, nrm)
    n_s = len(pts)
    if tracer.max_bounces <= 0 and not disc:
        return _per_state([GridResult(direct, np.zeros(n_s))] * cols, n_states)
    n_paths = max(1, int(n_paths))
    total = n_s * n_paths
    first = FirstDirections(n_s, n_paths, rng) if sampling == "sobol" else None
    tally = SensorTally(n_s, cols, first)
    key = stream_key(rng)  # each path's stream: (key, path number) (engines.common.streams)
    batch = max(1, int(tracer.opts.batch_paths))
    for start in range(0, total, batch):
        pid = np.arange(start, min(total, start + batch))
        sensor = pid // n_paths
        x = np.zeros((len(pid), cols))
        batch_streams = PathStreams(key, pid.astype(np.uint64))
        if tracer.max_bounces > 0:
            dirs = None
            if first is not None:
                u = first.uniforms(pid)
                dirs = cosine_from(u[:, 0], u[:, 1], nrm[sensor])
            orders = np.zeros((len(pid), cols)) if ladder else None
            acc = tracer.paths_split(pts[sensor], nrm[sensor], batch_streams, dirs, orders,
                                     None if hour_of is None else hour_of[sensor])
            x += math.pi * (np.cumsum(orders, axis=1) if orders is not None else acc[:, None])
        if disc:
            x += tracer.sensor_sun(pts[sensor], nrm[sensor],
                                   tracer.sun_directions(len(pid), batch_streams.rows(None, *SUN_DISC)),
                                   batch_streams)[:, None]
        tally.add(pid, sensor, x)
    return _per_state(tally.results(direct), n_states)


def _per_state(results: list[GridResult], n_states: int) -> list[GridResult]:
    """Results of ``n_states`` × the grid's sensors (state-major) split into one per state
    (one column of results expected); one state: as they are."""
    if n_states <= 1:
        return results
    (res,) = results
    lux = np.split(res.lux, n_states)
    se = np.split(res.stderr, n_states) if res.stderr is not None else [None] * n_states
    return [GridResult(a, b) for a, b in zip(lux, se, strict=True)]


def _tracer(scene: Scene, state: SkyState, params: EngineParams, grids: list[str] | None,
            options: TraceOptions, more: Sequence[SkyState] = ()) -> tuple[_Tracer, list[str]]:
    """The tracer of ``state`` (and of the further hour states ``more``, traced in the same
    batches) and the names of the grids to trace."""
    names = list(scene.grids) if grids is None else list(grids)
    missing = [g for g in names if g not in scene.grids]
    if missing:
        raise EngineError(f"unknown sensor grid(s): {', '.join(missing)}")
    if params.numpy.rays < 1:
        raise EngineError(f"engine.rays must be ≥ 1, got {params.numpy.rays}")
    geo = scene_geometry(scene, options.backend, int(getattr(params, "workers", 2) or 1))
    extra = [(st, scene_optics(scene, st, geo.material_names)) for st in more]
    return _Tracer(geo, scene_optics(scene, state, geo.material_names), state, params,
                   options, extra), names


def trace(scene: Scene, state: SkyState, params: EngineParams, grids: list[str] | None = None,
          seed: int | None = None, options: TraceOptions = DEFAULT_OPTIONS
          ) -> dict[str, GridResult]:
    """:func:`trace_hour` with explicit :class:`TraceOptions`."""
    tracer, names = _tracer(scene, state, params, grids, options)
    seed = params.seed if seed is None else seed
    return {name: _trace_grid(tracer, scene.grids[name], grid_rays(params, name),
                              _grid_seed(seed, name), params.numpy.sampling)[0]
            for name in names}


def trace_states(scene: Scene, states: list[SkyState], params: EngineParams,
                 grids: list[str] | None = None, seed: int | None = None,
                 options: TraceOptions = DEFAULT_OPTIONS) -> list[dict[str, GridResult]]:
    """Several hours of one scene traced in the same batches: every state's paths side by
    side in one set of arrays, so that small grids (a few sensors × ~1000 paths an hour) pay
    the per-query NumPy overhead once, not once per hour. Each hour's value is an unbiased
    estimate with its own standard error, like :func:`trace_hour`'s (other random numbers:
    not the same numbers). A sampled sun disc traces hour by hour."""
    if len(states) <= 1 or options.sun_disc:
        return [trace(scene, st, params, grids, seed, options) for st in states]
    tracer, names = _tracer(scene, states[0], params, grids, options, states[1:])
    seed = params.seed if seed is None else seed
    per_grid = {name: _trace_grid(tracer, scene.grids[name], grid_rays(params, name),
                                  _grid_seed(seed, name), params.numpy.sampling,
                                  n_states=len(states))
                for name in names}
    return [{name: res[h] for name, res in per_grid.items()} for h in range(len(states))]


def trace_bounce_ladder(scene: Scene, state: SkyState, params: EngineParams,
                        ab_values: list[int], grids: list[str] | None = None,
                        seed: int | None = None, options: TraceOptions = DEFAULT_OPTIONS
                        ) -> dict[int, dict[str, GridResult]]:
    """The hour traced at every ``-ab`` of ``ab_values`` from *one* set of paths traced to the
    largest: the result at ``-ab k`` sums the contributions of bounce order ≤ k, an unbiased
    estimate of a separate trace at ``max_bounces = k`` (the same paths: the steps of the
    ladder carry correlated, not independent, noise). ``-ab 0``: the direct sun alone."""
    tracer, names = _tracer(scene, state, params.changed(max_bounces=max(ab_values)), grids,
                            options)
    seed = params.seed if seed is None else seed
    out: dict[int, dict[str, GridResult]] = {ab: {} for ab in ab_values}
    for name in names:
        grid = scene.grids[name]
        res = _trace_grid(tracer, grid, grid_rays(params, name), _grid_seed(seed, name),
                          params.numpy.sampling, ladder=True)
        for ab in ab_values:
            out[ab][name] = res[ab - 1] if ab > 0 else GridResult(
                np.zeros(len(grid)) if options.sun_disc
                else tracer.sensor_sun(grid.points, grid.normals), np.zeros(len(grid)))
    return out


def grid_rays(params: EngineParams, grid: str) -> int:
    """Paths per sensor of ``grid``: ``engine.dense_rays`` for the dense façade maps when set,
    else ``engine.rays``."""
    if is_dense_grid(grid) and params.numpy.dense_rays is not None:
        return int(params.numpy.dense_rays)
    return int(params.numpy.rays)


def trace_hour(scene: Scene, state: SkyState, params: EngineParams,
               grids: list[str] | None = None, seed: int | None = None
               ) -> dict[str, GridResult]:
    """Illuminance (lux) and its Monte Carlo standard error per sensor of each grid, one hour.

    ``params.numpy.rays`` paths per sensor, ``params.numpy.max_bounces`` diffuse bounces (like ``-ab``),
    ``seed`` (default ``params.seed``): the same seed gives identical numbers; each grid draws
    from its own stream (seed, grid name), so a grid's values do not depend on which other
    grids are traced.
    """
    return trace(scene, state, params, grids, seed, DEFAULT_OPTIONS)
