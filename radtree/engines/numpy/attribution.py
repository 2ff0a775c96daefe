"""Which tree: the light each tree takes from each sensor, attributed while tracing.

Method — paired paths, each difference given to the first crown crossed:

1. The scene is traced twice with the *same* path streams (:mod:`.streams`: every draw is a
   hash of the path's number and its place in the program) and the same Sobol' first
   directions: once as it is (``with_trees``), once without the faces of the attributed
   trees (``without``, :meth:`radtree.scene.Scene.without_owners`). Both traces are the
   engine's ordinary trace (:func:`radtree.engines.numpy.tracing.trace`; ``with_trees`` is
   its result to the last bit) at one origin offset ε (the with-trees scene's).
2. While the tree-less path is traced, every one of its rays — each segment up to the surface
   it reaches (∞ when it escapes) and each shadow ray towards the sun that reaches the sun —
   is intersected with the trees' faces alone (leaves and trunks). The first of these rays, in
   path order, that meets a tree's face *names* the path's tree: the face it meets first
   along that ray (its :attr:`~radtree.scene.Mesh.owners`).
3. Until that ray, the two traces of the path are the same path (same surfaces, same draws),
   so the path's difference ``π (L_without − L_with)`` arises there or after and is given
   whole to the named tree; a path that crosses no tree has no difference (``unattributed``
   checks it: 0 up to rounding). A sensor's own direct sun (exact, no path) goes to the first
   tree its sun ray meets.

So the trees' shares sum to the change ``without − with_trees`` exactly, for every sensor,
and a tree's share is *net*: the light it blocks minus the light its leaves scatter onto the
sensor (from paths that meet it first). Overlapping crowns: a path goes to the first tree it
meets, in path order and, along one ray, nearest first — the tree standing in front takes
what the trees behind it would also have blocked. Removing one tree i and re-tracing changes
the sensor by the light of the paths that meet i (first or later); the two agree where paths
seldom meet two crowns (the check: ``benchmarks/tree_impact.py``).

Standard errors: from the spread of the Sobol' replicates' means (each tree's paths'
differences, the others' counted 0), or the per-path spread with ``random`` sampling — as the
engine's own (:mod:`.qmc`, :mod:`.tally`). Cost: two traces plus one query on the trees'
faces per ray of the tree-less trace.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from radtree.config import EngineParams
from radtree.engines.base import GridResult, TreeAttribution
from radtree.engines.numpy.engine import DEFAULT_OPTIONS, TraceOptions, _Tracer, scene_geometry
from radtree.engines.numpy.qmc import FirstDirections, replicate_stderr
from radtree.engines.numpy.raycast import make_caster
from radtree.engines.numpy.sampling import cosine_directions
from radtree.engines.numpy.streams import PathStreams, stream_key
from radtree.engines.numpy.tally import SensorTally
from radtree.engines.numpy.tracing import _grid_seed, _tracer, grid_rays
from radtree.errors import EngineError
from radtree.light.sky import SkyState
from radtree.scene import Scene, SensorGrid

__all__ = ["attribute_hour"]


class _Crowns:
    """The attributed trees' faces alone: a ray caster and each triangle's tree index."""

    def __init__(self, scene: Scene, owners: list[str], backend: str, workers: int):
        index = {o: i for i, o in enumerate(owners)}
        verts, faces, own, off = [], [], [], 0
        for m in scene.solid_meshes():
            if m.owners is None:
                continue
            keep = np.isin(m.owners, owners)
            if not keep.any():
                continue
            verts.append(m.vertices)
            faces.append(m.faces[keep] + off)
            own.append(np.array([index[o] for o in m.owners[keep]], np.int64))
            off += len(m.vertices)
        if not faces:
            raise EngineError("no tree faces to attribute light to (no mesh has owners)")
        self.owner = np.concatenate(own)
        self.caster = make_caster(np.vstack(verts), np.vstack(faces), backend, workers)

    def first(self, o: np.ndarray, d: np.ndarray, reach: np.ndarray) -> np.ndarray:
        """The tree index each ray meets first before ``reach`` (m), −1 for none."""
        out = np.full(len(o), -1, np.int64)
        if len(o):
            tri, t = self.caster.first_hit(np.ascontiguousarray(o), np.ascontiguousarray(d))
            hit = (tri >= 0) & (t < reach)
            out[hit] = self.owner[tri[hit]]
        return out


def attribute_hour(scene: Scene, state: SkyState, params: EngineParams,
                   grids: list[str] | None = None, owners: set[str] | None = None,
                   seed: int | None = None, options: TraceOptions = DEFAULT_OPTIONS
                   ) -> dict[str, TreeAttribution]:
    """The light each tree of ``owners`` (default every tree of ``scene``) removes from each
    sensor of ``grids`` (default all) at hour ``state`` (see the module doc)."""
    if options.sun_disc:
        raise EngineError("tree attribution traces a point sun (sun_disc = False)")
    names = [o for o in scene.owners() if owners is None or o in owners]
    if not names:
        raise EngineError("no tree faces to attribute light to (no mesh has owners)")
    workers = int(getattr(params, "workers", 2) or 1)
    geo = scene_geometry(scene, options.backend, workers)
    eps = options.epsilon if options.epsilon is not None else max(1e-5, 2e-6 * geo.size)
    opts = replace(options, epsilon=eps)
    bare = scene.without_owners(set(names))
    with_t, grid_names = _tracer(scene, state, params, grids, opts)
    without_t, _ = _tracer(bare, state, params, grid_names, opts)
    crowns = _Crowns(scene, names, options.backend, workers)
    seed = params.seed if seed is None else seed
    return {g: _attribute_grid(with_t, without_t, crowns, len(names), scene.grids[g],
                               grid_rays(params, g), _grid_seed(seed, g), params.sampling,
                               names)
            for g in grid_names}


def _attribute_grid(with_t: _Tracer, without_t: _Tracer, crowns: _Crowns, n_own: int,
                    grid: SensorGrid, n_paths: int, rng: np.random.Generator, sampling: str,
                    names: list[str]) -> TreeAttribution:
    pts, nrm = grid.points, grid.normals
    n_s = len(pts)
    direct_w = with_t.sensor_sun(pts, nrm)
    direct_o = without_t.sensor_sun(pts, nrm)
    sun_tree = np.full(n_s, -1, np.int64)
    lit = direct_o > 0
    if lit.any():
        sun = np.broadcast_to(without_t.sun, (int(lit.sum()), 3))
        sun_tree[lit] = crowns.first(pts[lit], sun, np.full(int(lit.sum()), np.inf))
    removed = np.zeros((n_own, n_s))
    gone = direct_o - direct_w
    at = sun_tree >= 0
    np.add.at(removed, (sun_tree[at], np.flatnonzero(at)), gone[at])
    unattributed = np.where(at, 0.0, gone)
    var = np.zeros((n_own, n_s))
    if with_t.max_bounces <= 0:
        return TreeAttribution(names, removed, np.sqrt(var), GridResult(direct_w, np.zeros(n_s)),
                               GridResult(direct_o, np.zeros(n_s)), unattributed)
    n_paths = max(1, int(n_paths))
    total = n_s * n_paths
    first = FirstDirections(n_s, n_paths, rng) if sampling == "sobol" else None
    key = stream_key(rng)
    r = first.r if first is not None else 1
    cells = n_s * r
    sums = np.zeros(n_own * cells)       # per tree and (sensor, replicate): Σ differences
    squares = np.zeros(n_own * n_s)      # per tree and sensor: Σ differences² (random sampling)
    counts = np.zeros(cells)
    loose = np.zeros(n_s)
    tallies = (SensorTally(n_s, 1, first), SensorTally(n_s, 1, first))
    batch = max(1, int(with_t.opts.batch_paths))
    for start in range(0, total, batch):
        pid = np.arange(start, min(total, start + batch))
        sensor = pid // n_paths
        dirs = None
        if first is not None:
            u = first.uniforms(pid)
            dirs = cosine_directions(u[:, 0], u[:, 1], nrm[sensor])
        acc_w = with_t.paths(pts[sensor], nrm[sensor], PathStreams(key, pid.astype(np.uint64)),
                             dirs=dirs)
        tree = np.full(len(pid), -1, np.int64)

        def meet(path: np.ndarray, o: np.ndarray, d: np.ndarray, reach: np.ndarray,
                 tree: np.ndarray = tree) -> None:
            ask = (tree[path] < 0) & (reach > 0)
            if ask.any():
                tree[path[ask]] = crowns.first(o[ask], d[ask], reach[ask])

        acc_o = without_t.paths(pts[sensor], nrm[sensor], PathStreams(key, pid.astype(np.uint64)),
                                dirs=dirs, segments=meet)
        tallies[0].add(pid, sensor, math.pi * acc_w[:, None])
        tallies[1].add(pid, sensor, math.pi * acc_o[:, None])
        diff = math.pi * (acc_o - acc_w)
        cell = sensor * r + (first.replicate(pid) if first is not None else 0)
        counts += np.bincount(cell, minlength=cells)
        named = tree >= 0
        sums += np.bincount(tree[named] * cells + cell[named], diff[named],
                            minlength=n_own * cells)
        squares += np.bincount(tree[named] * n_s + sensor[named], diff[named] ** 2,
                               minlength=n_own * n_s)
        loose += np.bincount(sensor[~named], diff[~named], minlength=n_s)
    per = sums.reshape(n_own, n_s, r)
    cnt = counts.reshape(n_s, r)
    n = cnt.sum(axis=1)
    removed += per.sum(axis=2) / n
    unattributed += loose / n
    if first is not None:
        se = np.stack([replicate_stderr(per[i], cnt) for i in range(n_own)])
    else:
        mean = per[:, :, 0] / n
        m2 = squares.reshape(n_own, n_s) - n * mean ** 2
        se = np.sqrt(np.maximum(m2, 0.0) / np.maximum(n - 1.0, 1.0) / n)
    (res_w,), (res_o,) = tallies[0].results(direct_w), tallies[1].results(direct_o)
    return TreeAttribution(names, removed, se, res_w, res_o, unattributed)
