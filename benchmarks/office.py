"""Wall time of one hour of the office study with Radiance: both grids, with and without tree.

    .venv/bin/python benchmarks/office.py                 # 13:30, 2 workers (2 cores)
    .venv/bin/python benchmarks/office.py --hour 10:30 --workers 1

The office-block example is copied to a temporary folder (nothing touches the repository) and
``simulate_project`` runs the chosen hour of both scenarios ("with": free-standing louvers
crowns; "without": open street) with the example's engine settings, writing the build folders
first (as ``radtree simulate`` does on a fresh project). Printed: the scene facts, the wall
time split into build (scene + Radiance files) and simulation (gendaylit, oconv, rtrace of
both grids, in parallel over the scenarios), the per-scenario tracing time, the grid means,
and the summary (``results/summary.csv``) of that hour. Target: < 60 s on 2 cores.
"""

from __future__ import annotations

import argparse
import importlib.util
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OFFICE = ROOT / "examples" / "office-block"
TARGET_S = 60.0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--hour", default="13:30")
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args(argv)

    from radtree.config import load_project
    from radtree.engines.radiance.binaries import find_radiance
    from radtree.office_summary import summarise
    from radtree.pipeline.assemble import make_scene
    from radtree.pipeline.build import build_project
    from radtree.pipeline.options import RunOptions
    from radtree.pipeline.simulate import simulate_project

    if find_radiance() is None:
        print("Radiance not found: nothing to benchmark")
        return 1
    scenarios = ["with", "without"]
    if importlib.util.find_spec("radtree.trees.build") is None:
        print("radtree.trees.build is not available: timing the 'without' scenario only")
        scenarios = ["without"]

    with tempfile.TemporaryDirectory(prefix="radtree-bench-office-") as tmp:
        proj_dir = Path(tmp) / "office"
        shutil.copytree(OFFICE, proj_dir, ignore=shutil.ignore_patterns(
            "build", "results", "report"))
        project = load_project(proj_dir)
        print(f"office block, {args.hour}, Radiance, {args.workers} worker(s), "
              f"{os.cpu_count()} CPUs, load average {os.getloadavg()[0]:.1f}")
        for name in scenarios:
            built = make_scene(project, project.scenario(name))
            grids = ", ".join(f"{g} {len(v)}" for g, v in built.scene.grids.items())
            print(f"  {name}: {built.triangles} triangles, -ab {built.ab}, grids: {grids}")
        e = project.engine
        print(f"  rtrace -ad {e.ad} -as {e.as_} -aa {e.aa:g} -lw {e.lw:g}")

        t0 = time.perf_counter()
        build_project(project, scenarios, pictures=False)
        t_build = time.perf_counter() - t0
        t1 = time.perf_counter()
        out = simulate_project(project, options=RunOptions(
            engine="radiance", scenarios=scenarios, hours=[args.hour], workers=args.workers,
            fresh=True))
        t_sim = time.perf_counter() - t1
        wall = time.perf_counter() - t0
        assert out is not None
        print(f"build (scenes + Radiance files): {t_build:6.1f} s")
        print(f"simulate (sky, oconv, rtrace):   {t_sim:6.1f} s")
        for _, row in out.timing.iterrows():
            print(f"  {row['scenario']:8s} tracing {row['tracing_s']:6.1f} s")
        summary = summarise(out.table)
        cols = ["scenario", "tree", "grid", "mean_lux", "min_lux", "max_lux", "uniformity",
                "pct_below_300", "pct_300_2000", "pct_above_2000"]
        print(summary[cols].to_string(index=False, float_format=lambda v: f"{v:.2f}"
                                      if abs(v) < 10 else f"{v:.0f}"))
        verdict = "met" if wall < TARGET_S else "NOT met"
        print(f"wall time, one hour, both grids, {' + '.join(scenarios)}: {wall:.1f} s "
              f"(target < {TARGET_S:.0f} s: {verdict})")
    return 0


if __name__ == "__main__":
    from _common import print_resources_at_exit  # benchmarks/_common.py

    print_resources_at_exit()
    sys.exit(main())
