"""Façade illuminance of a crown rebuilt from its synthetic airborne scan (issue 41).

The Mendoza example with one free-standing volume-louvers crown (``crown.count`` 1, trunk
``TRUNK_M`` from the façade so the crown clears the wall, ``louvers.crossings`` ``CROSSINGS``):
the crown as radtree builds it ("orig") is scanned by the synthetic airborne scanner
(:mod:`radtree.lidar.scanner`, 20 pulses/m², ground plane z = 0; not the façade or trunk) into
``data/scan.laz``, and the same crown rebuilt from that scan (``tree.points``, scenario
"scan": plant area density by voxel, slats filled voxel by voxel; placed with its plant-area
centroid on the trunk). Both are traced with the NumPy engine at two hours; the table gives
the façade mean per hour (the 8 sensors), the ratio scan / orig, and the ratio of the crowns'
shading (open − scan) / (open − orig), "open" being the street without a crown. Target: the
façade mean within 5 %.

Measured (session of issue 41, crossings 4, trunk 5.2 m, hours 10:30 / 13:30): leaf area from
the scan +2.5 % (default voxel 1.25 m); façade mean scan/orig 0.968 / 0.795 (voxel 1.25 m),
0.975 / 0.777 (0.8 m), 0.973 / 0.747 (1.0 m). With slats uniform in each voxel (before
slats followed the voxel's returns) it was 0.955 / 1.971 at 1.25 m and swung from 0.98 to
1.43 at 13:30 with the voxel size: the sensors' steep sun rays cross the crown's thin rim by
the wall, whose density inside a voxel decides their shade. Now the rebuilt crown shades the
13:30 sensors ≈ 20 % more than the original.
Not met at default settings.

``--turbid`` adds the scan as turbid voxels (``representation = "turbid"``,
:mod:`radtree.trees.turbid_voxels`: the same density grid, leaf area spread evenly in each
voxel). Measured 2026-12-07 09:10 UTC (load ≈ 10, 13 s a run): voxels/orig 0.980 / 1.378
(voxel 1.25 m), 0.980 / 1.418 (0.8 m), 0.985 / 1.348 (1.0 m), against slats/orig 0.968 /
0.795, 0.975 / 0.777, 0.973 / 0.747 in the same runs: the medium lets ≈ 40 % more light
through the rim at 13:30 where the returns-placed slats let ≈ 20 % less — the truth lies
between the two sub-voxel placements. Not met either.

    python benchmarks/lidar_facade.py [--hours 10:30 13:30] [--crossings 4] [--voxel M]
        [--turbid]
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MENDOZA = ROOT / "examples" / "mendoza-street"
TRUNK_M = 5.2
CROSSINGS = 4.0


def scenario(name: str, crossings: float, extra: str = "") -> str:
    return (f'\n[[scenario]]\nname = "{name}"\nmodel = "louvers"\nreflection = "traced"\n'
            f'form = "free"\nswitches = {{ "louvers.arrangement" = "volume", '
            f'"louvers.crossings" = {crossings:g}, "crown.count" = 1, '
            f'"crown.trunk_distance_m" = {TRUNK_M:g}{extra} }}\n')


def main() -> int:
    import numpy as np
    import pandas as pd

    from radtree.config import Scenario, load_project
    from radtree.lidar.scanner import AlsScan, ground_plane, scan_als
    from radtree.lidar.voxels import tree_voxels
    from radtree.site.frame import FacadeFrame
    from radtree.trees.build import build_tree
    from radtree.trees.synthetic_scan import GROUND, HIGH_VEGETATION, leaf_area_m2, write_scan
    from radtree.trees.volume import mean_cos

    ap = argparse.ArgumentParser()
    ap.add_argument("--hours", nargs="+", default=["10:30", "13:30"])
    ap.add_argument("--crossings", type=float, default=CROSSINGS)
    ap.add_argument("--voxel", type=float, default=None, help="tree.points_voxel_m (m)")
    ap.add_argument("--turbid", action="store_true",
                    help="also the scan as turbid voxels (representation = \"turbid\")")
    args = ap.parse_args()
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp_s:
        tmp = Path(tmp_s) / "study"
        shutil.copytree(MENDOZA, tmp, ignore=shutil.ignore_patterns(
            "build", "results", "report", "diagnose", "sweep", "campaign*"))
        toml = tmp / "radtree.toml"
        head = toml.read_text().split("\n[[scenario]]")[0]
        head = re.sub(r"^hours = \[.*\]$", "hours = [" + ", ".join(
            f'"{h}"' for h in args.hours) + "]", head, flags=re.M)
        head = re.sub(r"^dense_hours = .*$", "dense_grid = false", head, flags=re.M)
        toml.write_text(head + scenario("orig", args.crossings))
        project = load_project(tmp)
        frame = FacadeFrame(project.street.facade_azimuth_deg)
        orig = build_tree(project, project.scenario("orig"), frame)
        leaf = orig.meshes[0]
        true_area = leaf_area_m2([leaf.vertices[f] for f in leaf.faces])   # the triangles
        lo = tuple(leaf.vertices[:, :2].min(axis=0) - 3.0)
        hi = tuple(leaf.vertices[:, :2].max(axis=0) + 3.0)
        gv, gf = ground_plane(lo, hi)
        verts = np.vstack([leaf.vertices, gv])
        faces = np.vstack([leaf.faces, gf + len(leaf.vertices)])
        cls = np.r_[np.full(len(leaf.faces), HIGH_VEGETATION), np.full(len(gf), GROUND)]
        pts = scan_als(verts, faces, cls, lo, hi, AlsScan(pulse_density_m2=20.0))
        write_scan(pts, tmp / "data" / "scan.laz")
        grid = tree_voxels(tmp / "data" / "scan.laz", mean_cos(project.tree.louvers),
                           args.voxel)
        voxel = "" if args.voxel is None else f', "tree.points_voxel_m" = {args.voxel:g}'
        toml.write_text(toml.read_text() + scenario(
            "scan", args.crossings, ', "tree.points" = "data/scan.laz"' + voxel)
            + '\n[[scenario]]\nname = "open"\nmodel = "none"\nreflection = "traced"\n'
            'form = "free"\n' + (scenario("voxels", args.crossings, ', "tree.points" = '
                                 '"data/scan.laz", "tree.representation" = "turbid"' + voxel)
                                 if args.turbid else ""))
        exe = Path(sys.executable).with_name("radtree")
        subprocess.run([str(exe), "simulate", str(tmp), "--engine", "numpy"], check=True,
                       stdout=subprocess.DEVNULL)
        res = pd.read_csv(tmp / "results" / "illuminance.csv")
        res = res[res["grid"] == res["grid"].iloc[0]]
        mean = res.groupby(["scenario", "time"])["lux"].mean().unstack(0)
        project2 = load_project(tmp)
        rebuilt = build_tree(project2, Scenario("scan", "louvers", form="free",
                                                switches=project2.scenario("scan").switches),
                             frame)
    print(f"crown: Mendoza free crown (a 5 m, b 4.75 m), crossings {args.crossings:g}, trunk "
          f"{TRUNK_M:g} m from the façade; scan {len(pts.xyz)} points, voxel "
          f"{grid.size_m:g} m; {time.perf_counter() - t0:.0f} s")
    print(f"leaf area: built {true_area:.1f} m², from the scan {grid.leaf_area_m2:.1f} m² "
          f"({100 * (grid.leaf_area_m2 / true_area - 1):+.1f} %); slats "
          f"{int(orig.info['slat_count'])} → {int(rebuilt.info['slat_count'])}")
    print(f"{'hour':6} {'open lx':>9} {'orig lx':>9} {'scan lx':>9} {'scan/orig':>10} "
          f"{'shade scan/orig':>16}" + (f" {'voxels lx':>10} {'voxels/orig':>12}"
                                        if args.turbid else ""))
    worst = 0.0
    for hour, row in mean.iterrows():
        r = row["scan"] / row["orig"]
        shade = (row["open"] - row["scan"]) / (row["open"] - row["orig"])
        worst = max(worst, abs(r - 1))
        print(f"{hour:6} {row['open']:9.1f} {row['orig']:9.1f} {row['scan']:9.1f} {r:10.4f} "
              f"{shade:16.3f}" + (f" {row['voxels']:10.1f} {row['voxels'] / row['orig']:12.4f}"
                                  if args.turbid else ""))
    print(f"façade mean within 5 %: {'met' if worst <= 0.05 else 'NOT met'} (worst "
          f"{100 * worst:.1f} %)")
    return 0


if __name__ == "__main__":
    from _common import print_resources_at_exit

    print_resources_at_exit()
    sys.exit(main())
