"""Forward light tracing vs the NumPy backward engine on the Mendoza louvers dome.

For scenarios A (black ground, calculated reflection) and B (ground traced) of the shipped
Mendoza example (80 m street, 4 m louvers dome, 5 slat layers) at 12:30, and for the reduced
dome of ``radtree verify`` (:data:`radtree.verify.compare.REDUCED_DOME`), prints per engine:

* first-hit ray queries per second (forward: one per photon segment; NumPy: path segments and
  shadow rays), and photons or sensor paths per second;
* the façade mean (mean of the 8 sensors; forward: their 0.5 m patches) and its standard error
  (forward: from the independent batches, overlapping patches share photons; NumPy: from the
  sensors' independent paths);
* the time to a 1 % standard error of the façade mean, extrapolated as t · (s.e. / 1 %)².

Run: ``.venv/bin/python benchmarks/forward.py [--photons N] [--rays N]``. No assertions.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from radtree.config import load_project  # noqa: E402
from radtree.engines.forward import ForwardSettings, trace_forward  # noqa: E402
from radtree.engines.numpy import trace_hour  # noqa: E402
from radtree.engines.numpy.engine import DEFAULT_OPTIONS, scene_geometry  # noqa: E402
from radtree.light.hours import hour_states  # noqa: E402
from radtree.pipeline.assemble import make_scene  # noqa: E402
from radtree.verify.compare import MENDOZA, REDUCED_DOME  # noqa: E402

HOUR = "12:30"


def _line(engine: str, what: str, seconds: float, queries: int, units: float, unit: str,
          mean: float, se: float) -> None:
    t1 = seconds * (se / (0.01 * mean)) ** 2 if mean > 0 else math.inf
    print(f"  {engine:8s} {what:22s} {seconds:7.1f} s  {queries / seconds / 1e6:5.2f} M rays/s  "
          f"{units / seconds / 1e3:7.1f} k {unit}/s  façade {mean:8.1f} ± {se:6.1f} lx "
          f"({se / mean:5.1%})  → 1 % s.e. in {t1:8.3g} s")


def run(label: str, overrides: dict, scenarios: list[str], photons: int, rays: int) -> None:
    ov = {"site.hours": [HOUR], "sensors.dense_grid": False, **overrides}
    proj = load_project(MENDOZA, overrides=ov)
    print(f"{label} ({HOUR})")
    for name in scenarios:
        sc = proj.scenario(name)
        built = make_scene(proj, sc, dense_grid=False)
        st = hour_states(proj, sc, [HOUR])[0]
        scene = built.scene
        geo = scene_geometry(scene, DEFAULT_OPTIONS.backend, proj.engine.workers)
        print(f" scenario {name}: {scene.n_triangles} triangles, -ab {built.ab}")
        # forward (warm the geometry cache first: the same caster for both engines)
        trace_forward(scene, st, ForwardSettings(photons=1000, max_bounces=built.ab),
                      ["facade"])
        t0 = time.perf_counter()
        fw = trace_forward(scene, st, ForwardSettings(photons=photons, max_bounces=built.ab),
                           ["facade"])
        dt = time.perf_counter() - t0
        mean, se = fw.grid_mean("facade")
        _line("forward", f"{photons} photons", dt, fw.segments, photons, "photons", mean, se)
        # NumPy backward
        before = geo.caster.rays_cast
        t0 = time.perf_counter()
        res = trace_hour(scene, st, replace(proj.engine, rays=rays, max_bounces=built.ab),
                         ["facade"])["facade"]
        dt = time.perf_counter() - t0
        queries = geo.caster.rays_cast - before
        se_b = float(np.sqrt(np.sum(res.stderr ** 2)) / len(res.lux)) \
            if res.stderr is not None else 0.0
        _line("numpy", f"{rays} rays/sensor", dt, queries, rays * len(res.lux), "paths",
              float(res.lux.mean()), se_b)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--photons", type=int, default=2_000_000)
    ap.add_argument("--rays", type=int, default=2048)
    ap.add_argument("--scenarios", nargs="+", default=["A", "B"])
    a = ap.parse_args()
    run("Mendoza louvers dome (shipped example)", {}, a.scenarios, a.photons, a.rays)
    run("reduced dome (radtree verify)", dict(REDUCED_DOME), a.scenarios, a.photons, a.rays)


if __name__ == "__main__":
    from _common import print_resources_at_exit  # benchmarks/_common.py

    print_resources_at_exit()
    main()
