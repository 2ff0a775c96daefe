"""Which tree: the light each tree takes from each sensor, attributed while tracing.

What is attributed: to each tree i, the light its removal alone would give back,
``E(scene without tree i) − E(scene)`` (lux; positive = the tree takes light) — the change a
user sees when that tree is felled. It is estimated on *paired paths*: every trace below uses
the same path streams (:mod:`.streams`: each draw is a hash of the path's number and its place
in the program) and the same Sobol' first directions, so two traces of a path are the same
path until it meets a face that one scene has and the other has not.

1. The scene is traced as it is (``with_trees``: the engine's ordinary trace,
   :func:`radtree.engines.numpy.tracing.trace`, to the last bit) and without the faces of
   every attributed tree (``without``, :meth:`radtree.scene.Scene.without_owners`), at one
   origin offset ε (the with-trees scene's).
2. While both are traced, each ray of a path — every segment up to the surface it reaches
   (∞ when it escapes) and every shadow ray towards the sun (whole) — is tested against each
   tree's bounding box (its leaves' and trunk's faces). A path whose rays cross no box meets
   no tree: its two traces are the same path (``unattributed`` checks it: 0 exactly), and a
   tree whose box neither trace of a path crosses changes nothing on it.
3. A path whose two traces cross the box of one tree i only: without tree i it is the
   tree-less path (it meets no other tree), so its difference ``π (L_without − L_with)`` is
   tree i's, exactly.
4. A path whose traces cross the boxes of several trees is traced once more for each of them,
   i, in the scene without i alone (the with-trees scene with i's faces skipped: the
   tree-less scene's and the other crowns' ray casters, :class:`_SkipOne`), and
   ``π (L_without i − L_with)`` is tree i's. A sensor's own direct sun (exact, no path) is
   treated the same way.

Overlapping crowns: each tree gets what removing it *alone* gives back, so light that two
crowns both stop (either one would) is given to neither — the trees' shares of a sensor's
change ``without − with_trees`` then add up to less than 1 (more than 1 where one tree's leaves
light a sensor that another shades), and the remainder is the light they take jointly.
Removing one tree and re-tracing (``benchmarks/tree_impact.py``) estimates the same quantity.

Standard errors: from the spread of the Sobol' replicates' means of each tree's path
differences (the other paths counted 0), or the per-path spread with ``random`` sampling — as
the engine's own (:mod:`.qmc`, :mod:`.tally`). Cost: two traces, a box test per ray of both
traces, and one more trace of the paths that cross several boxes, per box crossed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from radtree.config import EngineParams
from radtree.engines.base import GridResult, TreeAttribution
from radtree.engines.common.geometry import Geometry, Optics, scene_optics, triangle_frames
from radtree.engines.common.raycast import RayCaster, make_caster
from radtree.engines.common.sampling import cosine_directions
from radtree.engines.common.streams import PathStreams, stream_key
from radtree.engines.numpy.engine import DEFAULT_OPTIONS, TraceOptions, _Tracer, scene_geometry
from radtree.engines.numpy.qmc import FirstDirections, replicate_stderr
from radtree.engines.numpy.tally import SensorTally
from radtree.engines.numpy.tracing import _grid_seed, _tracer, grid_rays
from radtree.errors import EngineError
from radtree.light.sky import SkyState
from radtree.scene import Scene, SensorGrid

__all__ = ["attribute_hour"]

_BOX_CHUNK = 1 << 13   # rays per box test (rays × trees booleans at a time)


class _Crowns:
    """The attributed trees' faces alone: triangles (material index in ``names``), the tree
    of each, each tree's bounding box and a ray caster."""

    def __init__(self, scene: Scene, owners: list[str], names: list[str], backend: str,
                 workers: int):
        index = {o: i for i, o in enumerate(owners)}
        mat = {n: i for i, n in enumerate(names)}
        verts, faces, own, mats, off = [], [], [], [], 0
        for m in scene.solid_meshes():
            if m.owners is None:
                continue
            keep = np.isin(m.owners, owners)
            if not keep.any():
                continue
            verts.append(m.vertices)
            faces.append(m.faces[keep] + off)
            own.append(np.array([index[o] for o in m.owners[keep]], np.int64))
            mats.append(np.full(int(keep.sum()), mat[m.material], np.int64))
            off += len(m.vertices)
        if not faces:
            raise EngineError("no tree faces to attribute light to (no mesh has owners)")
        self.vertices, self.faces = np.vstack(verts), np.vstack(faces)
        self.owner, self.material = np.concatenate(own), np.concatenate(mats)
        tris = self.vertices[self.faces]
        n = len(owners)
        self.lo = np.full((n, 3), np.inf)
        self.hi = np.full((n, 3), -np.inf)
        np.minimum.at(self.lo, self.owner, tris.min(axis=1))
        np.maximum.at(self.hi, self.owner, tris.max(axis=1))
        self.caster = make_caster(self.vertices, self.faces, backend, workers)

    def boxes(self, o: np.ndarray, d: np.ndarray, reach: np.ndarray) -> np.ndarray:
        """(rays, trees) True where the ray segment [0, reach) crosses the tree's box."""
        out = np.zeros((len(o), len(self.lo)), bool)
        pad = 1e-6 * max(1.0, float(np.abs(self.hi).max()))
        lo, hi = self.lo - pad, self.hi + pad
        for s in range(0, len(o), _BOX_CHUNK):
            oo, dd, rr = o[s:s + _BOX_CHUNK], d[s:s + _BOX_CHUNK], reach[s:s + _BOX_CHUNK]
            # the slabs one axis at a time; a NaN entry (a ray in a slab's plane, parallel to
            # it) leaves near / far as they are (fmax / fmin skip NaN)
            near = np.full((len(oo), len(lo)), -np.inf)
            far = np.full((len(oo), len(lo)), np.inf)
            with np.errstate(divide="ignore", invalid="ignore"):
                for a in range(3):
                    inv = (1.0 / dd[:, a])[:, None]
                    t1 = (lo[None, :, a] - oo[:, a, None]) * inv
                    t2 = (hi[None, :, a] - oo[:, a, None]) * inv
                    np.fmax(near, np.minimum(t1, t2), out=near)
                    np.fmin(far, np.maximum(t1, t2), out=far)
            out[s:s + _BOX_CHUNK] = (near <= far) & (far >= 0.0) & (near < rr[:, None])
        return out


class _SkipOne:
    """The ray caster of the with-trees scene without one tree: the nearest of the tree-less
    scene's hit and the crowns' first hit that is not that tree's (each of its faces met is
    passed through and the query resumed behind it). Triangles: the tree-less scene's, then
    the crowns' (offset by ``n_open``)."""

    name = "skip-one"
    rays_cast = 0

    def __init__(self, bare: RayCaster, crowns: _Crowns, n_open: int, skip: int, eps: float):
        self.bare, self.crowns, self.n_open, self.skip, self.eps = bare, crowns, n_open, skip, eps

    def first_hit(self, origins: np.ndarray, directions: np.ndarray, parallel: bool = True
                  ) -> tuple[np.ndarray, np.ndarray]:
        tri, t = self.bare.first_hit(origins, directions, parallel)
        t = np.where(tri >= 0, t, np.inf)
        ct, cd = self.crowns.caster.first_hit(origins, directions, parallel)
        cd = np.where(ct >= 0, cd, np.inf)
        base = np.zeros(len(ct))
        again = (ct >= 0) & (self.crowns.owner[np.maximum(ct, 0)] == self.skip) & (cd < t)
        for _ in range(4096):
            if not again.any():
                break
            i = again.nonzero()[0]
            base[i] += cd[i] + self.eps
            o = origins[i] + base[i, None] * directions[i]
            ct2, cd2 = self.crowns.caster.first_hit(np.ascontiguousarray(o),
                                                    np.ascontiguousarray(directions[i]),
                                                    parallel)
            ct[i], cd[i] = ct2, np.where(ct2 >= 0, cd2, np.inf)
            again[:] = False
            again[i] = ((ct2 >= 0) & (self.crowns.owner[np.maximum(ct2, 0)] == self.skip)
                        & (base[i] + cd[i] < t[i]))
        dist = base + cd
        crown = (ct >= 0) & (dist < t)
        out = np.where(crown, ct + self.n_open, tri)
        return out.astype(np.int64), np.where(crown, dist, np.where(tri >= 0, t, 0.0))


def _without_one_geometry(bare: Geometry, crowns: _Crowns, names: list[str], size: float
                          ) -> Geometry:
    """The with-trees scene's triangles as the tree-less scene's then the crowns' (material
    indices in ``names``, the with-trees scene's), without a caster yet (:class:`_SkipOne`)."""
    g = Geometry.__new__(Geometry)
    index = {n: i for i, n in enumerate(names)}
    remap = np.array([index[n] for n in bare.material_names], np.int64)
    cn, cv, cc = triangle_frames(crowns.vertices, crowns.faces)
    g.material_names = names
    g.vertices = np.vstack([bare.vertices, crowns.vertices])
    g.faces = np.vstack([bare.faces, crowns.faces + len(bare.vertices)])
    g.tri_material = np.concatenate([remap[bare.tri_material], crowns.material])
    g.normals = np.vstack([bare.normals, cn])
    g.v0 = np.ascontiguousarray(np.vstack([bare.v0, cv]))
    g.centroids = np.vstack([bare.centroids, cc])
    g.normals_t = np.ascontiguousarray(g.normals.T)
    g.v0_t = np.ascontiguousarray(g.v0.T)
    g.size = size
    g.media = bare.media   # turbid crowns carry no tree ids: never attributed
    return g


@dataclass
class _Hour:
    """What every grid of one hour shares: the tracers, the crowns and the per-tree scenes."""

    state: SkyState
    params: EngineParams
    opts: TraceOptions
    with_t: _Tracer
    bare_t: _Tracer
    crowns: _Crowns
    joint: Geometry
    optics: Optics

    def without(self, tree: int) -> _Tracer:
        """The tracer of the with-trees scene without tree ``tree``."""
        g = replace_caster(self.joint, _SkipOne(self.bare_t.geo.caster, self.crowns,
                                                len(self.bare_t.geo.faces), tree,
                                                self.with_t.eps))
        return _Tracer(g, self.optics, self.state, self.params, self.opts)


def replace_caster(geo: Geometry, caster: RayCaster) -> Geometry:
    """A shallow copy of ``geo`` with another ray caster."""
    g = Geometry.__new__(Geometry)
    g.__dict__.update(geo.__dict__)
    g.caster = caster
    return g


def attribute_hour(scene: Scene, state: SkyState, params: EngineParams,
                   grids: list[str] | None = None, owners: set[str] | None = None,
                   seed: int | None = None, options: TraceOptions = DEFAULT_OPTIONS
                   ) -> dict[str, TreeAttribution]:
    """The light each tree of ``owners`` (default every tree of ``scene``) takes from each
    sensor of ``grids`` (default all) at hour ``state``: what removing it alone gives back
    (see the module doc)."""
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
    bare_t, _ = _tracer(bare, state, params, grid_names, opts)
    crowns = _Crowns(scene, names, geo.material_names, options.backend, workers)
    hour = _Hour(state, params, opts, with_t, bare_t, crowns,
                 _without_one_geometry(bare_t.geo, crowns, geo.material_names, geo.size),
                 scene_optics(scene, state, geo.material_names))
    seed = params.seed if seed is None else seed
    return {g: _attribute_grid(hour, scene.grids[g], grid_rays(params, g),
                               _grid_seed(seed, g), params.numpy.sampling, names)
            for g in grid_names}


class _Sums:
    """The paired differences (without − with trees, lux) of one grid's paths, summed per
    tree and (sensor, replicate) — ``r`` replicates of the Sobol' first directions
    (``first``), one with random sampling — with their squares per tree and sensor (random
    sampling's standard error), the paths per cell and the differences no tree took."""

    def __init__(self, n_own: int, n_s: int, n_paths: int, first: FirstDirections | None):
        self.n_own, self.n_s, self.n_paths, self.first = n_own, n_s, n_paths, first
        self.r = first.r if first is not None else 1
        self.cells = n_s * self.r
        self.sums = np.zeros(n_own * self.cells)   # per tree and (sensor, replicate)
        self.squares = np.zeros(n_own * n_s)       # per tree and sensor
        self.counts = np.zeros(self.cells)
        self.loose = np.zeros(n_s)

    def cell_of(self, pid: np.ndarray) -> np.ndarray:
        return pid // self.n_paths * self.r + (
            self.first.replicate(pid) if self.first is not None else 0)

    def add(self, tree: np.ndarray, pid: np.ndarray, diff: np.ndarray) -> None:
        n_own, cells, n_s = self.n_own, self.cells, self.n_s
        self.sums[:] += np.bincount(tree * cells + self.cell_of(pid), diff,
                                    minlength=n_own * cells)
        self.squares[:] += np.bincount(tree * n_s + pid // self.n_paths, diff ** 2,
                                       minlength=n_own * n_s)

    def directions(self, pid: np.ndarray, nrm: np.ndarray) -> np.ndarray | None:
        """The paths' first directions (None: cosine samples drawn by the tracer)."""
        if self.first is None:
            return None
        u = self.first.uniforms(pid)
        return cosine_directions(u[:, 0], u[:, 1], nrm[pid // self.n_paths])

    def stderr(self) -> np.ndarray:
        """(trees, sensors) standard errors of the removed light."""
        per = self.sums.reshape(self.n_own, self.n_s, self.r)
        cnt = self.counts.reshape(self.n_s, self.r)
        n = cnt.sum(axis=1)
        if self.first is not None:
            return np.stack([replicate_stderr(per[i], cnt) for i in range(self.n_own)])
        mean = per[:, :, 0] / n
        m2 = self.squares.reshape(self.n_own, self.n_s) - n * mean ** 2
        return np.sqrt(np.maximum(m2, 0.0) / np.maximum(n - 1.0, 1.0) / n)


def _direct_sun_part(hour: _Hour, pts: np.ndarray, nrm: np.ndarray, n_own: int
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict]:
    """The sensors' direct sun with and without the trees, the light removed given to the
    one tree whose box the sun ray crosses (trees, sensors), what no box took, and per tree
    the sensors whose sun ray crosses several boxes (traced without each later)."""
    with_t, bare_t, crowns = hour.with_t, hour.bare_t, hour.crowns
    n_s = len(pts)
    direct_w = with_t.sensor_sun(pts, nrm)
    direct_o = bare_t.sensor_sun(pts, nrm)
    met_sun = np.zeros((n_s, n_own), bool)
    lit = direct_o > 0
    if lit.any():
        met_sun[lit] = crowns.boxes(pts[lit], np.broadcast_to(bare_t.sun, (int(lit.sum()), 3)),
                                    np.full(int(lit.sum()), np.inf))
    removed = np.zeros((n_own, n_s))
    gone = direct_o - direct_w
    count = met_sun.sum(axis=1)
    one = count == 1
    removed[met_sun[one].argmax(axis=1), np.flatnonzero(one)] = gone[one]
    unattributed = np.where(count == 0, gone, 0.0)
    later: dict[int, list[np.ndarray]] = {}   # tree → sensors whose sun crosses several boxes
    for sensor_ in np.flatnonzero(count > 1):
        for tree_ in np.flatnonzero(met_sun[sensor_]):
            later.setdefault(int(tree_), []).append(np.array([sensor_]))
    return direct_w, direct_o, removed, unattributed, later


def _paired_paths(hour: _Hour, grid: SensorGrid, sums: _Sums, key: int,
                  tallies: tuple[SensorTally, SensorTally]
                  ) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Every path traced with and without the trees (the same streams), each difference
    given to the one tree whose box it crossed (or none); the paths that crossed several
    boxes: (path ids, with-trees radiance, boxes crossed)."""
    with_t, bare_t, crowns = hour.with_t, hour.bare_t, hour.crowns
    pts, nrm, n_paths = grid.points, grid.normals, sums.n_paths
    several: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
    total = len(pts) * n_paths
    batch = max(1, int(with_t.opts.batch_paths))
    for start in range(0, total, batch):
        pid = np.arange(start, min(total, start + batch))
        sensor = pid // n_paths
        dirs = sums.directions(pid, nrm)
        met = np.zeros((len(pid), sums.n_own), bool)

        def meet(path: np.ndarray, o: np.ndarray, d: np.ndarray, reach: np.ndarray,
                 met: np.ndarray = met) -> None:
            ask = reach > 0
            if ask.any():
                met[path[ask]] |= crowns.boxes(o[ask], d[ask], reach[ask])

        acc_w = with_t.paths(pts[sensor], nrm[sensor], PathStreams(key, pid.astype(np.uint64)),
                             dirs=dirs, segments=meet)
        acc_o = bare_t.paths(pts[sensor], nrm[sensor], PathStreams(key, pid.astype(np.uint64)),
                             dirs=dirs, segments=meet)
        tallies[0].add(pid, sensor, math.pi * acc_w[:, None])
        tallies[1].add(pid, sensor, math.pi * acc_o[:, None])
        diff = math.pi * (acc_o - acc_w)
        sums.counts += np.bincount(sums.cell_of(pid), minlength=sums.cells)
        k = met.sum(axis=1)
        single = k == 1
        sums.add(met[single].argmax(axis=1), pid[single], diff[single])
        sums.loose += np.bincount(sensor[k == 0], diff[k == 0], minlength=sums.n_s)
        if (k > 1).any():
            several.append((pid[k > 1], acc_w[k > 1], met[k > 1]))
    return several


def _without_each(hour: _Hour, grid: SensorGrid, sums: _Sums, key: int,
                  several: list[tuple[np.ndarray, np.ndarray, np.ndarray]]) -> None:
    """The paths that crossed several trees' boxes, traced again without each of them."""
    pts, nrm, n_paths = grid.points, grid.normals, sums.n_paths
    crossed = {int(t) for _, _, m in several for t in np.flatnonzero(m.any(axis=0))}
    for tree in sorted(crossed):
        tracer = hour.without(tree)
        for pid, acc_w, m in several:
            sel = m[:, tree]
            if not sel.any():
                continue
            p = pid[sel]
            acc_i = tracer.paths(pts[p // n_paths], nrm[p // n_paths],
                                 PathStreams(key, p.astype(np.uint64)),
                                 dirs=sums.directions(p, nrm))
            sums.add(np.full(len(p), tree), p, math.pi * (acc_i - acc_w[sel]))


def _attribute_grid(hour: _Hour, grid: SensorGrid, n_paths: int, rng: np.random.Generator,
                    sampling: str, names: list[str]) -> TreeAttribution:
    """The grid's attribution: the direct sun, then (with diffuse bounces) ``n_paths``
    paired paths per sensor and the paths that crossed several trees again without each."""
    pts, nrm = grid.points, grid.normals
    n_own, n_s = len(names), len(pts)
    direct_w, direct_o, removed, unattributed, later = _direct_sun_part(hour, pts, nrm, n_own)
    if hour.with_t.max_bounces <= 0:
        _direct_without_one(hour, later, pts, nrm, direct_w, removed)
        return TreeAttribution(names, removed, np.zeros((n_own, n_s)),
                               GridResult(direct_w, np.zeros(n_s)),
                               GridResult(direct_o, np.zeros(n_s)), unattributed)
    n_paths = max(1, int(n_paths))
    first = FirstDirections(n_s, n_paths, rng) if sampling == "sobol" else None
    key = stream_key(rng)
    sums = _Sums(n_own, n_s, n_paths, first)
    tallies = (SensorTally(n_s, 1, first), SensorTally(n_s, 1, first))
    several = _paired_paths(hour, grid, sums, key, tallies)
    _without_each(hour, grid, sums, key, several)
    _direct_without_one(hour, later, pts, nrm, direct_w, removed)
    n = sums.counts.reshape(n_s, sums.r).sum(axis=1)
    removed += sums.sums.reshape(n_own, n_s, sums.r).sum(axis=2) / n
    unattributed += sums.loose / n
    (res_w,), (res_o,) = tallies[0].results(direct_w), tallies[1].results(direct_o)
    return TreeAttribution(names, removed, sums.stderr(), res_w, res_o, unattributed)


def _direct_without_one(hour: _Hour, later: dict[int, list[np.ndarray]], pts: np.ndarray,
                        nrm: np.ndarray, direct_w: np.ndarray, removed: np.ndarray) -> None:
    """The direct sun of the sensors whose sun ray crosses several trees' boxes, without each
    of those trees (``-ab 0`` traces)."""
    for i, parts in later.items():
        s = np.concatenate(parts)
        removed[i, s] += hour.without(i).sensor_sun(pts[s], nrm[s]) - direct_w[s]
