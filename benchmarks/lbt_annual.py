"""Ladybug Tools' own annual-daylight recipes against ``radtree annual`` on the same Honeybee
model, crowns and weather (issue 40, item 3b).

Steps (in a temporary copy of ``examples/honeybee-office``):

1. ``radtree annual`` (its defaults: ``-ab 4 -ad 1024 -lw 1e-4``, daylight coefficients, the
   generated clear-sky year of the site, occupancy 8–18) → ``results/annual/hourly.npz``:
   every grid's hourly lux for the leafed crown (``leaf_on``), the bare crown and no crown.
2. ``radtree export --format honeybee-scene`` of the scenarios ``model`` (no crown: radtree's
   ground plane only) and ``crown`` (every leaf, trunk and the ground as ShadeMesh with their
   Radiance modifiers, :mod:`radtree.export.honeybee_scene`) → two HBJSON models.
3. lbt-recipes' ``annual-daylight`` (one daylight-coefficient run, the sun smeared over the 145
   Reinhart patches of its ``sky_type total`` matrix) and ``annual-daylight-enhanced`` (2-phase:
   total sky − direct sky + the exact direct sun) on each model, with queenbee-local, Radiance
   from the ``pyradiance`` wheel, the same EPW and the same radiance parameters
   (``--lbt-params``), run by ``--lbt-python`` (an interpreter with ``pip install
   'radtree[lbt]'``, or a separate venv with ``lbt-recipes queenbee-local pyradiance``: they
   pull ~750 MB, cupy among them, so they are not part of ``make install``).
4. The same metrics from both hourly arrays and radtree's occupied hours (the recipe's own DA
   file equals this recomputation: its schedule is the same 8–18): DA300, sDA300/50, UDI
   below 100 / 100–3000 / above 3000 lx, mean lux; a static leafed crown all year in both (the
   recipe knows no seasons; radtree's seasonal result is printed beside).
5. An exact reference at ``--reference-hours`` diffuse-dominated hours (radtree total 200–400
   lx, no direct sun): ``gendaylit`` with the EPW's DNI/DHI at the hour's middle, ``rtrace -ab 4
   -ad 8192 -lw 1e-5`` on radtree's build of the model, the office 1 grid.

Measured 2026-12-07 09:06–09:24 UTC (load 6–9: helper sessions running; 1 039 s wall),
lbt-recipes 0.29.1, queenbee-local 1.0.3, honeybee-radiance 1.66.299, ``--lbt-params "-ab 4
-ad 8192 -lw 1e-5 -dr 0"``; radtree/lbt per metric, lbt − radtree in pp:

    recipe    scene  grid      DA300          sDA            UDI<100       UDI100-3000    UDI>3000     lux ratio
    enhanced  model  Office_1  74.1/69.8 −4.3  77.1/71.9 −5.2  4.6/5.7 +1.1  85.7/84.5 −1.2  9.7/9.9 +0.2  0.988
    enhanced  model  Office_2  74.6/69.1 −5.5  78.1/72.9 −5.2  4.6/5.4 +0.8  85.6/84.7 −0.9  9.8/9.9 +0.1  0.988
    enhanced  crown  Office_1  54.3/48.6 −5.7  58.3/50.0 −8.3  15.0/17.2 +2.2 79.2/76.9 −2.3  5.8/5.9 +0.1  0.984
    enhanced  crown  Office_2  37.0/34.3 −2.7  38.5/37.5 −1.0  15.4/22.5 +7.1 81.4/74.4 −7.0  3.2/3.2 −0.0  0.971
    plain     model  Office_1  74.1/69.9 −4.1  77.1/72.9 −4.2  4.6/5.5 +0.9  85.7/79.4 −6.4  9.7/15.1 +5.5 0.929
    plain     model  Office_2  74.6/69.9 −4.7  78.1/70.8 −7.3  4.6/5.3 +0.7  85.6/79.6 −6.1  9.8/15.1 +5.3 0.925
    plain     crown  Office_1  54.3/50.4 −3.9  58.3/54.2 −4.2  15.0/17.3 +2.3 79.2/73.2 −6.0  5.8/9.5 +3.6  0.912
    plain     crown  Office_2  37.0/35.9 −1.2  38.5/36.5 −2.1  15.4/22.2 +6.8 81.4/72.8 −8.7  3.2/5.0 +1.8  0.897

  (radtree with its leaf season, which the recipes cannot model: sDA 65.6 and 44.8.)

* Scene check first (independent of the annual methods): a uniform sky traced by ``rtrace
  -ab 4 -ad 8192`` on radtree's build of the model and on the recipe's translation of the
  exported HBJSON: 0.09658 vs 0.09665 (0.08 %).
* Exact reference, 8 diffuse-dominated hours (office 1, no crown): radtree 1.008–1.023 of the
  hourly rtrace at 6 hours, the enhanced recipe 0.966–1.000; at the other 2 (October mornings,
  the sun just behind the opposite building) radtree 1.126–1.156 and lbt 1.113–1.154: both
  annual methods take reflected sun from sky patches that straddle the building's edge.
* radtree annual moved between fresh runs when this was measured (an earlier run of the same
  command read sDA 81.2 / 82.3 without and 59.4 / 36.5 with the crown, and 0.997–1.007 of the
  reference at those 6 hours): ``rcontrib -n 2`` let its two children take rays as they came
  free. Since then the points are split into fixed chunks, one single-process rcontrib each
  (:mod:`radtree.annual.coefficients`): two fresh ``-j 2`` runs are bit-identical
  (``tests/test_annual_determinism.py``); a fresh run now differs from the table's radtree
  column by that same Monte Carlo spread (≈ 4 pp of sDA), itself larger than the 3 pp target.
* Where they differ: in diffuse-dominated hours (radtree 200–400 lx) the enhanced recipe reads
  a median 0.89–0.91 of radtree; DA and sDA count hours and sensors across 300 lx, so a few
  per cent near 300 lx move them by 5–10 pp. The plain recipe smears the sun over the sky
  patches: UDI above 3 000 lx +1.8 … +5.5 pp, mean lux 0.90–0.93. At the recipe's ``-ad 1024``
  (with its fixed ``-aa 0``) each sensor's hourly value is noisy enough to move UDI below
  100 lx by 6–19 pp.
* Target (issue 40, 3b: sDA, ASE, UDI within 3 pp): **not met** — sDA up to 8.3 pp (enhanced)
  and UDI 100–3000 up to 7.0 pp (Office_2 with the crown); met on UDI above 3 000 lx with the
  enhanced recipe (≤ 0.2 pp) and on the UDI bands without the crown (≤ 1.2 pp). ASE is not in
  these recipes' outputs (radtree's is in ``standards.csv``).

Run: ``.venv/bin/python benchmarks/lbt_annual.py --lbt-python /path/to/venv/bin/python
[--lbt-params "-ab 4 -ad 8192 -lw 1e-5 -dr 0"] [--recipes annual-daylight-enhanced]``.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "honeybee-office"
SCENES = {"model": "without", "crown": "leaf_on"}      # exported scenario → radtree variant
SKY_GLOWS = ("\nskyfunc glow skyglow 0 0 4 1 1 1 0\nskyglow source sky 0 0 4 0 0 1 180\n"
             "skyfunc glow groundglow 0 0 4 1 1 1 0\ngroundglow source ground 0 0 4 0 0 -1 180\n")
RECIPE = r'''
import os, sys, pyradiance
from honeybee_radiance.config import folders
folders.radiance_path = os.path.dirname(pyradiance.__file__)   # bin/ and lib/ of the wheel
from lbt_recipes.recipe import Recipe
from lbt_recipes.settings import RecipeSettings
recipe, model, epw, params, folder = sys.argv[1:6]
r = Recipe(recipe)
r.input_value_by_name("model", model)
r.input_value_by_name("wea", epw)
r.input_value_by_name("radiance-parameters", params)
try:
    r.run(RecipeSettings(folder=folder, workers=2, report_out=True), silent=True,
          queenbee_path=os.path.join(os.path.dirname(sys.executable), "queenbee"))
except TypeError:     # lbt-recipes 0.29's run.py fails on its own duration line, after the run
    pass
'''


def radtree(*args: str, cwd: Path) -> None:
    subprocess.run([sys.executable, "-m", "radtree", "-q", *args], cwd=cwd, check=True)


def metrics(lux: np.ndarray, occupied: np.ndarray) -> dict[str, float]:
    """DA300, sDA300/50, UDI bands and mean lux of (sensors, 8760) ``lux`` over the occupied
    hours (percent of occupied hours, sDA percent of sensors)."""
    e = lux[:, occupied]
    da = 100 * (e >= 300).mean(axis=1)
    return {"DA300": da.mean(), "sDA": 100 * (da >= 50).mean(), "UDI<100": 100 * (e < 100).mean(),
            "UDI100-3000": 100 * ((e >= 100) & (e <= 3000)).mean(),
            "UDI>3000": 100 * (e > 3000).mean(), "mean_lux": e.mean()}


def run_recipe(python: str, *, recipe: str, model: Path, epw: Path, params: str,
               folder: Path) -> Path:
    """Run one lbt recipe; the folder holding its ``results``."""
    env = dict(os.environ, PATH=f"{Path(python).parent}{os.pathsep}{os.environ['PATH']}")
    subprocess.run([python, "-c", RECIPE, recipe, str(model), str(epw), params, str(folder)],
                   check=True, env=env, capture_output=True)
    found = sorted(folder.rglob("results/sun-up-hours.txt"))
    if not found:
        raise SystemExit(f"{recipe}: no results under {folder}")
    return found[0].parent


def recipe_hourly(results: Path, grid: str) -> np.ndarray:
    """(sensors, 8760) lux of a recipe's ``total`` results (zero outside its sun-up hours)."""
    hours = np.floor(np.loadtxt(results / "sun-up-hours.txt")).astype(int)
    values = np.load(results / "__static_apertures__" / "default" / "total" / f"{grid}.npy")
    out = np.zeros((values.shape[0], 8760))
    out[:, hours] = values
    return out


def compare(hourly: dict, results: Path, *, scene: str, recipe: str) -> None:
    occupied = hourly["occupied"].astype(bool)
    for grid in ("Office_1", "Office_2"):
        ours = metrics(hourly[f"total__{SCENES[scene]}__{grid}"], occupied)
        theirs = metrics(recipe_hourly(results, grid), occupied)
        seasonal = metrics(hourly[f"total__with__{grid}"], occupied) if scene == "crown" else None
        cells = ", ".join(f"{k} {ours[k]:.1f}/{theirs[k]:.1f} ({theirs[k] - ours[k]:+.1f})"
                          for k in ours if k != "mean_lux")
        print(f"  {recipe:<25} {scene:<5} {grid}: {cells}; mean lux ratio lbt/radtree "
              f"{theirs['mean_lux'] / ours['mean_lux']:.3f}"
              + (f"; radtree with seasons sDA {seasonal['sDA']:.1f}" if seasonal else ""))


def reference(project: Path, *, hourly: dict, epw: Path, results: Path, hours: int) -> None:
    """Exact hourly rtrace (gendaylit with the EPW's DNI/DHI) of the model at ``hours``
    diffuse-dominated occupied hours (radtree 200–400 lx on office 1, no direct sun), against
    radtree's and the recipe's annual values of those hours."""
    from radtree.engines.radiance.binaries import require_radiance
    from radtree.engines.radiance.writer import rgb_to_lux

    env = require_radiance().env()
    site = next(r for r in epw.read_text().splitlines() if r.startswith("LOCATION")).split(",")
    lat, lon, tz = float(site[6]), float(site[7]), float(site[8])
    rows = [r.split(",") for r in epw.read_text().splitlines()[8:]]
    ours, theirs = hourly["total__without__Office_1"], recipe_hourly(results, "Office_1")
    mean, direct = ours.mean(axis=0), hourly["direct__without__Office_1"].mean(axis=0)
    pick = np.flatnonzero((mean > 200) & (mean < 400) & (direct == 0) & hourly["occupied"])
    build = project / "build" / "model"
    geometry = sorted(str(p.relative_to(build)) for p in (build / "geometry").glob("*.rad"))
    pts = (build / "grids" / "Office_1.pts").read_text()
    for h in sorted(np.random.default_rng(1).choice(pick, min(hours, len(pick)), replace=False)):
        r = rows[h]
        sky = subprocess.run(["gendaylit", r[1], r[2], str(int(r[3]) - 0.5), "-a", str(lat),
                              "-o", str(-lon), "-m", str(-15 * tz), "-W", r[14], r[15], "-O",
                              "0", "-g", "0.15"], capture_output=True, text=True, env=env,
                             check=True).stdout
        (build / "ref.sky").write_text(sky + SKY_GLOWS)
        with (build / "ref.oct").open("wb") as fh:
            subprocess.run(["oconv", "ref.sky", "materials.rad", "skies/1330_ground.rad",
                            *geometry], cwd=build, stdout=fh, check=True, env=env)
        out = subprocess.run(["rtrace", "-h", "-I", "-ab", "4", "-ad", "8192", "-lw", "1e-5",
                              "-aa", "0", "ref.oct"], cwd=build, input=pts, text=True,
                             capture_output=True, check=True, env=env).stdout
        ref = rgb_to_lux(np.loadtxt(out.splitlines()).reshape(-1, 3)).mean()
        print(f"  reference hour {h} ({r[1]}/{r[2]} {int(r[3]) - 1}:30): rtrace {ref:.1f} lx; "
              f"radtree {ours[:, h].mean() / ref:.3f}, lbt {theirs[:, h].mean() / ref:.3f}")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--lbt-python", default=sys.executable,
                    help="interpreter with lbt-recipes and queenbee-local")
    ap.add_argument("--lbt-params", default="-ab 4 -ad 8192 -lw 1e-5 -dr 0")
    ap.add_argument("--reference-hours", type=int, default=8)
    ap.add_argument("--recipes", nargs="+",
                    default=["annual-daylight-enhanced", "annual-daylight"])
    args = ap.parse_args()
    work = Path(tempfile.mkdtemp(prefix="lbt_annual_"))
    project = work / "honeybee-office"
    shutil.copytree(EXAMPLE, project)
    shutil.copytree(ROOT / "examples" / "office-block" / "data", work / "office-block" / "data")
    radtree("annual", str(project), "--no-figures", cwd=work)
    meta = json.loads((project / "results" / "annual" / "annual_meta.json").read_text())
    epw = Path(meta["weather"]["path"])
    hourly = dict(np.load(project / "results" / "annual" / "hourly.npz"))
    print(f"radtree annual: {meta['rcontrib']}, weather {epw.name}; lbt params {args.lbt_params}")
    for scene in SCENES:
        radtree("export", str(project), "--format", "honeybee-scene", "-s", scene, "--out",
                str(work / f"export_{scene}"), cwd=work)
        model = work / f"export_{scene}" / "radtree_scene.hbjson"
        for recipe in args.recipes:
            results = run_recipe(args.lbt_python, recipe=recipe, model=model, epw=epw,
                                 params=args.lbt_params, folder=work / f"{recipe}_{scene}")
            compare(hourly, results, scene=scene, recipe=recipe)
            if scene == "model" and recipe == args.recipes[0] and args.reference_hours:
                radtree("build", str(project), cwd=work)
                reference(project, hourly=hourly, epw=epw, results=results,
                          hours=args.reference_hours)
    print(f"(radtree/lbt per metric, lbt − radtree in brackets; work folder {work})")
    return 0


if __name__ == "__main__":
    from _common import print_resources_at_exit

    print_resources_at_exit()
    sys.exit(main())
