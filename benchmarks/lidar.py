"""Tree detection on a real airborne laser scanning plot (issue 41): the detection table.

Data: ``../shared/data/lidar/mixed_conifer_west.laz`` (the western half of lidR's
``MixedConifer.laz``, a real ALS plot with a reference segmentation ``treeID``; see its
SOURCE.md). The tile is segmented with radtree's defaults (:mod:`radtree.lidar.segment`) and
the detected tops matched one-to-one to the reference tops within 2 m
(:mod:`radtree.lidar.evaluate`). Targets: ≥ 80 % of the reference trees taller than 5 m found,
≤ 20 % false trees, median height error ≤ 1 m. The reference heights are the highest point of
each reference id and a detected tree's height is the highest point of its crown, so matched
heights usually share their point: the height figure checks that crowns are not merged under a
lower top, little more.

    python benchmarks/lidar.py
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: ../shared beside the repo (main checkout) or two levels up (a worktree in wt/NAME)
TILE = next((p for p in (ROOT.parent / "shared/data/lidar/mixed_conifer_west.laz",
                         ROOT.parent.parent / "shared/data/lidar/mixed_conifer_west.laz")
             if p.exists()), ROOT.parent / "shared/data/lidar/mixed_conifer_west.laz")
TARGETS = {"found": 0.80, "false": 0.20, "height_m": 1.0}


def main() -> int:
    from radtree.lidar.evaluate import detection
    from radtree.lidar.segment import SegmentConfig, segment_tile
    from radtree.lidar.tile import read_tile

    if not TILE.exists():
        print(f"lidar benchmark: {TILE} not found, skipped")
        return 0
    t0 = time.perf_counter()
    tile = read_tile(TILE)
    cfg = SegmentConfig()
    seg = segment_tile(tile, cfg)
    seconds = time.perf_counter() - t0
    d = detection(seg)
    print(f"tile {TILE.name}: {len(tile)} points, spacing {tile.spacing_m():.2f} m; "
          f"ws = {cfg.window_base_m:g} + {cfg.window_slope:g}·h m, CHM cell {cfg.cell_m:g} m, "
          f"smoothing {cfg.smooth_m:g} m; segmented in {seconds:.2f} s")
    print(d.table())
    ok = (d.found_fraction >= TARGETS["found"], d.false_fraction <= TARGETS["false"],
          d.median_height_error_m <= TARGETS["height_m"])
    print("targets: found ≥ 80 % {}, false ≤ 20 % {}, median height error ≤ 1 m {}".format(
        *("met" if k else "NOT met" for k in ok)))
    return 0


if __name__ == "__main__":
    from _common import print_resources_at_exit

    print_resources_at_exit()
    sys.exit(main())
