"""How precise is ``radtree annual``? The spread of sDA, DA and UDI between independent runs.

On ``examples/honeybee-office`` (two grids of 96 work-plane sensors; the year of the run: the
generated clear-sky EPW), the scenes without the crown and with the leafed crown are traced
with ``TraceParams.replicates`` R: every coefficient R times with independent sample
sequences (:mod:`radtree.annual.uncertainty`). Each replicate is one run of ``radtree annual``
at that ``-ad`` (the reflected-sun run at its default ``-ad`` ÷ 4, ``-lw`` ≥ 1e-3); the
spread of a metric over the replicates is the run-to-run spread a user sees. The mean of the
R replicates is a run at ≈ R × ``-ad``, and its jackknife SE is printed beside the SD / √R
the replicates imply.

Measured 2026-12-07 11:50–12:30 UTC, load 11–28 (≈ 6 sessions on 2 cores), ``--ad 1024
--replicates 6`` (the defaults: reflected sun ``-ad 256 -lw 1e-3``); per grid, one run's
mean ± SD over the 6 passes [range], and the 6 passes' mean ± its SE:

    scene     grid      one run: DA300     sDA                UDI<100           UDI100-3000
    no crown  Office_1  74.7 ± 0.46   78.8 ± 1.82 [77.1–82.3]   4.6 ± 0.06   85.7 ± 0.06
              Office_2  74.6 ± 0.56   78.5 ± 1.57 [76.0–80.2]   4.6 ± 0.09   85.6 ± 0.09
    leafed    Office_1  53.8 ± 0.38   56.1 ± 1.79 [53.1–58.3]  15.2 ± 0.36   79.0 ± 0.36
              Office_2  37.5 ± 0.62   39.6 ± 1.61 [37.5–41.7]  15.5 ± 1.04   81.3 ± 1.04
    mean of 6 (SE): DA 74.8 ± 0.25, 74.7 ± 0.30, 54.1 ± 0.16, 37.8 ± 0.32; sDA 79.2 ± 0.8,
    77.1 ± 1.2, 56.2 ± 1.2, 40.6 ± 0.8 (sensors); UDI<100 4.5, 4.5, 14.7 ± 0.2, 13.3 ± 0.3.

* UDI above 3000 lx moves ≤ 0.01 pp (the direct sun is exact); UDI below 100 lx of a single
  run is biased high where it is noisy (office 2 with the crown: 15.5 for one pass, 13.3 for
  the mean of 6 — noise spreads the low values below 100 lx).
* sDA: one pass at -ad 1024 has an SD of 1.6–1.8 pp (5 pp range over 6 runs), more than
  DA's 0.4–0.6: it counts 96 sensors, each 1.04 pp. The sensors' estimate
  (:func:`radtree.annual.uncertainty.sda_se`, from the 6 passes' DA SEs × √6) predicts
  1.55–1.57 pp for one pass (observed 1.57–1.82); the jackknife of sDA itself reads 0.00 on
  two of the four grids (no leave-one-out flipped a sensor), hence the sensors' estimate.
  sDA's SE falls as R^-¼, not R^-½ (sensors within ~1 SE of DA 50 % flip): 4 passes ≈ 1.1 pp,
  16 ≈ 0.8 pp — a default that reports it rather than one that hides it: ``radtree annual``
  now runs 4 passes and prints every metric's SE.
* Per sensor, one pass's mean lux over the hours without direct sun moves 7 % (SD/mean, sky
  part 9 %, reflected sun 11 %): a sensor deep in the room sees the window in a small solid
  angle, so few of its 1024 ambient samples reach the sky.
* Cost: 1 pass of both scenes 60 s CPU (362 s CPU for 6 passes of the two scenes, 100 s and
  288 s wall per pass at load ≈ 25); ``radtree annual`` on the example, three scenes: one
  pass (the old default) 84 s CPU, 354 s wall at load ≈ 11; four (the new default) 304 s
  CPU, 604 s wall at load 15–20 — 3.6 × (the direct sun at ``-ab 0`` is traced once).

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
