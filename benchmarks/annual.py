"""Annual-run benchmark: wall time of the full annual office run (8760 h, three scenes).

Copies the example project to a scratch folder (``/tmp/annual_bench_*``, removed afterwards
unless ``--keep``), runs ``radtree annual`` from scratch (no cached coefficients) with two
``rcontrib`` processes, and prints the wall time split into scenes, weather and each
scene's coefficients, then the key annual figures (sDA, ASE, UDI with and without the tree).

``--validate`` also traces a few hours point-in-time with ``rtrace`` (same scene and
``-ab``, ``gendaylit -W`` from the same WEA rows; converged sampling ``-ad ≥ 4096 -lw 1e-5``
— at the project's ``-ad 1024 -lw 2e-4`` rtrace reads the office work plane 5–8 % low) for
the scenes without tree and with the leafed crown, and prints the grid-mean ratio
annual / point-in-time per hour.

Uses ``examples/office-block``; when that example is missing, the street example (façade
grid only) and says so.

Run: ``.venv/bin/python benchmarks/annual.py [--validate] [--keep] [-j 2]``.
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import radtree.log  # noqa: E402
from radtree.annual.publish import run_annual  # noqa: E402
from radtree.annual.report import grid_summary  # noqa: E402
from radtree.annual.run import AnnualOptions, AnnualResult, annual_scenes  # noqa: E402
from radtree.config import load_project  # noqa: E402

VALIDATE_HOURS = [(12, 22, 12.5), (6, 21, 12.5), (3, 20, 9.5)]


def validate(result: AnnualResult, work: Path) -> None:
    """Point-in-time rtrace against the annual values for a few hours
    (:func:`radtree.verify.annual.point_in_time`, as ``radtree verify --full``'s annual rows)."""
    from radtree.annual.coefficients import scene_text
    from radtree.annual.run import choose_scenarios
    from radtree.verify.annual import hour_index, point_in_time

    project, wea = result.project, result.wea
    with_sc, without_sc, _ = choose_scenarios(project, result.options)
    scenes, grids, _, _ = annual_scenes(project, with_sc, without_sc, result.options.branches,
                                        result.options.grids)
    t = result.trace
    rho = result.ground_reflectance
    for variant in ("without", "leaf_on"):
        scene = scenes[variant]
        rad = work / f"validate_{variant}.rad"
        rad.write_text(scene_text(scene, rho))
        for m, d, h in VALIDATE_HOURS:
            i = hour_index(wea, m, d, h)
            t0 = time.perf_counter()
            ref, _ = point_in_time(scene, rad, wea, i, work, max(4 * t.ad, 4096),
                                   grids=tuple(grids), rho=rho, ab=t.ab)
            secs = time.perf_counter() - t0
            start = 0
            parts = []
            for g in grids:
                n = len(scene.grids[g])
                ann = result.total[variant][g][:, i]
                r = ref[start:start + n]
                parts.append(f"{g} mean {ann.mean():8.0f} vs {r.mean():8.0f} lx "
                             f"(ratio {ann.mean() / max(r.mean(), 1e-9):.3f})")
                start += n
            print(f"  validate {variant:8s} {m:02d}-{d:02d} {h:5.2f} h: " + "; ".join(parts)
                  + f"  [rtrace {secs:.0f} s]")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--validate", action="store_true", help="compare hours with rtrace")
    ap.add_argument("--keep", action="store_true", help="keep the scratch copy")
    ap.add_argument("-j", "--processes", type=int, default=2)
    args = ap.parse_args()
    src = ROOT / "examples" / "office-block"
    note = "office example"
    if not (src / "radtree.toml").exists():
        src = ROOT / "examples" / "mendoza-street"
        note = "office example not found: street example (façade grid) instead"
    work = Path(tempfile.mkdtemp(prefix="annual_bench_", dir="/tmp"))
    dst = work / src.name
    shutil.copytree(src, dst, ignore=shutil.ignore_patterns("build", "results", "report",
                                                            "sweep", "diagnose"))
    print(f"annual benchmark: {note} → {dst}")
    try:
        project = load_project(dst)
        t0 = time.perf_counter()
        radtree.log.enable(progress=False)   # the run's messages, as it goes
        out = run_annual(project, options=AnnualOptions(nproc=args.processes), figures=True)
        wall = time.perf_counter() - t0
        r = out.result
        print(f"\nwall time of the full annual run ({args.processes} rcontrib processes): "
              f"{wall:.1f} s ({wall / 60:.2f} min)")
        for k, v in r.timing.items():
            print(f"  {k:12s} {v:8.1f} s")
        print(f"  weather: {r.weather.description}")
        print(f"  rcontrib -ab {r.trace.ab} -ad {r.trace.ad} -lw {r.trace.lw:g}; reflected sun "
              f"-ad {r.sun_trace.ad} -lw {r.sun_trace.lw:g}")
        for row in grid_summary(project).itertuples(index=False):
            print(f"  {row.grid:>10} {row.tree:>7}: sDA300/50% {row.sda_300_50:5.1f} %, "
                  f"ASE1000,250 {row.ase_1000_250:5.1f} %, UDI <100 {row.udi_below_100:5.1f}, "
                  f"100–300 {row.udi_100_300:5.1f}, 300–3000 {row.udi_300_3000:5.1f}, "
                  f">3000 {row.udi_above_3000:5.1f} %, DA300 {row.da_300:5.1f} %")
        if args.validate:
            validate(r, work)
    finally:
        if args.keep:
            print(f"kept {work}")
        else:
            shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    from _common import print_resources_at_exit  # benchmarks/_common.py

    print_resources_at_exit()
    main()
