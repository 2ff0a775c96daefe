"""Engine benchmarks: ray-casting speed, NumPy-engine wall time per hour, engine differences.

Prints (no timing assertions):

1. first-hit ray–triangle queries per second on a ~51 k-triangle slat cloud (Embree with 1 and 2
   threads, the NumPy BVH fallback on a smaller batch);
2. wall time of one hour of the NumPy engine on a louvers-like slat scene (3000 slats of 0.3 m
   inclined 30°, random azimuth, in a 4 m sensor dome on the façade of the Mendoza canyon;
   Perez sky + sun of 11:30) at the default budget, and on the Mendoza project's own louvers
   crown (``radtree.pipeline.assemble.make_scene``) when that builds;
3. the NumPy engine's ray throughput against raw Embree on the very same rays: every
   Embree query of one traced hour is recorded as handed to Embree, then replayed through
   embreex's ``EmbreeScene.run`` (the same float32 rays in trimesh's Embree frame, chunks of 65 536 over
   the same number of threads) and through the engine's ``EmbreeCaster.first_hit`` in one call
   (conversions and float64 distances included); the engine's rays/s over raw Embree's is the
   throughput ratio (Mendoza scenarios B and F, 12:30, 1 and 2 threads; and B's 7 hours in the
   same batches, as ``radtree simulate`` traces a scenario); also Embree's own CPU
   time inside the engine (``EmbreeScene.run`` timed where the engine calls it) as a share of
   the engine's CPU time, and which shadow-ray kernel ran (``RADTREE_KERNEL``: c or numpy);
4. when Radiance is available, the per-row relative difference NumPy − Radiance on the slat
   scene, with Radiance at ``-ab 8 -ad 8192 -as 0 -aa 0`` and with ambient super-sampling
   (``-as 4096``, biased low here); ``--with-defaults`` adds the project's ``-as 512 -aa 0.1``.

Run: ``.venv/bin/python benchmarks/engines.py [--quick] [--only throughput]``.
"""

from __future__ import annotations

import argparse
import os
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from radtree.config import EngineParams, Sensors, Street  # noqa: E402
from radtree.engines.common.raycast import BVHCaster, EmbreeCaster, embree_available  # noqa: E402
from radtree.engines.common.sampling import cosine_hemisphere  # noqa: E402
from radtree.engines.numpy import describe, trace  # noqa: E402
from radtree.engines.numpy.engine import DEFAULT_OPTIONS, scene_geometry  # noqa: E402
from radtree.engines.numpy.scenes import dome_slats, sky_state  # noqa: E402
from radtree.engines.radiance.binaries import find_radiance  # noqa: E402
from radtree.optics import Material, Trans  # noqa: E402
from radtree.scene import Mesh, Scene  # noqa: E402
from radtree.sensor_grid import facade_circle  # noqa: E402
from radtree.site.frame import FacadeFrame  # noqa: E402
from radtree.site.street import street_materials, street_meshes  # noqa: E402

FRAME = FacadeFrame(0.0)
SENSORS = Sensors()
CENTRE = FRAME.to_world(np.array([[SENSORS.x_m, 0.0, SENSORS.height_m]]))[0]
HOUR: dict[str, Any] = dict(altitude=61.18, azimuth=78.88, dni=70000, dhi=12000, ground_reflectance=0.3,
            time="11:30")


def slat_scene(count: int, radius: float = 4.0, seed: int = 2) -> Scene:
    mats: dict[str, Material] = dict(street_materials(Street()))
    mats["leaf"] = Trans("leaf", 0.11, 0.30, 0.10)
    slats = dome_slats("crown", "leaf", count=count, radius=radius, centre=CENTRE,
                       facade_normal=FRAME.normal, size=0.3, inclination_deg=30,
                       rng=np.random.default_rng(seed), inner_radius=0.6)
    return Scene(street_meshes(Street(), FRAME) + [slats], mats,
                 {"facade": facade_circle(SENSORS, FRAME)})


def rays_per_second(quick: bool) -> None:
    print("== first-hit ray queries ==")
    mesh: Mesh = dome_slats("cloud", "leaf", count=25600, radius=4.0, centre=CENTRE,
                            facade_normal=FRAME.normal, size=0.3, inclination_deg=30,
                            rng=np.random.default_rng(1))
    v, f = mesh.vertices, mesh.faces
    n = 200_000 if quick else 1_000_000
    rng = np.random.default_rng(0)
    grid = facade_circle(SENSORS, FRAME)
    k = rng.integers(0, len(grid), n)
    o = grid.points[k]
    d = cosine_hemisphere(grid.normals[k], rng)
    # a second set: random origins inside the crown, random directions (short rays)
    o2 = CENTRE + rng.uniform(-3, 3, (n, 3)) * [1, 0.5, 1] + FRAME.normal * 1.5
    d2 = rng.normal(size=(n, 3))
    d2 /= np.linalg.norm(d2, axis=1)[:, None]
    import trimesh

    sphere = trimesh.creation.uv_sphere(radius=4.0, count=[161, 161])
    o3 = rng.normal(scale=0.5, size=(n, 3))
    print(f"meshes: slat cloud {len(f)} triangles (25 600 slats of 0.3 m in a 4 m dome); "
          f"sphere {len(sphere.faces)} triangles; {n} rays per set")
    if embree_available():
        for workers in (1, 2):
            c = EmbreeCaster(v, f, workers=workers)
            cs = EmbreeCaster(sphere.vertices, sphere.faces, workers=workers)
            for label, caster, (oo, dd) in (("slats, from sensors", c, (o, d)),
                                            ("slats, inside crown", c, (o2, d2)),
                                            ("sphere, from inside", cs, (o3, d2))):
                caster.first_hit(oo[:1000], dd[:1000])
                t = time.perf_counter()
                caster.first_hit(oo, dd)
                dt = time.perf_counter() - t
                print(f"  embree, {workers} thread(s), {label}: {n / dt / 1e6:.2f} M rays/s")
    else:
        print("  embreex not installed")
    m = 5_000 if quick else 50_000
    t = time.perf_counter()
    bvh = BVHCaster(v, f)
    build = time.perf_counter() - t
    t = time.perf_counter()
    bvh.first_hit(o[:m], d[:m])
    dt = time.perf_counter() - t
    print(f"  numpy-bvh (build {build:.2f} s, {bvh.n_nodes} nodes), from sensors: "
          f"{m / dt / 1e3:.1f} k rays/s")


def engine_hour(quick: bool) -> Scene:
    print("\n== NumPy engine, one hour ==")
    print(describe())
    sc = slat_scene(3000)
    st = sky_state("perez", **HOUR)
    p = EngineParams(rays=1024 if quick else 4096, max_bounces=8)
    t = time.perf_counter()
    geo = scene_geometry(sc, DEFAULT_OPTIONS.backend, p.workers)
    prep = time.perf_counter() - t
    geo.caster.rays_cast = 0
    t = time.perf_counter()
    r = trace(sc, st, p)["facade"]
    dt = time.perf_counter() - t
    rays = geo.caster.rays_cast
    assert r.stderr is not None
    print(f"slat scene: {sc.n_triangles} triangles (3000 slats), 8 sensors × {p.numpy.rays} paths, "
          f"max_bounces {p.numpy.max_bounces}, Perez sky + sun")
    print(f"  geometry {prep:.2f} s; tracing {dt:.2f} s per hour; {rays / 1e6:.2f} M rays "
          f"({rays / dt / 1e6:.2f} M rays/s overall); mean {r.lux.mean():.0f} lx, "
          f"stderr {100 * (r.stderr / r.lux).mean():.2f} %")
    try:
        from radtree.config import load_project
        from radtree.light.hours import hour_states
        from radtree.pipeline.assemble import make_scene

        project = load_project(ROOT / "examples" / "mendoza-street")
        scenario = next(s for s in project.scenarios if s.model == "louvers"
                        and s.reflection == "traced")
        built = make_scene(project, scenario, dense_grid=False)
        state = hour_states(project, scenario, ["11:30"])[0]
        pp = EngineParams(rays=p.numpy.rays, max_bounces=max(8, built.ab))
        scene_geometry(built.scene, DEFAULT_OPTIONS.backend, pp.workers)
        t = time.perf_counter()
        rr = trace(built.scene, state, pp)["facade"]
        dt = time.perf_counter() - t
        print(f"Mendoza project, scenario {scenario.name} (louvers), 11:30: "
              f"{built.triangles} triangles, {dt:.2f} s per hour, mean {rr.lux.mean():.0f} lx")
    except Exception as exc:  # the crown builder belongs to another module; report and go on
        print(f"Mendoza louvers crown not benchmarked: {type(exc).__name__}: {exc}")
    return sc


def _replay_raw(caster: EmbreeCaster, o32: np.ndarray, d32: np.ndarray, workers: int) -> float:
    """Wall time of raw ``EmbreeScene.run`` on the recorded float32 rays (already in Embree's
    frame: exactly what the engine handed Embree)."""
    wrap = caster._embree
    step = 1 << 16
    starts = range(0, len(o32), step)
    with ThreadPoolExecutor(workers) as pool:
        list(pool.map(lambda i: wrap.scene.run(o32[i:i + 1000], d32[i:i + 1000]), starts[:2]))
        t = time.perf_counter()
        list(pool.map(lambda i: wrap.scene.run(o32[i:i + step], d32[i:i + step]), starts))
        return time.perf_counter() - t


def _recorded_queries(caster: EmbreeCaster, work: Any, *args: Any
                      ) -> tuple[np.ndarray, np.ndarray, int]:
    """Every ray ``work(*args)`` sends to Embree through ``caster`` (float32 origins in Embree's
    frame, float32 unit directions, calls): recorded at the caster's one Embree call
    (``EmbreeCaster._run``), whichever caster method made it — with the C kernel the shadow
    rays' origins arrive there already converted."""
    casts: list[tuple[np.ndarray, np.ndarray]] = []
    lock = threading.Lock()
    original = caster._run

    def recording(o32: np.ndarray, d32: np.ndarray) -> np.ndarray:
        with lock:
            casts.append((np.array(o32, np.float32), np.array(d32, np.float32)))
        return original(o32, d32)

    caster._run = recording  # type: ignore[method-assign]
    try:
        work(*args)
    finally:
        caster._run = original  # type: ignore[method-assign]
    return (np.concatenate([c[0] for c in casts]), np.concatenate([c[1] for c in casts]),
            len(casts))


def _embree_inside(caster: EmbreeCaster, work: Any, *args: Any) -> tuple[float, float]:
    """CPU time of the Embree calls made while ``work(*args)`` runs (each calling thread's
    own clock around ``EmbreeScene.run``) and the process CPU time of the whole work."""
    wrap = caster._embree
    spent = [0.0]
    lock = threading.Lock()

    class Scene:  # times EmbreeScene.run, passes everything else through
        def run(self, o: np.ndarray, d: np.ndarray) -> np.ndarray:
            t = time.thread_time()
            out = wrap.scene.run(o, d)
            with lock:
                spent[0] += time.thread_time() - t
            return out

    class Wrap:
        origin, scale, scene = wrap.origin, wrap.scale, Scene()

    caster._embree = Wrap()
    try:
        c0 = time.process_time()
        work(*args)
        return spent[0], time.process_time() - c0
    finally:
        caster._embree = wrap


def engine_vs_embree(quick: bool, repeats: int = 3) -> None:
    print("\n== NumPy engine vs raw Embree on the same rays ==")
    from radtree.config import load_project
    from radtree.engines.numpy import trace_hour
    from radtree.engines.numpy.tracing import trace_states
    from radtree.light.hours import hour_states
    from radtree.pipeline.assemble import make_scene

    # one hour (trace_hour), and the project's 7 hours in the same batches as `radtree
    # simulate` traces a scenario (Engine.trace_many → trace_states), B only
    for name, n_hours in (("B", 1), ("F", 1), ("B", 7)):
        for workers in (1, 2):
            project = load_project(ROOT / "examples" / "mendoza-street", overrides={
                "sensors.dense_grid": False, "engine.workers": workers})
            hours = ["12:30"] if n_hours == 1 else list(project.site.hours)[:n_hours]
            sc = project.scenario(name)
            built = make_scene(project, sc, dense_grid=False)
            states = hour_states(project, sc, hours)
            p = replace(project.engine, rays=1024 if quick else 4096, max_bounces=built.ab)
            geo = scene_geometry(built.scene, DEFAULT_OPTIONS.backend, workers)
            caster = geo.caster
            if not isinstance(caster, EmbreeCaster):
                print("  embreex not installed: skipped")
                return
            if n_hours == 1:
                work, args = trace_hour, (built.scene, states[0], p, ["facade"])
            else:
                work, args = trace_states, (built.scene, states, p, ["facade"])
            work(*args[:2], replace(p, rays=16), ["facade"])
            o32, d32, calls = _recorded_queries(caster, work, *args)
            # the same rays in world coordinates, float64, for EmbreeCaster.first_hit
            o = o32.astype(np.float64) / caster.frame[3] + caster.frame[:3]
            d = d32.astype(np.float64)
            best = []
            for _ in range(max(1, repeats)):  # best of `repeats` each, back to back
                c0, t0 = time.process_time(), time.perf_counter()
                work(*args)
                engine, engine_cpu = time.perf_counter() - t0, time.process_time() - c0
                c0 = time.process_time()
                raw = _replay_raw(caster, o32, d32, workers)
                raw_cpu = time.process_time() - c0
                t0 = time.perf_counter()
                caster.first_hit(o, d)
                first_hit = time.perf_counter() - t0
                best.append((engine, raw, first_hit, engine_cpu, raw_cpu))
            engine, raw, first_hit, engine_cpu, raw_cpu = min(best)
            inside, inside_cpu = _embree_inside(caster, work, *args)
            from radtree.engines.common.kernel import name as kernel_name
            n = len(o)
            print(f"  scenario {name}, {len(hours)} hour(s): {built.triangles} triangles, "
                  f"{workers} thread(s), "
                  f"{n / 1e6:.2f} M queries in {calls} calls: engine {n / engine / 1e6:.2f} "
                  f"M rays/s ({engine:.2f} s, {engine_cpu:.2f} s CPU), raw Embree "
                  f"{n / raw / 1e6:.2f} M/s ({raw_cpu:.2f} s CPU), EmbreeCaster.first_hit "
                  f"{n / first_hit / 1e6:.2f} M/s → engine / raw Embree {raw / engine:.0%} "
                  f"(CPU {raw_cpu / engine_cpu:.0%}), engine / first_hit "
                  f"{first_hit / engine:.0%}; Embree's own CPU time inside the engine "
                  f"{inside:.2f} s = {inside / inside_cpu:.0%} of the engine's "
                  f"{inside_cpu:.2f} s; shadow-ray kernel {kernel_name()}; load "
                  f"{os.getloadavg()[0]:.1f}", flush=True)


def engines_differ(sc: Scene, quick: bool, with_defaults: bool) -> None:
    print("\n== NumPy vs Radiance (per sensor row) ==")
    if find_radiance() is None:
        print("Radiance not found: skipped")
        return
    from radtree.engines.radiance.engine import trace_hour as radiance_trace

    st = sky_state("perez", **HOUR)
    rays = 4096 if quick else 32768
    a = trace(sc, st, EngineParams(rays=rays, max_bounces=8))["facade"]
    assert a.stderr is not None
    rows = np.array(sc.grids["facade"].rows)
    ad = 2048 if quick else 8192
    settings = [(f"-ab 8 -ad {ad} -as 0 -aa 0", EngineParams(ab=8, ad=ad, as_=0, aa=0.0,
                                                             lw=1e-5)),
                (f"-ab 8 -ad {ad} -as {ad // 2} -aa 0",
                 EngineParams(ab=8, ad=ad, as_=ad // 2, aa=0.0, lw=1e-5))]
    if with_defaults:
        settings.append(("-ab 8 -ad 1024 -as 512 -aa 0.1 (project defaults, slow)",
                         EngineParams(ab=8, ad=1024, as_=512, aa=0.1, lw=5e-4)))
    for label, p in settings:
        t = time.perf_counter()
        b = radiance_trace(sc, st, p)["facade"]
        dt = time.perf_counter() - t
        parts = []
        for row in ("higher", "intermediate", "lower"):
            m = rows == row
            parts.append(f"{row} {a.lux[m].mean():.0f}/{b.lux[m].mean():.0f} "
                         f"({a.lux[m].mean() / b.lux[m].mean() - 1:+.1%})")
        print(f"  Radiance {label} [{dt:.1f} s]: numpy/radiance " + ", ".join(parts))
    print(f"  (numpy stderr ≈ {100 * (a.stderr / a.lux).mean():.2f} % per sensor)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="smaller batches")
    ap.add_argument("--with-defaults", action="store_true",
                    help="also run Radiance with the project's -as 512 -aa 0.1 (minutes)")
    ap.add_argument("--repeats", type=int, default=3,
                    help="throughput: best of this many runs of engine and raw Embree (3)")
    ap.add_argument("--only", choices=["rays", "hour", "throughput", "radiance"],
                    help="run one section (1 rays, 2 hour, 3 throughput, 4 radiance)")
    args = ap.parse_args()
    load = os.getloadavg() if hasattr(os, "getloadavg") else (float("nan"),) * 3
    print(f"cpus: {os.cpu_count()}, load average {load[0]:.2f}")
    run = {args.only} if args.only else {"rays", "hour", "throughput", "radiance"}
    if "rays" in run:
        rays_per_second(args.quick)
    if run & {"hour", "radiance"}:
        sc = engine_hour(args.quick) if "hour" in run else slat_scene(3000)
    if "throughput" in run:
        engine_vs_embree(args.quick, args.repeats)
    if "radiance" in run:
        engines_differ(sc, args.quick, args.with_defaults)


if __name__ == "__main__":
    from _common import print_resources_at_exit  # benchmarks/_common.py

    print_resources_at_exit()
    main()
