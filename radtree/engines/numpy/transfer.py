"""The transfer of a layer of explicit surfaces, traced backwards: where light that reaches a
point along a direction came from.

Paths start at given points along given directions and scatter off the scene's surfaces as in
the NumPy engine (Lambertian reflection and transmission, undeviated specular transmission,
mirrors; Russian roulette below a throughput of 0.05), with no sky, no ground glow and no sun:
each is reported where it leaves the scene, as the direction it leaves along and its
throughput. For a distant source of radiance L(ω) the radiance reaching the start point along
the reversed direction is the mean over the launched paths of throughput · L(escape
direction); binned by escape direction that is one row of the layer's BSDF
(:mod:`radtree.pipeline.dome_curvature`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from radtree.config import EngineParams
from radtree.engines.common.geometry import scene_geometry, scene_optics
from radtree.engines.common.streams import PathStreams, stream_key
from radtree.engines.numpy.engine import TraceOptions, _Tracer
from radtree.engines.numpy.scenes import sky_state
from radtree.errors import EngineError
from radtree.scene import Scene


@dataclass(frozen=True)
class Escapes:
    """Every escape of the traced paths: ``path`` (index of the launched ray), ``direction``
    (unit vector it leaves along, world axes), ``weight`` (its throughput, ≤ 1 but for the
    roulette's promotion) and how many rays were ``launched``."""

    path: np.ndarray
    direction: np.ndarray
    weight: np.ndarray
    launched: int


def trace_escapes(scene: Scene, origins: np.ndarray, directions: np.ndarray, *,
                  max_bounces: int = 16, seed: int = 1, backend: str = "auto",
                  workers: int = 2, batch: int = 1 << 17) -> Escapes:
    """Back-trace one path per (origin, direction) through ``scene`` (metres, world axes);
    ``max_bounces`` diffuse events per path (as ``rtrace -ab``); the same ``seed`` gives the
    same escapes."""
    o = np.asarray(origins, float).reshape(-1, 3)
    d = np.asarray(directions, float).reshape(-1, 3)
    if len(o) != len(d):
        raise EngineError(f"{len(o)} origins but {len(d)} directions")
    d = d / np.linalg.norm(d, axis=1, keepdims=True)
    state = sky_state("none", ground_glow=False)
    params = EngineParams(max_bounces=max_bounces, workers=workers, seed=seed)
    geo = scene_geometry(scene, backend, workers)
    tracer = _Tracer(geo, scene_optics(scene, state, geo.material_names), state, params,
                     TraceOptions(backend=backend))
    key = stream_key(np.random.default_rng(seed))
    paths: list[np.ndarray] = []
    dirs: list[np.ndarray] = []
    weights: list[np.ndarray] = []
    for start in range(0, len(o), batch):
        s = slice(start, start + batch)

        def record(idx: np.ndarray, e: np.ndarray, w: np.ndarray, start: int = start) -> None:
            paths.append(idx + start)
            dirs.append(np.array(e, float))
            weights.append(np.array(w, float))

        ids = np.arange(start, min(len(o), start + batch), dtype=np.uint64)
        tracer.paths(o[s], d[s], PathStreams(key, ids), dirs=d[s], escapes=record)
    if not paths:
        return Escapes(np.zeros(0, np.int64), np.zeros((0, 3)), np.zeros(0), len(o))
    return Escapes(np.concatenate(paths), np.vstack(dirs), np.concatenate(weights), len(o))
