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
[--ad N] [--pmap N] [--scenarios A B ...] [--hour HH:MM] [--backward numpy]
[--focus M] [--guide Q --guide-radius M] [--skip-forward]``. No assertions. ``--backward``
with no engine runs the forward engine alone; ``--skip-forward`` the backward ones alone (run
them as separate processes). Wall and CPU seconds are both printed: on a shared machine the CPU
time is the comparable cost.

Measured (session 6, 12:30, idle 2 cores; ``--photons 64000000 --guide 0.5 --guide-radius 1
--guide-scenarios B C D F --backward numpy --points 8192 --rays 16``, 612 s wall): forward −
NumPy A −0.11 ± 1.04 %, B −1.69 ± 1.11 %, C +0.75 ± 0.67 %, D +0.90 ± 0.79 %, E −1.04 ±
0.67 %, F −0.20 ± 1.97 % — every scenario within 2 %. NumPy A 990.2, B 1 280.6, C 3 042.3,
D 2 583.4, E 2 374.4, F 1 433.8 lx; Radiance (separate runs) A 986.9, B 1 278.1, E 2 373.5
(32 points, -ad 256), C 3 027.4, D 2 573.5 (2 048 points, -ad 64). Forward time to 1 %: A 98,
B 137, C 1.9, D 3.1, E 34, F 445 CPU-s. Session 5's D "−5.2 %" was the NumPy side: 1 024
points per patch under-sample D's sun flecks (2 716 ± 57 there, 2 583 ± 20 at 8 192).

Measured (session 5, 12:30, 2 cores shared by 6 sessions, load 16–23: a process got 5–8 % of
a core, so CPU seconds are quoted). Forward with the stratified launch (``--focus 0.5``), 8 M
photons: A 979.4 ± 18.7 lx (1.9 %, 27 CPU-s), B 1 372 ± 227 (17 %), C 3 636 ± 618 (17 %),
D 2 575.5 ± 13.5 (0.52 %, 23 CPU-s), E 2 317 ± 84 (3.6 %), F 1 090 ± 103 (9.5 %);
+ guided scattering (``--guide 0.5 --guide-radius 1``), 4 M photons: B 1 182.5 ± 36.6 (3.1 %,
14 CPU-s), C 3 107.0 ± 26.9 (0.87 %, 11 CPU-s), F 1 302 ± 84 (6.5 %), A 947.6 ± 15.0 (1.6 %),
D 2 608.9 ± 14.5 (0.56 %), E 2 374.9 ± 35.6 (1.5 %); at 16 M: B 1 230.6 ± 16.2 (1.3 %, 56
CPU-s), A 1 073 ± 115 (11 %: one tail event); rings alone at 16 M: D 2 574.4 ± 10.0 (0.39 %).
NumPy backward (32
points × 256 paths; C, D 1 024 points × 32 paths): A 988.2 ± 6.0, B 1 281.3 ± 7.7,
C 3 166.9 ± 57.4, D 2 716.4 ± 57.4, E 2 375.0 ± 8.3, F 1 408.3 ± 16.4. Radiance (32 points,
-ad 256): A 987.6 ± 6.4 (90 CPU-s), B 1 279.3 ± 6.2, C 3 290 ± 398, D 2 829 ± 397, E 2 362.2 ± 5.1
(F not finished). The uniform launch (session 4) needed ≈ 2 000 s for 1 % on
A; the rings need ≈ 100 CPU-s. Scenarios with traced street light (B, C, F) are heavy-tailed
without the guide: one batch in 16 can hold 40× the others (a photon from a far ring, launched
at low density, reaching the detectors through the dome); even with it the dome scenes' means
rise with the photon count (A: 917 at 1 M, 927–940 at 2 M, 979 at 8 M) — a tail the 16-batch
standard error does not see, so forward − backward within 2 % is shown only where the
combined standard error is ≈ 2 %: C (−1.9 % ± 2.0 %), E (0.0 % ± 1.5 %), A (−0.9 % ± 2.0 %).

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

_CHILD = [0.0]


def _children_cpu() -> float:
    """CPU seconds of finished child processes (rtrace) since the last call."""
    import resource

    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    now = r.ru_utime + r.ru_stime
    out, _CHILD[0] = now - _CHILD[0], now
    return out


def _line(engine: str, seconds: float, rays: float, unit: str, mean: float, se: float,
          cpu: float) -> None:
    """Wall and CPU seconds (the machine is shared: CPU time is the comparable figure), the
    rates per wall and per CPU second, and the times to a 1 % standard error (t · (s.e./1 %)²)."""
    k = (se / (0.01 * mean)) ** 2 if mean > 0 else math.inf
    print(f"   {engine:9s} {mean:9.1f} ± {se:6.1f} lx ({se / mean:5.2%})  {seconds:7.1f} s wall "
          f"{cpu:7.1f} s CPU  {rays / seconds / 1e3:8.1f} k {unit}/s ({rays / cpu / 1e3:8.1f} k "
          f"per CPU s)  → 1 % s.e. in {seconds * k:8.3g} s wall, {cpu * k:8.3g} s CPU",
          flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--photons", type=int, default=32_000_000)
    ap.add_argument("--points", type=int, default=32)
    ap.add_argument("--rays", type=int, default=512)
    ap.add_argument("--ad", type=int, default=512)
    ap.add_argument("--focus", type=float, default=0.5,
                    help="forward: stratified launch, innermost ring radius m (0: uniform)")
    ap.add_argument("--guide", type=float, default=0.0,
                    help="forward: share of diffuse directions aimed at the target (0: none)")
    ap.add_argument("--guide-radius", type=float, default=1.0, help="its sphere's radius, m")
    ap.add_argument("--guide-scenarios", nargs="*", default=None,
                    help="the scenarios the guide applies to (default: all)")
    ap.add_argument("--pmap", type=int, default=0, help="photon map photons (0: not run)")
    ap.add_argument("--scenarios", nargs="+", default=["A", "B", "C", "D", "E", "F"])
    ap.add_argument("--hour", default="12:30")
    ap.add_argument("--skip-forward", action="store_true",
                    help="backward engines only (run the estimators in separate processes)")
    ap.add_argument("--backward", nargs="*", default=None,
                    help="backward engines compared (default: every available one; none: "
                         "forward only)")
    a = ap.parse_args()
    proj = load_project(MENDOZA, overrides={"site.hours": [a.hour], "sensors.dense_grid": False})
    backward = a.backward if a.backward is not None else [
        e.name for e in available_engines() if e.name != "forward"]
    print(f"Mendoza example, {a.hour}: forward {a.photons} photons; backward {a.points} points "
          f"per 0.5 m patch (NumPy {a.rays} paths each, Radiance -ad {a.ad})")
    summary = []
    for name in a.scenarios:
        sc = proj.scenario(name)
        built = make_scene(proj, sc, dense_grid=False)
        st = hour_states(proj, sc, [a.hour])[0]
        scene = built.scene
        print(f" scenario {name}: {scene.n_triangles} triangles, -ab {built.ab}", flush=True)
        f_mean = f_se = math.nan
        if not a.skip_forward:
            t0, c0 = time.perf_counter(), time.process_time()
            guide = a.guide if a.guide_scenarios is None or name in a.guide_scenarios else 0.0
            if guide != a.guide:
                print(f"   (forward without the guide for {name})")
            fw = trace_forward(scene, st, ForwardSettings(
                photons=a.photons, max_bounces=built.ab, focus_m=a.focus or None,
                guide=guide, guide_radius_m=a.guide_radius), ["facade"])
            dt = time.perf_counter() - t0
            f_mean, f_se = fw.grid_mean("facade")
            _line("forward", dt, fw.segments, "ray segments", f_mean, f_se,
                  time.process_time() - c0)
        runs = [(e, replace(proj.engine, ad=a.ad)) for e in backward]
        if a.pmap:
            runs.append(("radiance", replace(proj.engine, ad=a.ad, pmap_photons=a.pmap,
                                             pmap_caustic_photons=a.pmap)))
        for e, params in runs:
            label = "pmap" if params.radiance.pmap_photons else e
            t0, c0 = time.perf_counter(), time.process_time()
            bw = backward_patch_mean(e, scene, st, "facade", 0.5, ab=built.ab,
                                     points=a.points, rays=a.rays, params=params)
            dt = time.perf_counter() - t0
            n = len(scene.grids["facade"]) * a.points * (a.rays if e == "numpy" else a.ad)
            _line(label, dt, n, "paths" if e == "numpy" else "first-bounce rays", bw.lux,
                  bw.stderr, time.process_time() - c0 + _children_cpu())
            diff = (f_mean - bw.lux) / bw.lux
            comb = math.hypot(f_se, bw.stderr) / bw.lux
            summary.append((name, label, bw.lux, f_mean, diff, comb))
    print("\nforward − backward (façade patch mean), target within 2 %")
    for name, label, b, f, d, c in summary if not a.skip_forward else []:
        ok = "ok" if abs(d) <= max(0.02, 3 * c) else "MISS"
        print(f"  {name:2s} vs {label:9s} {b:9.1f} / {f:9.1f} lx  {d:+6.2%} ± {c:5.2%}  {ok}")


if __name__ == "__main__":
    from _common import print_resources_at_exit  # benchmarks/_common.py

    print_resources_at_exit()
    main()
