"""Three-phase annual against the default annual (daylight coefficients) on the office example.

Copies ``examples/office-block`` twice into ``--work`` (kept, so a rerun reuses the crown BSDFs
and every cached matrix: pass a fresh folder to time from scratch), runs

**Sun runs** (``--sun-runs``): with ``sun_crown = "explicit"`` the 3-phase method's direct and
reflected sun *are* the default method's rcontrib runs (in one project ``--method 3phase``
reuses them). The two methods run in two copies of the project, so by default (``shared``)
the default method's sun coefficients (``results/annual/coefficients/{leaf_on,leaf_off}/
sun_*.npy``, the same file names: the same inputs) are copied into the 3-phase copy before
it runs, as one project would hold them, and the comparison measures the sky part, the only
part the methods compute differently. ``own`` traces them again in the 3-phase copy (an
existing copy is kept: delete ``3phase/results/annual/coefficients/leaf_*/sun_*`` for a
fresh realisation); the difference then also holds the Monte Carlo noise of two runs of
the same reflected-sun computation (measured on the office example, leaf-on work plane:
±34 % per point, 3.5 pp of UDI < 100 lx; README, three-phase section). The scene without
the tree is always traced in each copy (its difference is that noise floor without a crown).

Options: ``--sun-crowns explicit,bsdf,fivephase`` (``AnnualOptions.sun_crown`` variants of
the 3-phase run, the later ones reusing the first's matrices: the sun runs through the
explicit crown, as the default method's, on the BSDF crown, or by the five-phase idea,
:mod:`radtree.annual.fivephase`), ``--no-second-weather`` (a quicker comparison);
``--samples 50 --daylight-samples 100`` is a quicker variant (≈ 9 min from scratch at load
2–5 on 2 cores, of which the BSDFs 396 s).

1. ``radtree annual`` (``--method dc``: rcontrib daylight coefficients of the explicit slat
   crown, leaf-on and bare-branch scenes);
2. ``radtree annual --method 3phase`` (crown BSDFs leaf-on/off with ``tree.bsdf.samples``
   rays per Klems patch, view matrix, daylight matrices, rmtxop; the sun as the default method
   on the BSDF-crown scenes);
3. both again with a second weather file (the project's EPW with its direct normal
   irradiance × 0.6 and its diffuse × 1.4, written to ``--work``): what a second weather file
   costs each method once its coefficients/matrices exist;

and prints, per grid, sDA300/50 and the UDI bands of both methods (with the tree: leaf-on or
bare by the schedule; and without), their differences in percentage points, the wall and CPU
times and the cost of the second leaf state (3-phase: its daylight matrices, rmtxop and the
sun runs on the bare BSDF crown; dc: the rcontrib runs of the bare-branch scene).

Measured 2026-12-07 (``--samples 50 --daylight-samples 100 --sun-crowns
fivephase,explicit,bsdf --no-second-weather``, facet-plane grouping, load 4–9 on 2 cores;
3-phase 1 151 s wall): 3-phase − dc on every band and sDA, façade / work plane, with the
tree — ``explicit`` within 0.5 pp on both; ``bsdf`` up to +14.2 pp (work plane UDI <100);
``fivephase`` up to +9.0 / +14.9 pp (UDI <100; the difference of two noisy BSDF sun runs
per sensor-hour, :mod:`radtree.annual.fivephase`; CHANGELOG.md).

Measured again 2026-12-07 16:58–17:10 UTC with the BSDF shell as ``aBSDF`` (the default
since; ``--sun-crowns fivephase,bsdf,explicit``, otherwise as above, the earlier run's
folder copied so its BSDFs and dc runs were reused; load 4.5–7.7; 3-phase 625 s wall, of it
the leaf-on sun runs 247 s): ``fivephase`` façade within 1.1 pp on every band (UDI <100
+0.9, 100–300 +1.0, 300–3000 −1.1, >3000 −0.8), work plane UDI <100 +5.2, 100–300 −5.8,
300–3000 −0.3, >3000 +0.9, sDA 0 — **met on the façade, not on the work plane**; ``bsdf``
façade within 2.2 pp (>3000 +2.2), work plane UDI <100 +8.1, 100–300 −8.5, sDA −2.5;
``explicit`` within 0.5 pp as before.

Measured again 2026-12-08 01:27 UTC with the crown XMLs reciprocal patch by patch
(:func:`radtree.engines.radiance.bsdf.reciprocal_patches`; the same command and folder, so the
dc runs were reused and the BSDFs regenerated; load 2–3.4; 3-phase 511 s wall, the BSDFs
222 s): ``fivephase`` façade within 0.9 pp on every band (UDI <100 +0.9, 100–300 +0.7,
300–3000 −0.9, >3000 −0.7), work plane UDI <100 **+4.7**, 100–300 **−5.4**, 300–3000 −0.1,
>3000 +0.7, sDA **+5.0** (7.5 against 2.5 %: the grid's few sensors above the line) — still
**not met on the work plane**; ``bsdf`` work plane UDI <100 +7.1, 100–300 −7.5, sDA −2.5;
``explicit`` within 0.5 pp.

Run: ``nice .venv/bin/python benchmarks/threephase.py [--work DIR] [--samples 200] [-j 2]``.

Measured again 2026-12-08 03:53–03:59 UTC after the three-phase closure fixes (one facet
group per crown; the room-side daylight matrices traced into the room; the 01:27 folder
copied, load 2–3.4; the benchmark 370 s wall): ``fivephase`` façade UDI <100 +1.1, 100–300
+1.2, 300–3000 −1.5, >3000 −0.9, work plane sDA +2.5, UDI <100 +4.9, 100–300 −5.5,
300–3000 −0.1, >3000 +0.7 — the work plane's miss is unchanged; ``explicit``, whose sky
is the same chain, within 0.5 pp: the miss is in the five-phase sun.

Measured again 2026-12-08 04:52–05:00 UTC after the third fix (free crowns' T no longer
mirrored left/right, ``sender_text(material_faces_room=False)``; the 01:27 folder copied
afresh to /tmp/fp_s26, load 1.6–2.7, 262 s wall): ``fivephase`` façade UDI <100 +1.1,
100–300 +1.2, 300–3000 −1.5, >3000 −0.8 (sDA 0.0); work plane sDA +5.0, UDI <100 **+4.9**,
100–300 **−5.5**, 300–3000 −0.0, >3000 +0.7 — **not met on the work plane**, unchanged by the
chain fixes; ``bsdf`` work plane UDI <100 +7.2, 100–300 −7.5, sDA −2.5; ``explicit``
within 0.5 pp on both grids (its sky is the fixed chain).
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import radtree.log  # noqa: E402
from radtree.annual.methods import compute as compute_annual  # noqa: E402
from radtree.annual.report import summarise  # noqa: E402
from radtree.annual.run import AnnualOptions, AnnualResult  # noqa: E402
from radtree.annual.tables import annual_tables  # noqa: E402
from radtree.config import load_project  # noqa: E402

COLUMNS = ["sda_300_50", "udi_below_100", "udi_100_300", "udi_300_3000", "udi_above_3000"]


def cpu_seconds() -> float:
    """User + system CPU of this process and its finished children (Radiance programs)."""
    own = resource.getrusage(resource.RUSAGE_SELF)
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def timed(project_dir: Path, options: AnnualOptions, overrides: dict | None = None
          ) -> tuple[AnnualResult, float, float]:
    project = load_project(project_dir, overrides=overrides)
    t0, c0 = time.perf_counter(), cpu_seconds()
    radtree.log.enable(progress=False)   # the run's messages, as it goes
    result = compute_annual(project, options=options)
    return result, time.perf_counter() - t0, cpu_seconds() - c0


def figures(result: AnnualResult) -> pd.DataFrame:
    annual, summary, _ = annual_tables(result)
    return summarise(annual, summary).set_index(["grid", "tree"])[COLUMNS]


def second_weather(epw: Path, dest: Path) -> Path:
    """The EPW with DNI (field 15) × 0.6 and DHI (field 16) × 1.4 (epw2wea reads these two):
    a cloudier year at the same site, so the same sun positions."""
    lines = epw.read_text().splitlines()
    out = lines[:8]
    for line in lines[8:]:
        f = line.split(",")
        if len(f) > 16:
            dni, dhi = float(f[14]) * 0.6, float(f[15]) * 1.4
            f[14], f[15] = f"{dni:.0f}", f"{dhi:.0f}"
        out.append(",".join(f))
    dest.write_text("\n".join(out) + "\n")
    return dest


def share_sun_runs(src: Path, dest: Path) -> int:
    """Copy the default method's sun coefficients of both leaf states from the project copy
    ``src`` into ``dest`` (same names: the cache key is the runs' input); their number."""
    n = 0
    for state in ("leaf_on", "leaf_off"):
        folder = src / "results" / "annual" / "coefficients" / state
        target = dest / "results" / "annual" / "coefficients" / state
        target.mkdir(parents=True, exist_ok=True)
        for f in sorted(folder.glob("sun_*.npy")):
            shutil.copy2(f, target / f.name)
            n += 1
    return n


def same_crown(project_dir: Path, overrides: dict, r3: AnnualResult) -> AnnualResult:
    """The 3-phase year with its sky part replaced by the default method's rcontrib sky
    coefficients traced on the same BSDF-crown scenes (both leaf states; the sun terms are
    the same runs in both): the matrices' own error, without the crown's representation."""
    from dataclasses import replace

    from radtree.annual.coefficients import CoefficientRunner
    from radtree.annual.phenology import crown_year, phenology_of
    from radtree.annual.skymatrix import sky_matrix
    from radtree.annual.threephase import (
        STATES,
        ThreePhase,
        _scene_with,
        crown_models,
        sky_lux,
        state_xmls,
    )
    from radtree.pipeline.assemble import make_scene

    project = load_project(project_dir, overrides=overrides)
    sc = project.scenario(r3.scenarios["with"])
    models, form = crown_models(project, sc, state_xmls(project, sc))
    bare = make_scene(project, replace(sc, model="none"), dense_grid=False).scene
    grids, rho, mf = list(r3.grids), r3.ground_reflectance, r3.options.mf
    sky = sky_matrix(r3.wea, mf, rho)
    work = project.results_dir / "annual" / "threephase"
    tp = ThreePhase(work, bare=bare, models=models, form=form, grids=grids, rho=rho, mf=mf,
                    trace=r3.trace, samples=r3.options.daylight_samples)
    views, v_sky = tp.view()
    total = {k: dict(v) for k, v in r3.total.items()}
    direct = {k: dict(v) for k, v in r3.direct.items()}
    for state in STATES:
        runner = CoefficientRunner(_scene_with(bare, models[state]), grids,
                                   work / f"sun_{state}", rho)
        diff = sky_lux(runner.sky(mf, r3.trace), sky) - sky_lux(
            tp.coefficients(state, views, v_sky), sky)
        start = 0
        for g in grids:
            n = len(r3.grids[g]["points"])
            total[state][g] = (r3.total[state][g] + diff[start:start + n]).astype(np.float32)
            start += n
    crown_year(total, direct, grids, r3.wea, r3.options.leaf,
               phenology_of(project, r3.options.species_phenology))
    return replace(r3, total=total, direct=direct)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--work", type=Path, default=Path("/tmp/threephase_bench"))
    ap.add_argument("--samples", type=int, default=200, help="tree.bsdf.samples")
    ap.add_argument("--daylight-samples", type=int, default=400, help="rfluxmtx -c of D")
    ap.add_argument("-j", "--processes", type=int, default=2)
    ap.add_argument("--same-crown", action="store_true",
                    help="also trace rcontrib sky coefficients on the 3-phase BSDF crowns")
    ap.add_argument("--methods", default="dc,3phase", help="comma-separated: dc, 3phase")
    ap.add_argument("--sun-crowns", default="explicit,bsdf",
                    help="3phase variants run in turn (AnnualOptions.sun_crown: explicit, bsdf, "
                         "fivephase): the first is "
                         "'3phase' (timed, second weather file), the others reuse its matrices")
    ap.add_argument("--sun-runs", choices=("shared", "own"), default="shared",
                    help="shared: the 3-phase copy uses the default method's sun runs (as one "
                         "project does); own: it traces its own (module text)")
    ap.add_argument("--no-second-weather", action="store_true",
                    help="skip the second weather file (a quicker comparison)")
    args = ap.parse_args()
    methods = [m for m in ("dc", "3phase") if m in args.methods.split(",")]
    sun_crowns = args.sun_crowns.split(",")
    src = ROOT / "examples" / "office-block"
    args.work.mkdir(parents=True, exist_ok=True)
    dirs = {}
    for m in methods:
        dirs[m] = args.work / m
        if not dirs[m].exists():
            shutil.copytree(src, dirs[m], ignore=shutil.ignore_patterns("build", "results"))
    over = {"tree.bsdf.samples": args.samples}
    print(f"three-phase benchmark on {src} → {args.work}; load {os.getloadavg()}")
    runs: dict[str, tuple[AnnualResult, float, float]] = {}
    for m in methods:
        print(f"\n== {m}", flush=True)
        if m == "3phase" and args.sun_runs == "shared" and "dc" in dirs:
            print(f"  sun runs: {share_sun_runs(dirs['dc'], dirs[m])} files of the default "
                  "method's copy", flush=True)
        opts = AnnualOptions(nproc=args.processes, method=m, sun_crown=sun_crowns[0],
                             daylight_samples=args.daylight_samples, replicates=1)
        runs[m] = timed(dirs[m], opts, over)
    variants: dict[str, tuple[AnnualResult, float, float]] = {}
    if "3phase" in runs:
        variants[sun_crowns[0]] = runs["3phase"]
        for sc in sun_crowns[1:]:
            print(f"\n== 3phase, sun crown {sc} (matrices reused)", flush=True)
            opts = AnnualOptions(nproc=args.processes, method="3phase", sun_crown=sc,
                                 daylight_samples=args.daylight_samples)
            variants[sc] = timed(dirs["3phase"], opts, over)
    again: dict[str, tuple[AnnualResult, float, float]] = {}
    if not args.no_second_weather:
        epw2 = second_weather(runs[methods[0]][0].weather.path,
                              args.work / "second_weather.epw")
        for m in methods:
            print(f"\n== {m}, second weather file", flush=True)
            opts = AnnualOptions(nproc=args.processes, method=m, epw=epw2,
                                 sun_crown=sun_crowns[0],
                                 daylight_samples=args.daylight_samples, replicates=1)
            again[m] = timed(dirs[m], opts, over)

    pd.set_option("display.width", 250)
    pd.set_option("display.max_columns", None)
    for label, pair in (("project weather", runs), ("second weather file", again)):
        for m, (r, _, _) in pair.items():
            print(f"\n{label}, {m}:")
            print(figures(r).round(1))
    if args.same_crown and "3phase" in runs:
        ref = same_crown(dirs["3phase"], over, runs["3phase"][0])
        a, b = figures(ref), figures(runs["3phase"][0])
        print("\nsame BSDF crown: rcontrib sky | 3-phase sky | difference (percentage points)")
        print(pd.concat({"rcontrib": a, "3phase": b, "diff_pp": b - a}, axis=1).round(1))
    for label, pair in (("project weather", runs), ("second weather file", again)):
        if len(pair) < 2:
            continue
        a, b = figures(pair["dc"][0]), figures(pair["3phase"][0])
        print(f"\n{label}: dc | 3phase | 3phase − dc (percentage points)")
        print(pd.concat({"dc": a, "3phase": b, "diff_pp": b - a}, axis=1).round(1))
        print("largest |difference|: "
              + ", ".join(f"{g}/{t} {float(np.abs((b - a).loc[(g, t)]).max()):.1f} pp"
                          for g, t in a.index))
    if "dc" in runs and len(variants) > 1:
        a = figures(runs["dc"][0])
        rows = {"dc": a}
        for sc, (r, _, _) in variants.items():
            rows[f"3phase sun={sc}"] = figures(r)
            rows[f"diff_pp sun={sc}"] = figures(r) - a
        print("\n3-phase sun variants against dc (percentage points), with the tree:")
        table = pd.concat(rows, axis=0, names=["run"]).xs("with", level="tree")
        print(table.round(1))
        for sc, (r, wall, cpu) in variants.items():
            print(f"  sun={sc}: wall {wall:.1f} s, CPU {cpu:.1f} s, sun runs "
                  + ", ".join(f"{s} {r.timing.get(f'{s}_sun_s', float('nan')):.1f} s"
                              for s in ("leaf_on", "leaf_off")))
    print(f"\nload now {os.getloadavg()}")
    for label, pair in (("project weather", runs), ("second weather file", again)):
        for m, (r, wall, cpu) in pair.items():
            print(f"{label:20s} {m:7s} wall {wall:8.1f} s, CPU {cpu:8.1f} s")
            for k, v in r.timing.items():
                print(f"    {k:32s} {v:8.1f} s")
    if "dc" in runs:
        print("\nsecond leaf state, dc: rcontrib of the bare-branch scene "
              f"{runs['dc'][0].timing.get('leaf_off_s', float('nan')):.1f} s")
    if "3phase" in runs:
        t3 = runs["3phase"][0].timing
        print("second leaf state, 3-phase: daylight matrices "
              f"{t3.get('3phase_daylight_leaf_off_s', 0.0):.1f} s + room side "
              f"{t3.get('3phase_daylight_room_leaf_off_s', 0.0):.1f} s + rmtxop "
              f"{t3.get('3phase_rmtxop_leaf_off_s', 0.0):.1f} s + sky product "
              f"{t3.get('leaf_off_sky_product_s', 0.0):.1f} s (with its sun runs "
              f"{t3.get('leaf_off_s', 0.0):.1f} s)")


if __name__ == "__main__":
    from _common import print_resources_at_exit  # benchmarks/_common.py

    print_resources_at_exit()
    main()
