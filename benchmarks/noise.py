"""Time to a stated noise: each estimator's standard error of a grid mean, and its time to 1 %.

Three cases, one hour each:

* **louvers dome** — scenario B of examples/mendoza-street (5 slat layers, ground traced,
  sun only), 12:30, the 8 façade sensors;
* **free volume crown** — scenario F of the same example (free-standing crowns, slats
  scattered through the volume, Perez sky; its first crown realisation), 12:30, façade;
* **office work plane** — scenario "with" of examples/office-block (crowns in front of the
  central office, Perez sky), 13:30, the 40 work-plane points.

Estimators and how their standard error (s.e.) of the grid mean is measured:

* **radiance** — ``rtrace -I`` at a few ``-ad`` (the project's other options: ``-as 0 -aa 0``,
  its ``-ab`` and ``-lw``), each repeated with ``-u+`` (uncorrelated sampling: every run draws
  new random numbers; the project itself runs ``-u-``). The s.e. of the mean of one run is
  √(Σᵢ sᵢ²) / n from the per-sensor variances sᵢ² across the repeats (sensors are traced
  independently), n sensors;
* **numpy** — the built-in engine at a few ``engine.rays``, repeated with distinct seeds, the
  same pooled s.e. (the engine's own per-sensor s.e. from its paths is printed beside it);
* **forward** — the forward light tracer at a few photon counts, one run each: s.e. from its
  independent batches (overlapping detector patches share photons, so the batches, not the
  sensors, give the error).

For every run: wall time and CPU time (user + system; Radiance: the rtrace child; NumPy and
forward: this process, all threads), first-hit ray queries per second (NumPy: path segments +
shadow rays; forward: photon segments; ``rtrace`` reports no ray count, so none for
Radiance). Then per estimator the time to a 1 % s.e., extrapolated with s.e. ∝ 1/√time fitted
over the settings and, beside it, from the largest setting alone (fixed per-run costs make the
small settings pessimistic); the exponent of a free power-law fit is printed too (−0.5 when the
law holds; it is poorly determined when the settings' times differ little, as Radiance's do
here: a fixed cost per rtrace run). On a shared machine
the CPU-time figures are the comparable ones (wall time also measures the other jobs). Bias:
its highest setting's mean (over the repeats) against the best-converged value (the smallest
s.e. of all), in % ± the combined s.e. — Radiance and the NumPy engine agree to ≈ 1–3 % on
slat crowns (benchmarks/engines.py), the forward detector patches average over 0.5 m.

Run: ``.venv/bin/python benchmarks/noise.py [--quick] [--cases dome free office]
[--repeats N]``. Default: a few minutes on 2 cores. No assertions.
"""

from __future__ import annotations

import argparse
import math
import os
import resource
import sys
import tempfile
import time
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from radtree.config import load_project  # noqa: E402
from radtree.engines.forward import ForwardSettings, trace_forward  # noqa: E402
from radtree.engines.numpy import trace_hour  # noqa: E402
from radtree.engines.numpy.engine import DEFAULT_OPTIONS, scene_geometry  # noqa: E402
from radtree.engines.radiance.binaries import find_radiance, run  # noqa: E402
from radtree.engines.radiance.engine import read_rgb_as_lux, run_hour  # noqa: E402
from radtree.engines.radiance.writer import write_build  # noqa: E402
from radtree.light.hours import hour_states  # noqa: E402
from radtree.pipeline.assemble import make_scene  # noqa: E402


@dataclass(frozen=True)
class Case:
    key: str
    label: str
    example: str
    scenario: str
    hour: str
    grid: str


CASES = [
    Case("dome", "louvers dome (Mendoza B)", "mendoza-street", "B", "12:30", "facade"),
    Case("free", "free volume crown (Mendoza F, crown 1)", "mendoza-street", "F", "12:30",
         "facade"),
    Case("office", "office work plane (office-block 'with')", "office-block", "with", "13:30",
         "workplane"),
]


@dataclass
class Setting:
    """One estimator setting: its repeated runs' per-sensor lux, times and ray counts."""

    estimator: str
    label: str
    runs: list[np.ndarray] = field(default_factory=list)
    wall: list[float] = field(default_factory=list)
    cpu: list[float] = field(default_factory=list)
    rays: list[int] = field(default_factory=list)
    own_se: list[float] = field(default_factory=list)  # the estimator's own s.e. per run

    @property
    def mean(self) -> float:
        return float(np.mean([r.mean() for r in self.runs]))

    @property
    def se(self) -> float:
        """s.e. of one run's grid mean."""
        if len(self.runs) >= 2:
            per_sensor = np.var(np.stack(self.runs), axis=0, ddof=1)
            return float(math.sqrt(per_sensor.sum()) / per_sensor.size)
        return self.own_se[0] if self.own_se else math.nan

    @property
    def se_of_mean(self) -> float:
        """s.e. of the mean over the repeats."""
        return self.se / math.sqrt(len(self.runs))

    @property
    def t_wall(self) -> float:
        return float(np.mean(self.wall))

    @property
    def t_cpu(self) -> float:
        return float(np.mean(self.cpu))


def _children_cpu() -> float:
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    return ru.ru_utime + ru.ru_stime


def radiance_settings(scene, state, engine, ab: int, grid: str, ads: list[int], repeats: int
                      ) -> list[Setting]:
    install = find_radiance()
    if install is None:
        print("  radiance: not found, skipped")
        return []
    out = []
    with tempfile.TemporaryDirectory(prefix="radtree-noise-") as tmp:
        folder = Path(tmp)
        plan = write_build(scene, [state], replace(engine, ad=ads[0]), ab, folder, install,
                           hour_grids={state.label: [grid]})
        run_hour(plan, state.label, grids=[grid])  # octree (not timed)
        base = list(plan.rtrace_opts)
        pts = (folder / "grids" / f"{grid}.pts").read_bytes()
        for ad in ads:
            opts = ["-u+" if o == "-u-" else o for o in base]
            opts[opts.index("-ad") + 1] = str(ad)
            plan.rtrace_opts = opts
            s = Setting("radiance", f"-ad {ad}")
            for _ in range(repeats):
                dst = folder / "results" / "noise.rgb"
                c0, t0 = _children_cpu(), time.perf_counter()
                run(plan.rtrace_command(state.label), stdin=pts, cwd=folder, stdout_path=dst)
                s.wall.append(time.perf_counter() - t0)
                s.cpu.append(_children_cpu() - c0)
                s.runs.append(read_rgb_as_lux(dst, expected=None))
            out.append(s)
            _print_setting(s)
    return out


def numpy_settings(scene, state, engine, ab: int, grid: str, rays: list[int], repeats: int
                   ) -> list[Setting]:
    geo = scene_geometry(scene, DEFAULT_OPTIONS.backend, engine.workers)
    trace_hour(scene, state, replace(engine, rays=16, max_bounces=ab), [grid])  # warm
    out = []
    for n in rays:
        s = Setting("numpy", f"{n} rays")
        for seed in range(1, repeats + 1):
            r0, c0, t0 = geo.caster.rays_cast, time.process_time(), time.perf_counter()
            res = trace_hour(scene, state, replace(engine, rays=n, max_bounces=ab, seed=seed),
                             [grid])[grid]
            s.wall.append(time.perf_counter() - t0)
            s.cpu.append(time.process_time() - c0)
            s.rays.append(geo.caster.rays_cast - r0)
            s.runs.append(res.lux)
            if res.stderr is not None:
                s.own_se.append(float(np.sqrt(np.sum(res.stderr ** 2)) / len(res.lux)))
        out.append(s)
        _print_setting(s)
    return out


def forward_settings(scene, state, engine, ab: int, grid: str, photons: list[int]
                     ) -> list[Setting]:
    trace_forward(scene, state, ForwardSettings(photons=1000, max_bounces=ab), [grid],
                  workers=engine.workers)  # warm
    out = []
    for n in photons:
        s = Setting("forward", f"{n // 1000} k photons")
        c0, t0 = time.process_time(), time.perf_counter()
        fw = trace_forward(scene, state, ForwardSettings(photons=n, max_bounces=ab), [grid],
                           workers=engine.workers)
        s.wall.append(time.perf_counter() - t0)
        s.cpu.append(time.process_time() - c0)
        s.rays.append(fw.segments)
        s.runs.append(fw.grids[grid].lux)
        s.own_se.append(fw.grid_mean(grid)[1])
        out.append(s)
        _print_setting(s)
    return out


def _print_setting(s: Setting) -> None:
    rays = f"{np.sum(s.rays) / np.sum(s.wall) / 1e6:5.2f} M rays/s" if s.rays else \
        "   — rays/s   "
    own = f" (own s.e. {np.mean(s.own_se):.2f})" if s.own_se and len(s.runs) > 1 else ""
    print(f"  {s.estimator:8s} {s.label:14s} ×{len(s.runs)}: {s.t_wall:7.2f} s wall "
          f"{s.t_cpu:7.2f} s CPU per run, {rays}; mean {s.mean:9.2f} lx, s.e. {s.se:7.2f} lx "
          f"({s.se / s.mean:6.2%}){own}", flush=True)


def fit_time_to(settings: list[Setting], target: float, cpu: bool
                ) -> tuple[float, float, float]:
    """Time to a relative s.e. ``target`` with s.e. ∝ t^-½: (fitted over every setting,
    from the largest setting alone), and the exponent of a free power-law fit."""
    t = np.array([s.t_cpu if cpu else s.t_wall for s in settings])
    rel = np.array([s.se / s.mean for s in settings])
    ok = np.isfinite(rel) & (rel > 0) & (t > 0)
    if not ok.any():
        return math.inf, math.inf, math.nan
    a = np.mean(np.log(rel[ok]) + 0.5 * np.log(t[ok]))
    slope = np.polyfit(np.log(t[ok]), np.log(rel[ok]), 1)[0] if ok.sum() >= 2 else math.nan
    last = int(np.flatnonzero(ok)[-1])
    return (float(math.exp(2 * (a - math.log(target)))),
            float(t[last] * (rel[last] / target) ** 2), float(slope))


def summarise(case: Case, by_estimator: dict[str, list[Setting]]) -> None:
    every = [s for ss in by_estimator.values() for s in ss]
    best = min(every, key=lambda s: s.se_of_mean / s.mean)
    print(f"  best-converged value: {best.mean:.2f} ± {best.se_of_mean:.2f} lx "
          f"({best.estimator}, {best.label}, {len(best.runs)} run(s))")
    times = {}
    for name, ss in by_estimator.items():
        if not ss:
            continue
        tw, tw_top, slope_w = fit_time_to(ss, 0.01, cpu=False)
        tc, tc_top, slope_c = fit_time_to(ss, 0.01, cpu=True)
        times[name] = (tw, tc, tw_top, tc_top)
        top = ss[-1]
        err = math.hypot(top.se_of_mean, best.se_of_mean) if top is not best else top.se_of_mean
        print(f"  {name:8s} time to 1 % s.e.: {tw:9.3g} s wall, {tc:9.3g} s CPU (fit over the "
              f"settings; from {top.label} alone {tw_top:.3g} s wall, {tc_top:.3g} s CPU; free "
              f"exponent {slope_w:+.2f} wall, {slope_c:+.2f} CPU); bias of {top.label}: "
              f"{top.mean / best.mean - 1:+.2%} ± {err / best.mean:.2%}")
    if "numpy" in times and "radiance" in times:
        n, r = times["numpy"], times["radiance"]
        print(f"  numpy / radiance time to 1 %: {n[0] / r[0]:.3f} wall, {n[1] / r[1]:.3f} CPU "
              f"(fit); {n[2] / r[2]:.3f} wall, {n[3] / r[3]:.3f} CPU (largest settings) — "
              f"target ≤ 0.2")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="smoke run: small settings, 2 repeats")
    ap.add_argument("--cases", nargs="+", choices=[c.key for c in CASES],
                    default=[c.key for c in CASES])
    ap.add_argument("--repeats", type=int, default=None, help="repeats per setting (default 3)")
    args = ap.parse_args()
    repeats = args.repeats or (2 if args.quick else 3)
    ads = [16, 32] if args.quick else [32, 128]
    rays = [64, 256] if args.quick else [256, 1024, 4096]
    photons = [50_000, 200_000] if args.quick else [250_000, 1_000_000]
    print(f"cpus: {os.cpu_count()}, load average {os.getloadavg()[0]:.2f}; repeats {repeats}; "
          f"radiance -ad {ads}, numpy rays {rays}, forward photons {photons}")
    for case in [c for c in CASES if c.key in args.cases]:
        proj = load_project(ROOT / "examples" / case.example,
                            overrides={"site.hours": [case.hour], "sensors.dense_grid": False})
        sc = proj.scenario(case.scenario)
        built = make_scene(proj, sc, dense_grid=False)
        state = hour_states(proj, sc, [case.hour])[0]
        grid = built.scene.grids[case.grid]
        print(f"\n== {case.label}, {case.hour}, grid {case.grid} ({len(grid)} points): "
              f"{built.scene.n_triangles} triangles, -ab {built.ab} ==", flush=True)
        engine = proj.engine
        found = {
            "radiance": radiance_settings(built.scene, state, engine, built.ab, case.grid, ads,
                                          repeats),
            "numpy": numpy_settings(built.scene, state, engine, built.ab, case.grid, rays,
                                    repeats),
            "forward": forward_settings(built.scene, state, engine, built.ab, case.grid,
                                        photons),
        }
        summarise(case, found)


if __name__ == "__main__":
    from _common import print_resources_at_exit  # benchmarks/_common.py

    print_resources_at_exit()
    main()
