"""Round trip through the synthetic scanner (issue 41): radtree's crowns → ALS points → trees.

A synthetic street of 20 volume-louvers crowns (:mod:`radtree.trees.synthetic_scan`, seed 0)
is scanned by the synthetic airborne scanner (:mod:`radtree.lidar.scanner`, defaults: 20
pulses/m², 300 m altitude, one thin beam per pulse) into a LAZ tile, which
``radtree.lidar.segment`` turns into trees; each detected tree's points (``clip``) are then
inverted to plant area (:mod:`radtree.lidar.voxels`, G of the slats' 30° inclination, default
voxel size). Detected trees are matched one-to-one to the true trunks within 2 m. Targets:
tree count exact, heights ±0.5 m, crown diameters ±10 %, leaf area ±10 % (each tree). The
façade-illuminance part of the issue's round trip is not measured here.

    python benchmarks/lidar_roundtrip.py [--pulses 20] [--crossings 2]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path


def main() -> int:
    import numpy as np

    from radtree.lidar.clip import write_subset
    from radtree.lidar.evaluate import match_tops
    from radtree.lidar.scanner import AlsScan
    from radtree.lidar.segment import segment_tile
    from radtree.lidar.tile import read_tile
    from radtree.lidar.voxels import DEFAULT_SPACINGS, tree_voxels
    from radtree.trees.synthetic_scan import (
        STREET_LOUVERS,
        scan_street,
        synthetic_street,
        write_scan,
    )
    from radtree.trees.volume import mean_cos

    ap = argparse.ArgumentParser()
    ap.add_argument("--pulses", type=float, default=20.0, help="pulses per m²")
    ap.add_argument("--crossings", type=float, default=STREET_LOUVERS.crossings)
    args = ap.parse_args()
    lv = replace(STREET_LOUVERS, crossings=args.crossings)
    trees = synthetic_street()
    t0 = time.perf_counter()
    pts, areas, _ = scan_street(trees, AlsScan(pulse_density_m2=args.pulses), lv)
    with tempfile.TemporaryDirectory() as tmp:
        tile_path = write_scan(pts, Path(tmp) / "street.laz")
        tile = read_tile(tile_path)
        seg = segment_tile(tile)
        det = np.array([[t.top_x, t.top_y] for t in seg.trees]).reshape(-1, 2)
        truth = np.array([[t.x, t.y] for t in trees])
        pairs = match_tops(det, truth, 2.0)
        rows = []
        for r, c, d in pairs:
            dt, tt = seg.trees[r], trees[c]
            clip = write_subset(tile_path, seg.tree_mask(dt.id), Path(tmp) / f"{dt.id}.laz")
            grid = tree_voxels(clip, mean_cos(lv))
            rows.append((tt, dt, d, grid.leaf_area_m2, areas[tt.id], grid.size_m))
    seconds = time.perf_counter() - t0
    print(f"synthetic street: {len(trees)} trees, crossings {lv.crossings:g}, slats "
          f"{lv.slat_size_m:g} m at {lv.inclination_deg:g}°; scan {args.pulses:g} pulses/m², "
          f"{len(pts.xyz)} points, spacing {tile.spacing_m():.2f} m; {seconds:.1f} s")
    print(f"{'tree':5} {'det':5} {'dist':>5} {'h true':>7} {'h det':>6} {'dh':>6} "
          f"{'d true':>7} {'d det':>6} {'dd %':>6} {'LA true':>8} {'LA det':>7} {'dLA %':>6}")
    dh, dd, dla = [], [], []
    for tt, dt, d, la, la_true, _ in rows:
        dh.append(dt.height_m - tt.height_m)
        dd.append(dt.crown_diameter_m / (2 * tt.crown_radius_m) - 1)
        dla.append(la / la_true - 1)
        print(f"{tt.id:5} {dt.id:5} {d:5.2f} {tt.height_m:7.2f} {dt.height_m:6.2f} "
              f"{dh[-1]:+6.2f} {2 * tt.crown_radius_m:7.2f} {dt.crown_diameter_m:6.2f} "
              f"{100 * dd[-1]:+6.1f} {la_true:8.1f} {la:7.1f} {100 * dla[-1]:+6.1f}")
    dh_a, dd_a, dla_a = np.abs(dh), np.abs(dd), np.abs(dla)
    print(f"trees: true {len(trees)}, detected {len(seg.trees)}, matched {len(rows)} "
          f"(target: exact) — {'met' if len(seg.trees) == len(rows) == len(trees) else 'NOT met'}")
    for name, v, lim, unit, scale in (("height", dh_a, 0.5, "m", 1), ("crown diameter", dd_a,
                                                                      0.10, "%", 100),
                                      ("leaf area", dla_a, 0.10, "%", 100)):
        print(f"{name}: max |error| {scale * v.max():.2f} {unit}, median "
              f"{scale * np.median(v):.2f} {unit}, within ±{scale * lim:g} {unit}: "
              f"{int(np.sum(v <= lim))}/{len(v)} — {'met' if v.max() <= lim else 'NOT met'}")
    print(f"voxel size {rows[0][5]:g} m ({DEFAULT_SPACINGS:g} point spacings); total leaf area true "
          f"{sum(areas.values()):.0f} m², from the scan {sum(r[3] for r in rows):.0f} m²")
    return 0


if __name__ == "__main__":
    from _common import print_resources_at_exit

    print_resources_at_exit()
    sys.exit(main())
