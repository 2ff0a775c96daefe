"""Wall time of a 24-case sweep of the Mendoza example on a dask LocalCluster, 1 and 2 workers.

    .venv/bin/python benchmarks/sweep.py              # reduced cost (below), ~2 min on 2 cores
    .venv/bin/python benchmarks/sweep.py --hours 10:30,11:30,12:30,13:30,14:30,15:30,16:30 \
        --ab 3 --ad 1024 --as 512                      # closer to a real run (much longer)

Design: full factorial ``tree.dome.radius_m=3.5:4.7:4`` × ``tree.louvers.layers=3,4,5`` ×
``tree.louvers.slat_size_m=0.25,0.3`` = 24 cases of scenario A (louvers crown in the study's
sensor-dome form, ground-reflected light calculated), Radiance engine.

Reduced-cost setting (default), because a literal case (7 hours, ``-ab 3``, 6 000-slat crown)
takes many minutes (2 hours at ``-ab 2 -ad 256 -as 512`` took 160 s): two hours (10:30,
13:30), ``-ab 1 -ad 512 -as 0``, no dense façade grid — about 1 s per case-hour. The figures
are for scaling, not for accuracy. If the crown models cannot be built (not installed yet), the
scenario falls back to an open street (``model = "none"``) and the output says so.

Each run starts its own cluster (the wall time includes starting the worker processes) and
writes to its own folder, so the 2-worker run recomputes everything.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MENDOZA = ROOT / "examples" / "mendoza-street"
PARAMS = ["tree.dome.radius_m=3.5:4.7:4", "tree.louvers.layers=3,4,5",
          "tree.louvers.slat_size_m=0.25,0.3"]


def crown_models_work(project: Path) -> str | None:
    """None when scenario A's crown can be built, else the reason."""
    from radtree.config import load_project
    from radtree.pipeline.assemble import make_scene

    try:
        p = load_project(project)
        make_scene(p, p.scenario("A"), dense_grid=False)
    except Exception as exc:  # noqa: BLE001 - any failure means: fall back, and say why
        return f"{type(exc).__name__}: {exc}"
    return None


def _spin(n: int) -> int:
    x = 0
    for i in range(n):
        x += i
    return x


def parallel_headroom(n: int = 6_000_000) -> float:
    """How much faster two CPU-bound processes finish together than one after the other.

    2.0 on an idle 2-core machine; lower when other jobs hold the cores. A yardstick for the
    sweep's scaling figure.
    """
    import multiprocessing as mp

    ctx = mp.get_context("spawn")
    with ctx.Pool(2) as pool:
        pool.map(_spin, [1000, 1000])  # start-up outside the timing
        t = time.perf_counter()
        pool.map(_spin, [n], chunksize=1)
        pool.map(_spin, [n], chunksize=1)
        serial = time.perf_counter() - t
        t = time.perf_counter()
        pool.map(_spin, [n, n], chunksize=1)
        both = time.perf_counter() - t
    return serial / both


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hours", default="10:30,13:30", help="comma-separated HH:MM")
    ap.add_argument("--engine", default="auto", choices=["auto", "radiance", "numpy"])
    ap.add_argument("--ab", type=int, default=1)
    ap.add_argument("--ad", type=int, default=512)
    ap.add_argument("--as", dest="as_", type=int, default=0)
    ap.add_argument("--workers", default="1,2", help="worker counts to time (default 1,2)")
    args = ap.parse_args()

    sys.path.insert(0, str(ROOT))
    from radtree.pipeline.options import RunOptions
    from radtree.sweep import SweepOptions, run_sweep

    tmp = Path(tempfile.mkdtemp(prefix="radtree-bench-sweep-"))
    try:
        project = tmp / "mendoza"
        shutil.copytree(MENDOZA, project, ignore=shutil.ignore_patterns(
            "build", "results", "report", "diagnose", "sweep"))
        reason = crown_models_work(project)
        model = "louvers (dome form)"
        if reason is not None:
            toml = project / "radtree.toml"
            toml.write_text(re.sub(r'model = "\w+"', 'model = "none"', toml.read_text()))
            model = f"none (open street) — crown models unavailable: {reason}"
        hours = [h.strip() for h in args.hours.split(",") if h.strip()]
        fixed = {"sensors.dense_grid": False, "engine.ab": args.ab, "engine.ad": args.ad,
                 "engine.as": args.as_}
        print("radtree sweep benchmark: Mendoza example, scenario A, 24 cases")
        print(f"  parameters: {' × '.join(PARAMS)}")
        print(f"  model: {model}")
        print(f"  hours: {', '.join(hours)}; -ab {args.ab} -ad {args.ad} -as {args.as_}; "
              f"dense grid off; engine {args.engine}; CPU cores: {os.cpu_count()}; "
              f"load average before: {os.getloadavg()[0]:.1f}")
        times: dict[int, float] = {}
        for w in [int(x) for x in args.workers.split(",")]:
            t = time.perf_counter()
            out = run_sweep(project, sweep=SweepOptions(params=PARAMS, out=tmp / f"sweep-{w}",
                                                        fixed=fixed),
                            run=RunOptions(scenarios=["A"], hours=hours, engine=args.engine,
                                           scheduler="local", workers=w))
            times[w] = time.perf_counter() - t
            busy = float(out.cases["seconds"].fillna(0).sum())
            print(f"  {w} worker(s): {times[w]:7.1f} s wall ({len(out.computed)} cases run, "
                  f"{len(out.failed)} failed; {busy:.1f} s of case time, "
                  f"{busy / len(out.cases):.2f} s per case; engine {out.engine}; "
                  f"load average {os.getloadavg()[0]:.1f})")
            if out.failed:
                print("    first failure: " + str(out.failures["error"].iloc[0])[:300])
        if 1 in times and 2 in times:
            print(f"  scaling 1 → 2 workers: {times[1] / times[2]:.2f}× faster "
                  f"(ideal 2.00×; includes cluster start-up)")
            print(f"  yardstick: two CPU-bound processes run {parallel_headroom():.2f}× faster "
                  "together than one after the other on this machine now")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return 0


if __name__ == "__main__":
    from _common import print_resources_at_exit  # benchmarks/_common.py

    print_resources_at_exit()
    sys.exit(main())
