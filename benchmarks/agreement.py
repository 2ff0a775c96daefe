"""Forward vs backward on the full Mendoza example (80 m street, 4 m louvers dome; F: free
volume crowns under a Perez sky): scenarios A–F at one hour, converged settings.

Per scenario and estimator it prints the façade patch mean (the 8 sensors' 0.5 m squares: the
forward engine's detectors; the backward engines trace ``--points`` random points in each
square, :func:`radtree.verify.compare.backward_patch_mean`), its standard error, the wall-clock
time, the ray rate (forward: photon ray segments/s; NumPy: sensor paths/s; Radiance: points ×
-ad ambient rays/s at the first bounce) and the time to a 1 % standard error, extrapolated as
t · (s.e. / 1 %)²; then the forward − backward difference in % with its combined standard
error, against the 2 % target. The Radiance photon map (``mkpmap`` + ``rtrace -ap``, global
and caustic photons) is the fourth estimator with ``--pmap N``.

Run: ``.venv/bin/python benchmarks/agreement.py [--photons N] [--points N] [--rays N]
[--ad N] [--pmap N] [--scenarios A B ...] [--hour HH:MM] [--backward numpy]``. No assertions.

Measured (session 4, 12:30, 2 cores shared by 8 sessions, load 12–16; 32 points per patch,
NumPy 256 paths each): forward − NumPy façade patch mean, ± combined standard error —
A −0.3 % ± 4.7 % (64 M photons; 985.4 vs 988.2 lx; Radiance -ad 256: 984.1 ± 6.2 lx),
B −0.1 % ± 7.8 % (16 M), C −2.0 % ± 16 % (16 M), D −4.0 % ± 18 % (16 M),
E −1.9 % ± 2.6 % (64 M; −9.8 % ± 4.1 % at 16 M), F +1.3 % ± 9.9 % (16 M). Time to a 1 %
standard error of the façade mean: forward 1 050 (E) – 8 700 (F) s; NumPy 0.06 (E) – 14 (F) s
(C, D: ≈ 300 s — sunflecks through the holes make the 0.5 m patch mean itself noisy);
Radiance 160–260 s (A, B). Forward rate 0.24–0.6 M ray segments/s. The 80 m street makes the
whole-scene sun disc ≈ 6 400 m² for 2 m² of detectors: the forward estimator is 10²–10⁵ times
slower to a given error here than the backward ones.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from radtree.config import load_project  # noqa: E402
from radtree.engines.forward import ForwardSettings, trace_forward  # noqa: E402
from radtree.engines.registry import available_engines  # noqa: E402
from radtree.light.hours import hour_states  # noqa: E402
from radtree.pipeline.assemble import make_scene  # noqa: E402
from radtree.verify.compare import MENDOZA, backward_patch_mean  # noqa: E402


def _line(engine: str, seconds: float, rays: float, unit: str, mean: float, se: float) -> None:
    t1 = seconds * (se / (0.01 * mean)) ** 2 if mean > 0 else math.inf
    print(f"   {engine:9s} {mean:9.1f} ± {se:6.1f} lx ({se / mean:5.2%})  {seconds:7.1f} s  "
          f"{rays / seconds / 1e3:9.1f} k {unit}/s  → 1 % s.e. in {t1:8.3g} s", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--photons", type=int, default=32_000_000)
    ap.add_argument("--points", type=int, default=32)
    ap.add_argument("--rays", type=int, default=512)
    ap.add_argument("--ad", type=int, default=512)
    ap.add_argument("--pmap", type=int, default=0, help="photon map photons (0: not run)")
    ap.add_argument("--scenarios", nargs="+", default=["A", "B", "C", "D", "E", "F"])
    ap.add_argument("--hour", default="12:30")
    ap.add_argument("--backward", nargs="+", default=None,
                    help="backward engines compared (default: every available one)")
    a = ap.parse_args()
    proj = load_project(MENDOZA, overrides={"site.hours": [a.hour], "sensors.dense_grid": False})
    backward = a.backward or [e.name for e in available_engines() if e.name != "forward"]
    print(f"Mendoza example, {a.hour}: forward {a.photons} photons; backward {a.points} points "
          f"per 0.5 m patch (NumPy {a.rays} paths each, Radiance -ad {a.ad})")
    summary = []
    for name in a.scenarios:
        sc = proj.scenario(name)
        built = make_scene(proj, sc, dense_grid=False)
        st = hour_states(proj, sc, [a.hour])[0]
        scene = built.scene
        print(f" scenario {name}: {scene.n_triangles} triangles, -ab {built.ab}", flush=True)
        t0 = time.perf_counter()
        fw = trace_forward(scene, st, ForwardSettings(photons=a.photons, max_bounces=built.ab),
                           ["facade"])
        dt = time.perf_counter() - t0
        f_mean, f_se = fw.grid_mean("facade")
        _line("forward", dt, fw.segments, "ray segments", f_mean, f_se)
        runs = [(e, replace(proj.engine, ad=a.ad)) for e in backward]
        if a.pmap:
            runs.append(("radiance", replace(proj.engine, ad=a.ad, pmap_photons=a.pmap,
                                             pmap_caustic_photons=a.pmap)))
        for e, params in runs:
            label = "pmap" if params.pmap_photons else e
            t0 = time.perf_counter()
            bw = backward_patch_mean(e, scene, st, "facade", 0.5, ab=built.ab,
                                     points=a.points, rays=a.rays, params=params)
            dt = time.perf_counter() - t0
            n = len(scene.grids["facade"]) * a.points * (a.rays if e == "numpy" else a.ad)
            _line(label, dt, n, "paths" if e == "numpy" else "first-bounce rays", bw.lux,
                  bw.stderr)
            diff = (f_mean - bw.lux) / bw.lux
            comb = math.hypot(f_se, bw.stderr) / bw.lux
            summary.append((name, label, bw.lux, f_mean, diff, comb))
    print("\nforward − backward (façade patch mean), target within 2 %")
    for name, label, b, f, d, c in summary:
        ok = "ok" if abs(d) <= max(0.02, 3 * c) else "MISS"
        print(f"  {name:2s} vs {label:9s} {b:9.1f} / {f:9.1f} lx  {d:+6.2%} ± {c:5.2%}  {ok}")


if __name__ == "__main__":
    from _common import print_resources_at_exit  # benchmarks/_common.py

    print_resources_at_exit()
    main()
