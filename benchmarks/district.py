"""District benchmark: wall time and peak memory of the synthetic Mendoza district
(``examples/district``) — the 7 hours of the ``trees`` scenario on 1 and 2 Dask workers, with
60 and 240 trees, per engine.

Each case copies the example to a scratch folder (``/tmp/district_bench_*``, removed
afterwards unless ``--keep``), regenerates the inventory with ``make_district.py --trees N``
(same 12 buildings and façade sensors; trees spread along the same sidewalks), then runs, each
in its own process, ``radtree build`` and ``radtree simulate -s trees --engine E --scheduler
local --workers W --fresh``. Peak memory is the largest sum of the resident set sizes of the
command's whole process tree (Dask workers and rtrace included), sampled every 0.1 s with
psutil; CPU is the tree's user + system time (``getrusage``), which a busy machine inflates
less than the wall time. Targets (Radiance): ≤ 5 min for the 7 hours on 2 cores, ≤ 2 GiB, memory and build
time at 240 trees ≤ 1.3 × those at 60 (crowns are instanced: one octree per species).

Measured 2026-12-01 on the shared 2-core machine at load average 12–24 (other jobs running, so
wall times are inflated; CPU = the process tree's user + system seconds), 7 hours, ``trees``:

    engine    trees workers  build wall/CPU/peak      simulate wall/CPU/peak
    radiance     60   1      35.5 s / 4.2 s / 0.24 GiB  172 s / 34 s / 0.48 GiB
    radiance     60   2      35.5 s / 4.2 s / 0.24 GiB  132 s / 34 s / 0.49 GiB
    radiance    240   1      11.5 s / 3.4 s / 0.24 GiB  607 s / 151 s / 0.49 GiB
    radiance    240   2      11.5 s / 3.4 s / 0.24 GiB  592 s / 168 s / 0.61 GiB
    numpy        60   1      14.9 s / 3.2 s / 0.24 GiB   89 s / 16 s / 0.56 GiB
    numpy        60   2      14.9 s / 3.2 s / 0.24 GiB  112 s / 25 s / 0.86 GiB
    numpy       240   1      22.6 s / 3.6 s / 0.24 GiB  205 s / 33 s / 0.71 GiB
    numpy       240   2      22.6 s / 3.6 s / 0.24 GiB  126 s / 38 s / 1.12 GiB

Rerun 22:16–22:26 UTC at load 5–10, Radiance (after the species library's leaf-angle update):

    radiance     60   1       9.2 s / 3.4 s / 0.24 GiB   89 s /  32 s / 0.37 GiB
    radiance     60   2       9.2 s / 3.4 s / 0.24 GiB   78 s /  34 s / 0.48 GiB
    radiance    240   1       8.5 s / 3.4 s / 0.24 GiB  241 s / 120 s / 0.38 GiB
    radiance    240   2       8.5 s / 3.4 s / 0.24 GiB  150 s / 133 s / 0.58 GiB

i.e. 240/60: build time ×0.93 (CPU ×1.00), build memory ×1.00, simulate memory ×1.19.

First run, Radiance 240/60: build CPU ×0.81, build memory ×1.00, simulate memory ×1.26 (2 workers); the
tracing itself grows (CPU ×4.9): rays meet ~4× as many crowns. NumPy (crowns expanded, no
instancing): simulate memory ×1.30, CPU ×1.5.

Run: ``.venv/bin/python benchmarks/district.py [--engines radiance numpy] [--trees 60 240]
[--workers 1 2] [--keep]``.
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import psutil

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "district"
GIB = 1024.0 ** 3


def run_measured(argv: list[str], cwd: Path) -> tuple[float, float, float, str]:
    """Wall time (s), peak RSS of the whole process tree (bytes), CPU time of the tree (user +
    system s, every waited-for descendant: Dask workers, rtrace) and the output's tail."""
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    ru0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.Popen(argv, cwd=cwd, env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True)
    root = psutil.Process(proc.pid)
    peak = 0.0
    while proc.poll() is None:
        try:
            procs = [root, *root.children(recursive=True)]
            peak = max(peak, float(sum(p.memory_info().rss for p in procs if p.is_running())))
        except psutil.Error:
            pass
        time.sleep(0.1)
    wall = time.perf_counter() - t0
    ru1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (ru1.ru_utime - ru0.ru_utime) + (ru1.ru_stime - ru0.ru_stime)
    out = proc.stdout.read() if proc.stdout else ""
    if proc.returncode:
        raise RuntimeError(f"{' '.join(argv)} failed ({proc.returncode}):\n{out[-3000:]}")
    return wall, peak, cpu, out.strip().splitlines()[-1] if out.strip() else ""


def case(engine: str, trees: int, workers: list[int], keep: bool) -> list[dict]:
    work = Path(tempfile.mkdtemp(prefix=f"district_bench_{engine}_{trees}_"))
    proj = work / "district"
    shutil.copytree(EXAMPLE, proj, ignore=shutil.ignore_patterns("build", "results", "report"))
    py = sys.executable
    subprocess.run([py, str(proj / "make_district.py"), "--trees", str(trees), "--out",
                    str(proj / "data")], check=True, capture_output=True)
    rows = []
    try:
        bwall, bpeak, bcpu, _ = run_measured([py, "-m", "radtree.cli", "build", str(proj),
                                        "-s", "trees"], work)
        for w in workers:
            swall, speak, scpu, tail = run_measured(
                [py, "-m", "radtree.cli", "simulate", str(proj), "-s", "trees", "--engine",
                 engine, "--scheduler", "local", "--workers", str(w), "--fresh"], work)
            rows.append({"engine": engine, "trees": trees, "workers": w, "build_s": bwall,
                         "build_peak_gib": bpeak / GIB, "build_cpu_s": bcpu,
                         "simulate_s": swall, "simulate_cpu_s": scpu,
                         "simulate_peak_gib": speak / GIB, "tail": tail})
            print(f"  {engine:8s} {trees:4d} trees  {w} worker(s): build {bwall:6.1f} s "
                  f"(CPU {bcpu:6.1f} s) {bpeak / GIB:5.2f} GiB | simulate 7 h {swall:7.1f} s "
                  f"(CPU {scpu:7.1f} s) {speak / GIB:5.2f} GiB, load "
                  f"{os.getloadavg()[0]:.1f}   ({tail})", flush=True)
    finally:
        if not keep:
            shutil.rmtree(work, ignore_errors=True)
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--engines", nargs="+", default=["radiance", "numpy"])
    ap.add_argument("--trees", nargs="+", type=int, default=[60, 240])
    ap.add_argument("--workers", nargs="+", type=int, default=[1, 2])
    ap.add_argument("--keep", action="store_true")
    args = ap.parse_args()
    print(f"district benchmark: {os.cpu_count()} cores, load {os.getloadavg()[0]:.1f}")
    rows = []
    for engine in args.engines:
        for n in args.trees:
            rows += case(engine, n, args.workers, args.keep)
    print("\nsummary (targets for Radiance: simulate ≤ 300 s on 2 workers, ≤ 2 GiB; "
          "240-tree build time and memory ≤ 1.3 × 60-tree):")
    for engine in args.engines:
        got = {(r["trees"], r["workers"]): r for r in rows if r["engine"] == engine}
        lo, hi = min(args.trees), max(args.trees)
        w = max(args.workers)
        if (lo, w) in got and (hi, w) in got:
            a, b = got[(lo, w)], got[(hi, w)]
            print(f"  {engine}: {hi}/{lo} trees — build time ×{b['build_s'] / a['build_s']:.2f} "
                  f"(CPU ×{b['build_cpu_s'] / a['build_cpu_s']:.2f}), "
                  f"build memory ×{b['build_peak_gib'] / a['build_peak_gib']:.2f}, simulate "
                  f"time ×{b['simulate_s'] / a['simulate_s']:.2f} (CPU "
                  f"×{b['simulate_cpu_s'] / a['simulate_cpu_s']:.2f}), simulate memory "
                  f"×{b['simulate_peak_gib'] / a['simulate_peak_gib']:.2f}; worst simulate "
                  f"{max(r['simulate_s'] for r in got.values()):.0f} s, peak "
                  f"{max(r['simulate_peak_gib'] for r in got.values()):.2f} GiB")


if __name__ == "__main__":
    from _common import print_resources_at_exit  # benchmarks/_common.py

    print_resources_at_exit()
    main()
