"""The NumPy engine's C kernel (``radtree.engines.common._kernel``) gives the NumPy code's numbers
to the bit: the shadow-ray loop with both kernels on the same rays, whole traces with both,
the conversion into Embree's float32 frame; ``RADTREE_KERNEL`` selects the kernel.

The kernel is optional (built at install when a C compiler is at hand); where a compiler is,
it must have been built.
"""

from __future__ import annotations

import shutil
import sysconfig

import numpy as np
import pytest

from radtree.config import EngineParams
from radtree.engines.common import kernel
from radtree.engines.common.raycast import EmbreeCaster, embree_available
from radtree.engines.common.streams import PathStreams
from radtree.engines.numpy import shadow, tracing
from radtree.engines.numpy.engine import DEFAULT_OPTIONS, TraceOptions, describe
from radtree.engines.numpy.scenes import dome_slats, sky_state
from radtree.optics import Plastic, Trans
from radtree.scene import Scene, SensorGrid, quad

built = kernel._load()[0] is not None
needs_kernel = pytest.mark.skipif(not built or not embree_available(),
                                  reason="the C kernel is not built or embreex is missing")


def test_kernel_is_built_where_a_compiler_is():
    cc = (sysconfig.get_config_var("CC") or "cc").split()[0]
    if shutil.which(cc) is None:
        pytest.skip(f"no C compiler ({cc})")
    assert built, f"radtree.engines.common._kernel is {kernel._load()[1]}: pip install -e ."


def test_radtree_kernel_selects_the_kernel(monkeypatch):
    monkeypatch.setenv("RADTREE_KERNEL", "numpy")
    assert kernel.kernel() is None and kernel.name() == "numpy"
    assert "shadow-ray kernel numpy (RADTREE_KERNEL=numpy)" in kernel.describe()
    monkeypatch.setenv("RADTREE_KERNEL", "fortran")
    with pytest.raises(ValueError, match="RADTREE_KERNEL"):
        kernel.kernel()
    monkeypatch.setenv("RADTREE_KERNEL", "c")
    if built:
        assert kernel.name() == "c"
        if embree_available():
            assert "shadow-ray kernel c" in describe()
    else:
        with pytest.raises(ImportError, match="RADTREE_KERNEL=c"):
            kernel.kernel()


def _scene(states: int = 1) -> tuple[Scene, list]:
    """Leafy slats in a dome (specular transmittance 0.1: shadow rays cross several layers and
    go faint, Russian roulette) over a ground."""
    slats = dome_slats("crown", "leaf", count=400, radius=2.0, centre=np.array([0.0, 0.0, 3.0]),
                       facade_normal=np.array([0.0, 1.0, 0.0]), size=0.3, inclination_deg=30,
                       rng=np.random.default_rng(2), inner_radius=0.3)
    ground = dome_slats("ground", "ground", count=30, radius=6.0, centre=np.array([0, 0, -6.5]),
                        facade_normal=np.array([0.0, 1.0, 0.0]), size=2.0, inclination_deg=0,
                        rng=np.random.default_rng(3))
    pts = np.array([[0.0, 0.0, 1.0], [0.5, -0.3, 2.5], [-0.4, 0.2, 3.6], [0.1, 0.1, 0.2]])
    grid = SensorGrid("g", pts, np.tile([0.0, 0.0, 1.0], (len(pts), 1)))
    scene = Scene([slats, ground], {"leaf": Trans("leaf", 0.1, 0.3, 0.1),
                                    "ground": Plastic("ground", 0.2)}, {"g": grid})
    hours = [sky_state("perez", altitude=a, azimuth=az, dni=60000, dhi=12000,
                       ground_reflectance=0.2, time=t)
             for a, az, t in [(50, 140, "12:00"), (30, 100, "09:00"), (65, 200, "14:00")]]
    return scene, hours[:states]


def _both(monkeypatch, run):
    """``run()`` with the NumPy code, then with the C kernel."""
    monkeypatch.setenv("RADTREE_KERNEL", "numpy")
    ref = run()
    monkeypatch.setenv("RADTREE_KERNEL", "c")
    return ref, run()


@needs_kernel
@pytest.mark.parametrize("states", [1, 3])
def test_shadow_rays_identical_with_both_kernels(monkeypatch, states):
    """Transmittance of 20 000 shadow rays through the slats (roulette drawn from the same
    generator: the same number of draws), towards one point sun or each ray's own hour."""
    scene, hours = _scene(states)
    rng = np.random.default_rng(5)
    k = 20000
    o = rng.normal(scale=1.5, size=(k, 3)) + [0.0, 0.0, 2.0]
    hour = rng.integers(0, states, k)

    def run():
        tr, _ = tracing._tracer(scene, hours[0], EngineParams(rays=8), None, DEFAULT_OPTIONS,
                                hours[1:])
        assert isinstance(tr.caster, EmbreeCaster) and not tr.sun_grazing
        sun = tr.suns if states > 1 else tr.sun[None, :]
        draws = np.random.default_rng(11)
        out = [shadow.transmittance(tr, o, sun.take(hour, axis=0) if states > 1 else
                                    np.broadcast_to(sun[0], (k, 3)), draws,
                                    hour=hour if states > 1 else 0)]
        for h in range(states):  # one point sun for all rays (the sensors' direct sun)
            out.append(shadow.transmittance(tr, o, np.broadcast_to(sun[h], (k, 3)), draws,
                                            hour=h))
        out.append(shadow.transmittance(tr, o, np.broadcast_to(sun[0], (k, 3)), None, hour=0))
        out.append(draws.random(4))  # as many roulette draws taken
        return out

    ref, got = _both(monkeypatch, run)
    first = ref[0]
    assert 0.2 < np.mean(first == 1.0) < 0.9 and np.any((first > 0) & (first < 1))
    for a, b in zip(ref, got, strict=True):
        assert np.array_equal(a, b)


@needs_kernel
@pytest.mark.parametrize("workers", [1, 2])
def test_traces_identical_with_both_kernels(monkeypatch, workers):
    """Whole traces: one hour, three hours in one batch, the -ab ladder (point sun), and the
    sampled sun disc (the NumPy path either way)."""
    scene, hours = _scene(3)
    p = EngineParams(rays=300, max_bounces=4, seed=3, workers=workers)
    opts = TraceOptions(min_part_paths=64, batch_paths=600)

    def run():
        r = [tracing.trace(scene, hours[0], p, options=opts)["g"]]
        r += [x["g"] for x in tracing.trace_states(scene, hours, p, options=opts)]
        lad = tracing.trace_bounce_ladder(scene, hours[1], p, [1, 2, 4], options=opts)
        r += [lad[ab]["g"] for ab in (1, 2, 4)]
        r.append(tracing.trace(scene, hours[2], p, options=TraceOptions(sun_disc=True))["g"])
        return r

    ref, got = _both(monkeypatch, run)
    for a, b in zip(ref, got, strict=True):
        assert np.array_equal(a.lux, b.lux) and np.array_equal(a.stderr, b.stderr)
    assert np.all(ref[0].lux > 0)


@needs_kernel
def test_frame_conversion_equals_numpy():
    """Origins into Embree's float32 frame: float32, − origin in float64, × scale, float32 —
    the kernel's ``frame`` and ``cross`` against NumPy's casts (a compiler that folds the
    float32 round trip away fails here)."""
    k_mod = kernel._load()[0]
    rng = np.random.default_rng(8)
    o = rng.normal(size=(3, 5000)) * 10.0 ** rng.uniform(-3, 3, (3, 5000))
    frame = np.array([-40.0, 0.0, -1.5, 1.1930999725437872])
    ref = np.array(o, np.float32)
    ref = np.multiply(np.subtract(ref, frame[:3, None], dtype=np.float64), frame[3], out=ref,
                      casting="same_kind").T
    got = np.empty((5000, 3), np.float32)
    k_mod.frame(o, frame, got)
    assert np.array_equal(got, ref)
    k_mod.frame(np.ascontiguousarray(o.T).T, frame, got)  # (n, 3) rows seen as (3, n)
    assert np.array_equal(got, ref)


@needs_kernel
@pytest.mark.parametrize("states", [1, 3])
def test_crossing_equals_the_numpy_crossing(monkeypatch, states):
    """One ``cross`` + ``roulette`` on hits of given triangles: the next origins equal
    ``shadow.crossed_sun``'s (and so ``crossed``'s plane-distance arithmetic) to the bit, their
    float32 copies NumPy's conversion, the roulette NumPy's ``u · R < v``, the compaction
    ``(v > 0).nonzero()``'s order."""
    monkeypatch.setenv("RADTREE_KERNEL", "c")
    k_mod = kernel.kernel()
    scene, hours = _scene(states)
    tr, _ = tracing._tracer(scene, hours[0], EngineParams(rays=8), None, DEFAULT_OPTIONS,
                            hours[1:])
    assert tr.tri_pack is not None and isinstance(tr.caster, EmbreeCaster)
    rng = np.random.default_rng(9)
    n = 6000
    tri = rng.integers(-1, tr.n_tri, n).astype(np.int32)  # -1: a miss
    o = np.ascontiguousarray((tr.geo.centroids[tri] + rng.normal(scale=0.3, size=(n, 3))).T)
    hour = rng.integers(0, states, n)
    vis = rng.choice([1.0, 0.5, 0.03, 0.01, 0.001, 0.0], n)
    idx = rng.permutation(n).astype(np.int64)
    hit = (tri >= 0).nonzero()[0]
    # NumPy: the transmittance loop's steps
    v = vis[idx[hit]] * tr.tri_ts[tri[hit]]
    faint = (v > 0) & (v < shadow.SHADOW_ROULETTE)
    u = rng.random(int(faint.sum()))
    v[faint] = np.where(u * shadow.SHADOW_ROULETTE < v[faint], shadow.SHADOW_ROULETTE, 0.0)
    go = hit[v > 0]
    sun = tr.suns if states > 1 else tr.sun[None, :]
    h = hour[go] if states > 1 else 0
    d = sun.take(hour[go], axis=0) if states > 1 else np.broadcast_to(sun[0], (len(go), 3))
    ref_o = shadow.crossed_sun(tr, o[:, go], d, tri[go].astype(np.intp), h)
    ref_vis = vis.copy()
    ref_vis[idx[hit]] = v
    ref32 = np.array(ref_o, np.float32)
    ref32 = np.multiply(np.subtract(ref32, tr.caster.frame[:3, None], dtype=np.float64),
                        tr.caster.frame[3], out=ref32, casting="same_kind").T
    # the kernel, in place
    kv, ki, ko = vis.copy(), idx.copy(), o.copy()
    hours = hour.astype(np.int64) if states > 1 else None
    o32 = np.empty((n, 3), np.float32)
    n_hit, m, n_faint = k_mod.cross(tri, ki, kv, shadow.SHADOW_ROULETTE, tr.tri_pack,
                                    tr.sun_cos, tr.n_tri, 0, hours, np.ascontiguousarray(sun),
                                    tr.eps, ko, tr.caster.frame, o32)
    assert (n_hit, n_faint) == (len(hit), len(u)) and m > len(go)
    m = k_mod.roulette(ki, kv, hours, ko, o32, m, u, shadow.SHADOW_ROULETTE)
    assert m == len(go) and 0 < m < len(hit)
    assert np.array_equal(ko[:, :m], ref_o)
    assert np.array_equal(o32[:m], ref32)
    assert np.array_equal(ki[:m], idx[go])
    assert np.array_equal(kv, ref_vis)
    if hours is not None:
        assert np.array_equal(hours[:m], hour[go])


@needs_kernel
def test_first_hit_distances_equal_plane_distance():
    """``distances`` (EmbreeCaster._chunk with the kernel) against ``plane_distance``: hits,
    misses (inf), grazing rays (the centroid's distance), a broadcast direction row."""
    from radtree.engines.common.raycast import plane_distance

    k_mod = kernel._load()[0]
    scene, _ = _scene()
    tr, _ = tracing._tracer(scene, _scene()[1][0], EngineParams(rays=8), None,
                            DEFAULT_OPTIONS)
    c = tr.caster
    assert isinstance(c, EmbreeCaster)
    rng = np.random.default_rng(4)
    n = 8000
    tri = rng.integers(-1, tr.n_tri, n).astype(np.int32)
    o = c._centroids[tri] + rng.normal(scale=0.5, size=(n, 3))
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    g = rng.random(n) < 0.05  # grazing: d in the triangle's plane
    d[g] = np.cross(c._normals[tri[g]], rng.normal(size=(int(g.sum()), 3)))
    d[g] /= np.linalg.norm(d[g], axis=1)[:, None]
    for dirs in (d, np.broadcast_to(d[0], (n, 3))):
        idx, t = np.empty(n, np.int64), np.empty(n)
        assert k_mod.distances(tri, o, dirs, c._rows, c._centroids, idx, t) == (tri >= 0).sum()
        hit = (tri >= 0).nonzero()[0]
        ref = np.full(n, np.inf)
        ref[hit] = plane_distance(c._v0, c._normals, c._centroids, o[hit],
                                  np.ascontiguousarray(dirs[hit]), tri[hit].astype(np.intp))
        assert np.array_equal(idx, tri) and np.array_equal(t, ref)
        assert np.any(t == 0) and np.any(np.isinf(t)) and np.any(t > 0)


@needs_kernel
@pytest.mark.parametrize("states", [1, 3])
def test_surface_equals_the_path_loop_arithmetic(states):
    """``surface`` against the path loop's NumPy lines: hit points ``t[:, None] * d + o``,
    cosines by einsum, facing normals by ``where``, event coefficients by ``take``."""
    k_mod = kernel._load()[0]
    scene, hours = _scene(states)
    tr, _ = tracing._tracer(scene, hours[0], EngineParams(rays=8), None, DEFAULT_OPTIONS,
                            hours[1:])
    assert tr.tri_pack is not None
    rng = np.random.default_rng(6)
    n = 7000
    tri = rng.integers(0, tr.n_tri, n)
    t = rng.random(n) * 10.0 ** rng.uniform(-4, 1, n)
    o = rng.normal(scale=3.0, size=(n, 3))
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    hour = rng.integers(0, states, n) if states > 1 else None
    p, nf, cosd, coef = np.empty((n, 3)), np.empty((n, 3)), np.empty(n), np.empty((4, n))
    k_mod.surface(tri, t, o, d, tr.tri_pack, tr.tri_coef_t if hour is None else
                  tr.tri_coefs_flat_t, hour, tr.n_tri, p, nf, cosd, coef)
    ref_p = t[:, None] * d
    ref_p += o
    ng = tr.geo.normals.take(tri, axis=0)
    ref_cos = np.einsum("ij,ij->i", d, ng)
    ref_nf = np.where((ref_cos < 0)[:, None], ng, -ng)
    ref_coef = (tr.tri_coef_t.take(tri, axis=1) if hour is None else
                tr.tri_coefs_flat_t.take(hour * tr.n_tri + tri, axis=1))
    assert np.array_equal(p, ref_p) and np.array_equal(cosd, ref_cos)
    assert np.array_equal(nf, ref_nf) and np.array_equal(coef, ref_coef)
    assert np.any(ref_cos < 0) and np.any(ref_cos > 0)


@needs_kernel
@pytest.mark.parametrize("case", ["sun", "disc", "hours"])
def test_nee_equals_the_path_loop_arithmetic(case):
    """``nee`` against the path loop's NumPy lines: cosines by einsum, the weights
    ``where(cs > 0, rd cs, −td cs) / π`` (× each hour's direct normal lux), the rays with
    f > 0 and their shadow-ray origins ``nf · (ε sign cs) + p``."""
    import math

    k_mod = kernel._load()[0]
    rng = np.random.default_rng(12)
    n = 6000
    nf = rng.normal(size=(n, 3))
    nf /= np.linalg.norm(nf, axis=1)[:, None]
    p = rng.normal(scale=5.0, size=(n, 3))
    coef = rng.random((4, n)) * (rng.random((4, n)) < 0.8)
    rd, td = coef[0], coef[1]
    sun = np.array([0.3, -0.5, 0.81])
    sun /= np.linalg.norm(sun)
    sd = (np.broadcast_to(sun, (n, 3)) if case == "sun" else
          sun + rng.normal(scale=0.01, size=(n, 3)))
    hour = rng.integers(0, 3, n) if case == "hours" else None
    dnis = np.array([70000.0, 0.0, 31000.5])
    eps = 1.6e-4
    f, ni, so = np.empty(n), np.empty(n, np.int64), np.empty((n, 3))
    m = k_mod.nee(nf, sd, rd, td, dnis if hour is not None else None, hour, eps, p, f, ni, so)
    cs = np.einsum("ij,ij->i", nf, sd)
    ref_f = np.where(cs > 0, rd * cs, -td * cs) / math.pi
    if hour is not None:
        ref_f *= dnis[hour]
    ref_ni = (ref_f > 0).nonzero()[0]
    ref_so = nf.take(ref_ni, axis=0)
    ref_so *= (eps * np.sign(cs[ref_ni]))[:, None]
    ref_so += p.take(ref_ni, axis=0)
    assert np.array_equal(f, ref_f) and m == len(ref_ni) > 0
    assert np.array_equal(ni[:m], ref_ni) and np.array_equal(so[:m], ref_so)
    assert np.any(cs[ref_ni] < 0) and np.any(cs[ref_ni] > 0)


@needs_kernel
def test_paths_take_strided_inputs(monkeypatch):
    """A part of an interleaved batch split (every second path: strided points, normals, first
    directions and hour states) traces as its contiguous copy — inside a closed box, where
    every first ray hits and nothing is compacted before the first surface pass."""
    monkeypatch.setenv("RADTREE_KERNEL", "c")
    c = np.array([[-1.0, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                  [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]])
    faces = [(0, 1, 2, 3), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)]
    walls = [quad(f"w{i}", "wall", c[list(f)]) for i, f in enumerate(faces)]
    grid = SensorGrid("g", np.zeros((1, 3)), np.array([[0.0, 0.0, 1.0]]))
    _, hours = _scene(3)
    scene = Scene(walls, {"wall": Plastic("wall", 0.5)}, {"g": grid})
    tr, _ = tracing._tracer(scene, hours[0], EngineParams(rays=8, max_bounces=4), None,
                            DEFAULT_OPTIONS, hours[1:])
    rng = np.random.default_rng(4)
    n = 4000
    pts = rng.uniform(-0.5, 0.5, size=(n, 3))
    nrm = np.tile([0.0, 0.0, 1.0], (n, 1))
    dirs = rng.normal(size=(n, 3))
    dirs /= np.linalg.norm(dirs, axis=1)[:, None]
    hour = rng.integers(0, 3, n)
    ids = np.arange(0, n, 2, dtype=np.uint64)
    strided = tr.paths(pts[::2], nrm[::2], PathStreams(9, ids), dirs=dirs[::2], hour=hour[::2])
    copied = tr.paths(pts[::2].copy(), nrm[::2].copy(), PathStreams(9, ids),
                      dirs=dirs[::2].copy(), hour=hour[::2].copy())
    assert np.array_equal(strided, copied)
