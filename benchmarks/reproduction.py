"""Wall time of the full reference reproduction (scenarios A–E × 7 hours) with Radiance.

Prints build and tracing times (wall and CPU, rtrace children included), peak memory (this
process), the machine load, the façade means and the statistics against
the measured data.
Run: .venv/bin/python benchmarks/reproduction.py  (target, issue 22: ≤ 10 s on 2 idle cores)
"""

from __future__ import annotations

import os
import resource
import shutil
import tempfile
import time
from pathlib import Path

import pandas as pd

from radtree.config import load_project
from radtree.measurements import load_measured
from radtree.pipeline.build import build_project
from radtree.pipeline.options import RunOptions
from radtree.pipeline.simulate import simulate_project
from radtree.stats import compare

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        dst = Path(tmp) / "mendoza"
        shutil.copytree(ROOT / "examples" / "mendoza-street", dst,
                        ignore=shutil.ignore_patterns("build", "results", "report"))
        project = load_project(dst, overrides={"sensors.dense_grid": False})
        scenarios = ["A", "B", "C", "D", "E"]
        load = os.getloadavg()[0]
        c0 = _cpu()
        t0 = time.perf_counter()
        build_project(project, scenarios, pictures=False)
        t1 = time.perf_counter()
        out = simulate_project(project, options=RunOptions(engine="radiance", scenarios=scenarios,
                                                           workers=2))
        t2 = time.perf_counter()
        assert out is not None
        measured, _ = load_measured(project.measured)
        cmp = compare(out.table, measured)
        print(f"build {t1 - t0:.1f} s, tracing {t2 - t1:.1f} s, total {t2 - t0:.1f} s "
              f"for {len(scenarios)} scenarios × {len(project.site.hours)} hours (Radiance, "
              "2 workers, façade sensors only)")
        own = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        print(f"CPU {_cpu() - c0:.1f} s (user + system, rtrace included); peak RSS "
              f"{own:.0f} MiB (Python; each rtrace is a few tens of MiB); "
              f"load average at the start {load:.2f} on {os.cpu_count()} cores")
        pd.set_option("display.width", 120)
        print(cmp.stats[["scenario", "model", "reflection", "rmse", "rmse_low", "rmse_high",
                         "mbe", "r2"]].round(3).to_string(index=False))
        print(out.timing.round(2).to_string(index=False))


def _cpu() -> float:
    """User + system CPU seconds of this process and its finished children."""
    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


if __name__ == "__main__":
    from _common import print_resources_at_exit  # benchmarks/_common.py

    print_resources_at_exit()
    main()
