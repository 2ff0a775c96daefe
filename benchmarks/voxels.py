"""Turbid voxel crowns (``[tree] points`` / ``[tree] voxels`` with ``representation =
"turbid"``, :mod:`radtree.engines.common.voxels`): the walk's throughput, and a crown from
points as slats vs as turbid voxels, NumPy engine.

* ``walk``: shadow rays (exact transmittance) and free-path draws through one 20 × 20 × 20 grid
  of 0.25 m voxels, rays from random points 10 m out towards random points of the grid:
  rays per second, and the tracer's memory (density array + proxy boxes).
* ``crown``: one synthetic crown (``StreetTree`` 10 m high, 3 m crown radius) scanned at 25
  pulses/m², placed on the 3 trunks of the reference street's free row (examples/mendoza-
  street, scenario A, 12:30, façade circle, ``--rays`` paths), each configuration in its own
  child process (peak memory = its ``ru_maxrss``): explicit louvers-from-points slats (mean of
  ``--realisations`` slat crowns, seeds 1…R, s.e. from their spread), turbid voxels, both at
  the default 1 m voxels and at 0.65 m, and the 1 m grid written to a voxel CSV with 4 × the
  density (4 × the leaf area: the turbid crown's memory and time do not grow with it).

Measured 2026-12-07 09:04–09:08 UTC on the 2-core machine shared with four other sessions
(load average 5.6–7.7: wall times inflated):

    walk: 200 000 shadow rays 1.16 s (172 k rays/s), 200 000 free paths 1.12 s (179 k/s);
          tracer memory 0.06 MiB density + 0.00 MiB proxy boxes
    crown (256 paths, 12:30)        time    peak      façade mean ± s.e. (range)
    explicit slats, 1 m voxels     27.2 s  0.20 GiB   9 371 ± 1 222 lx (4 253–13 979; 8 crowns)
    turbid voxels, 1 m voxels       6.4 s  0.19 GiB  10 262 ±    68 lx (3 grids 16×16×10)
    explicit slats, 0.65 m voxels  12.6 s  0.20 GiB   6 965 ±   542 lx (4 860–9 322; 8 crowns)
    turbid voxels, 0.65 m voxels    3.4 s  0.19 GiB  10 935 ±    67 lx (3 grids 25×25×16)
    turbid voxels × 4 density       2.7 s  0.17 GiB   2 555 ±    47 lx

At 1 m voxels the turbid crown agrees with the mean of 8 slat crowns (+9.5 %, within its
s.e. of 13 %); at 0.65 m it reads +57 % (≈ 7 s.e.). Voxel by voxel the two hold the same leaf
area (checked by binning the slats); the difference is inside the voxels: the slats stand at
the voxel's returns (± half a point spacing), the medium spreads the leaf area evenly, and the 8
façade sensors see the crown through its rim by the wall (where one slat crown ranged
4 860–9 322 lx). A façade-level equivalence of the two from-points crowns is therefore NOT
shown here; the medium's own transmission is verified analytically (``radtree verify``).

Run: ``.venv/bin/python benchmarks/voxels.py [--cases walk crown] [--rays 256]``.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
MENDOZA = ROOT / "examples" / "mendoza-street"


def walk_case(n: int = 200_000) -> None:
    import numpy as np

    from radtree.config import Louvers
    from radtree.engines.common.streams import GeneratorDraws
    from radtree.engines.common.voxels import VoxelTracer
    from radtree.media_voxels import VoxelCrowns
    from radtree.optics import Trans
    from radtree.trees.turbid import leaf_kind

    kind = leaf_kind(Louvers(inclination_distribution="ellipsoidal"), "leaf")
    pad = np.random.default_rng(1).uniform(0.0, 1.0, (20, 20, 20))
    tr = VoxelTracer(VoxelCrowns.of(np.zeros((1, 3)), size_m=0.25, pads=[pad], kinds=[kind]),
                     materials={"leaf": Trans("leaf", 0.1, 0.1, 0.0)})
    rng = np.random.default_rng(2)
    d = rng.standard_normal((n, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    o = rng.uniform(0.0, 5.0, (n, 3)) - 10.0 * d
    t0 = time.perf_counter()
    tr.transmittance(o, d)
    t1 = time.perf_counter()
    tr.collide(o, d, np.full(n, np.inf), GeneratorDraws(rng))
    t2 = time.perf_counter()
    print(f"walk: {n} shadow rays {t1 - t0:.2f} s ({n / (t1 - t0) / 1e3:.0f} k rays/s), {n} "
          f"free paths {t2 - t1:.2f} s ({n / (t2 - t1) / 1e3:.0f} k/s); tracer memory "
          f"{tr.values.nbytes / 2**20:.2f} MiB density + {tr.boxes.corners.nbytes / 2**20:.2f} "
          "MiB boxes")


def _child(args: argparse.Namespace) -> None:
    import numpy as np

    from radtree.config import effective_project, load_project
    from radtree.engines.numpy.tracing import trace_states
    from radtree.light.hours import hour_states
    from radtree.media_voxels import VoxelCrowns
    from radtree.pipeline.assemble import make_scene

    ov = json.loads(args.overrides)
    t0 = time.perf_counter()
    means, ses, slats, grid = [], [], 0.0, None
    for seed in range(1, args.realisations + 1):
        proj = load_project(MENDOZA, overrides={
            **ov, "tree.form": "free", "site.hours": ["12:30"], "sensors.dense_grid": False,
            "tree.louvers.seed": seed})
        sc = proj.scenario("A")
        built = make_scene(proj, sc, dense_grid=False)
        states = hour_states(proj, sc)
        eng = effective_project(proj, sc).engine.changed(rays=args.rays, max_bounces=built.ab,
                                                         workers=2)
        res = trace_states(built.scene, states, eng, seed=seed)[0]["facade"]
        means.append(float(res.lux.mean()))
        ses.append(float(np.sqrt(np.sum(res.stderr ** 2)) / len(res.lux))
                   if res.stderr is not None else 0.0)
        slats = built.info.get("slat_count", 0.0)
        media = built.scene.media
        grid = list(media.pads[0].shape) if isinstance(media, VoxelCrowns) else None
    spread = float(np.std(means, ddof=1) / np.sqrt(len(means))) if len(means) > 1 else 0.0
    se = max(spread, float(np.sqrt(np.sum(np.square(ses)))) / len(ses))
    print("RESULT " + json.dumps({
        "seconds": time.perf_counter() - t0, "mean": float(np.mean(means)), "se": se,
        "min": min(means), "max": max(means),
        "peak_gib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0 ** 2,
        "slats": slats, "grid": grid}))


def _run(overrides: dict, rays: int, realisations: int = 1) -> dict:
    argv = [sys.executable, __file__, "--child", "--overrides", json.dumps(overrides),
            "--rays", str(rays), "--realisations", str(realisations)]
    done = subprocess.run(argv, capture_output=True, text=True,
                          env=dict(os.environ, PYTHONPATH=str(ROOT)))
    line = [x for x in done.stdout.splitlines() if x.startswith("RESULT ")]
    if done.returncode or not line:
        raise SystemExit(f"{overrides} failed:\n{done.stderr[-3000:]}")
    return json.loads(line[-1][7:])  # type: ignore[no-any-return]


def crown_case(rays: int, realisations: int) -> None:
    import numpy as np

    from radtree.lidar.scanner import AlsScan
    from radtree.trees.synthetic_scan import StreetTree, scan_street, write_scan

    with tempfile.TemporaryDirectory() as tmp:
        pts, _, _ = scan_street([StreetTree("S01", 10.0, 10.0, 10.0, 3.0, 3.0)],
                                AlsScan(pulse_density_m2=25.0))
        laz = write_scan(pts, Path(tmp) / "tree.laz")
        from radtree.config import load_project
        from radtree.trees.points_crown import points_grid

        tree = load_project(MENDOZA, {"tree.points": str(laz)}).tree
        g = points_grid(tree)
        cxy = g.centroid_xy()
        i, j, k = np.nonzero(g.pad >= 0)
        x = g.x0 + (i + 0.5) * g.size_m - cxy[0]
        y = g.y0 + (j + 0.5) * g.size_m - cxy[1]
        z = (k + 0.5) * g.size_m
        csv = Path(tmp) / "crown.csv"
        csv.write_text("x_m,y_m,z_m,pad_m2_m3\n" + "\n".join(
            f"{a:.6f},{b:.6f},{c:.6f},{4 * p:.9g}" for a, b, c, p in zip(x, y, z, g.pad[i, j, k])))
        fine: dict = {"tree.points": str(laz), "tree.points_voxel_m": 0.65}
        runs: list[tuple[str, dict]] = [("explicit slats from points", {"tree.points": str(laz)}),
                ("turbid voxels from points", {"tree.points": str(laz),
                                               "tree.representation": "turbid"}),
                ("explicit slats, 0.65 m voxels", fine),
                ("turbid voxels, 0.65 m voxels", {**fine, "tree.representation": "turbid"}),
                ("turbid voxels × 4 density", {"tree.voxels": str(csv),
                                               "tree.voxels_size_m": g.size_m,
                                               "tree.representation": "turbid"})]
        print(f"crown ({rays} paths, 12:30; explicit: mean of {realisations} slat crowns)")
        print(f"  {'':30s} {'time':>7s} {'peak':>9s}  façade mean ± s.e. (range)")
        for name, ov in runs:
            r = _run(ov, rays, realisations if name.startswith("explicit") else 1)
            what = (f"{r['slats']:.0f} slats" if r["grid"] is None else
                    "grids of " + "×".join(str(v) for v in r["grid"]))
            print(f"  {name:30s} {r['seconds']:6.1f} s {r['peak_gib']:5.2f} GiB  "
                  f"{r['mean']:7.0f} ± {r['se']:.0f} lx ({r['min']:.0f}–{r['max']:.0f}; {what})")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", nargs="+", default=["walk", "crown"])
    ap.add_argument("--rays", type=int, default=256)
    ap.add_argument("--realisations", type=int, default=8)
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--overrides", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        _child(args)
        return
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs (shared machine)")
    if "walk" in args.cases:
        walk_case()
    if "crown" in args.cases:
        crown_case(args.rays, args.realisations)


if __name__ == "__main__":
    main()
