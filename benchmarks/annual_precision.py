"""How precise is ``radtree annual``? The spread of sDA, DA and UDI between independent runs.

On ``examples/honeybee-office`` (two grids of 96 work-plane sensors; the year of the run: the
generated clear-sky EPW), the scenes without the crown and with the leafed crown are traced
with ``TraceParams.replicates`` R: every coefficient R times with independent sample
sequences (:mod:`radtree.annual.uncertainty`). Each replicate is one run of ``radtree annual``
at that ``-ad`` (the reflected-sun run at its default ``-ad`` ÷ 4, ``-lw`` ≥ 1e-3); the
spread of a metric over the replicates is the run-to-run spread a user sees. The mean of the
R replicates is a run at ≈ R × ``-ad``, and its jackknife SE is printed beside the SD / √R
the replicates imply.

Run: ``.venv/bin/python benchmarks/annual_precision.py [--ad 1024 4096] [--replicates 8]``.
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SHOWN = ("DA300", "sDA", "UDI<100", "UDI100-3000", "UDI>3000")


def main() -> int:
    from radtree.annual.coefficients import CoefficientRunner
    from radtree.annual.metrics import daylight_autonomy
    from radtree.annual.run import AnnualOptions, plan_annual, plan_year, with_season
    from radtree.annual.schedule import occupied
    from radtree.annual.uncertainty import (
        grid_metrics,
        jackknife,
        metrics_se,
        sda_se,
        year_replicates,
    )
    from radtree.config import load_project

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--ad", type=int, nargs="+", default=[1024, 4096])
    ap.add_argument("--replicates", type=int, default=8)
    ap.add_argument("--sun-ad", type=int, help="reflected-sun -ad (default: -ad ÷ 4, ≥ 128)")
    ap.add_argument("--variants", nargs="+", default=["without", "leaf_on"])
    ap.add_argument("--processes", type=int, default=2)
    ap.add_argument("--work", type=Path, help="work folder (default: a temporary one)")
    args = ap.parse_args()
    work = args.work or Path(tempfile.mkdtemp(prefix="annual_precision_"))
    project_dir = work / "honeybee-office"
    if not project_dir.exists():
        shutil.copytree(ROOT / "examples" / "honeybee-office", project_dir)
        shutil.copytree(ROOT / "examples" / "office-block" / "data",
                        work / "office-block" / "data")
    project = load_project(project_dir)
    options = with_season(project, AnnualOptions(nproc=args.processes))
    for ad in args.ad:
        plan = plan_annual(project, replace(options, ad=ad, sun_ad=args.sun_ad))
        trace = replace(plan.trace, replicates=args.replicates)
        sun_trace = replace(plan.sun_trace, replicates=args.replicates)
        year = plan_year(project, plan)
        occ = occupied(year[1].hour, options.occupancy)
        print(f"-ab {trace.ab} -ad {trace.ad} -lw {trace.lw:g}; reflected sun -ad "
              f"{sun_trace.ad} -lw {sun_trace.lw:g}; {args.replicates} replicates")
        for variant in args.variants:
            scene = plan.scenes[variant]
            t0 = time.perf_counter()
            runner = CoefficientRunner(scene, plan.grids, work / f"ad{ad}" / variant, plan.rho)
            reps = [tot for tot, _ in year_replicates(runner, year, options.mf,
                                                      options.sun_mf, trace, sun_trace)]
            wall = time.perf_counter() - t0
            start = 0
            for g in plan.grids:
                n = len(scene.grids[g])
                rows = [r[start:start + n] for r in reps]
                start += n
                single = {k: np.array([grid_metrics(r, occ)[k] for r in rows]) for k in SHOWN}
                est, se = metrics_se(rows, occ)
                # one run's sDA SE predicted from the sensors: its DA SE is √R × the mean's
                _, da_se = jackknife(rows, lambda e, o=occ: {"da": daylight_autonomy(e, o)})
                da_mean = daylight_autonomy(np.mean(rows, axis=0), occ)
                one_sda = sda_se(da_mean, np.sqrt(len(rows)) * da_se["da"])
                cells = "; ".join(
                    f"{k} {v.mean():.1f} sd {v.std(ddof=1):.2f} [{v.min():.1f}–{v.max():.1f}]"
                    for k, v in single.items())
                print(f"  {variant:<8} {g:<9} one run: {cells}")
                cells = "; ".join(f"{k} {est[k]:.1f} ± {se[k]:.2f} (sd/√R "
                                  f"{single[k].std(ddof=1) / np.sqrt(len(rows)):.2f})"
                                  for k in SHOWN)
                print(f"  {'':<8} {g:<9} mean of {len(rows)}: {cells}; one run's sDA SE "
                      f"predicted {one_sda:.2f} (observed sd {single['sDA'].std(ddof=1):.2f})")
            print(f"  {variant}: {wall:.0f} s wall for {args.replicates} replicates "
                  f"({wall / args.replicates:.0f} s per run)")
    print(f"(work folder {work})")
    return 0


if __name__ == "__main__":
    from _common import print_resources_at_exit

    print_resources_at_exit()
    sys.exit(main())
