"""Photo benchmark: render + analysis time of a synthetic fisheye per photo-derived crown,
and the fitting time per crown.

On a scratch copy of ``examples/mendoza-street`` (``/tmp/photo_bench_*``, removed unless
``--keep``): for A-photo (louvers dome cut by the façade photo), C-photo (perforated) and
F-photo (free crowns fitted to the upward photo), the crown is built (build s; for F-photo
that includes the fit), rendered at ``--size`` px (default 2000 × 2000: one ray per pixel of
the 90° circle, Embree when installed; render s) and analysed by radtree.hemi (analysis s),
and the ring × segment / per-ring gap-fraction RMS against the photo is printed. Then the
fit alone (photo analysis excluded: cached) is timed for F-photo, one photo and the three
photos of a folder (the same stand-in photo three times). Target: render + analysis ≤ 5 s
for 2000 × 2000 on 2 cores. "CPU s (all)" is the process CPU time of build + render +
analysis, all threads: on a loaded machine the wall times overstate an idle run.

Run: ``.venv/bin/python benchmarks/photo.py [--size 2000] [--keep]``.
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--size", type=int, default=2000)
    ap.add_argument("--keep", action="store_true")
    args = ap.parse_args()
    if args.keep:
        work = Path(tempfile.mkdtemp(prefix="photo_bench_"))
        run(work, args.size)
        print(f"kept {work}")
    else:
        with tempfile.TemporaryDirectory(prefix="photo_bench_") as tmp:
            run(Path(tmp), args.size)


def run(work: Path, size: int) -> None:
    """Every timing of the module docstring, on a copy of the example in ``work``."""
    from radtree.config import load_project
    from radtree.photo.check import check_rows, rms_of
    from radtree.photo.render import render_scenario
    from radtree.pipeline.assemble import facade_frame
    from radtree.trees import photo_fit
    from radtree.trees.build import apply_switches
    from radtree.trees.envelope import crown_row_spec
    from radtree.trees.photo import analyse_photo, photo_source

    shutil.copytree(ROOT / "examples" / "mendoza-street", work / "m",
                    ignore=shutil.ignore_patterns("build", "results", "report"))
    p = load_project(work / "m", overrides={"sensors.dense_grid": False,
                                            "sensors.dense_hours": []})
    print(f"{'scenario':9} {'build s':>8} {'render s':>9} {'analysis s':>11} "
          f"{'render+analysis s':>18} {'CPU s (all)':>12} {'RMS cells':>10} {'RMS rings':>10}")
    for name in ("A-photo", "C-photo", "F-photo"):
        sc = p.scenario(name)
        c0 = time.process_time()
        r = render_scenario(p, sc, size)
        t0 = time.perf_counter()
        model = r.analyse()
        t_an = time.perf_counter() - t0
        cpu = time.process_time() - c0
        photos = [analyse_photo(x, r.source) for x in r.source.images]
        rms, ring = rms_of(check_rows(name, photos, model))
        print(f"{name:9} {r.seconds['build']:8.2f} {r.seconds['cast']:9.2f} {t_an:11.2f} "
              f"{r.seconds['cast'] + t_an:18.2f} {cpu:12.2f} {rms:10.4f} {ring:10.4f}")
    sc = p.scenario("F-photo")
    tree, _ = apply_switches(p.tree, dict(sc.switches), root=p.root)
    src = photo_source(tree)
    spec = crown_row_spec(tree, p.sensors, p.street)
    cam = photo_fit.camera_point(tree, p.sensors)
    folder = work / "photos"
    folder.mkdir()
    for k in range(3):
        shutil.copyfile(src.path, folder / f"photo{k}.jpg")
    for label, s in (("1 photo", src), ("3 photos", replace(src, path=folder))):
        for x in s.images:
            analyse_photo(x, s)            # analysis cached: time the fit alone
        photo_fit._CACHE.clear()
        t0 = time.perf_counter()
        fit, _ = photo_fit.fit_crown(s, cam, spec, tree.louvers, facade_frame(p))
        print(f"F-photo fit, {label}: {time.perf_counter() - t0:.2f} s "
              f"(LAD {fit.lad:.3f} m²/m³, x {fit.x:.3f}, mean tilt "
              f"{fit.mean_tilt_deg:.1f}°, ring RMS {fit.ring_rms:.4f})")


if __name__ == "__main__":
    from _common import print_resources_at_exit  # benchmarks/_common.py

    print_resources_at_exit()
    main()
