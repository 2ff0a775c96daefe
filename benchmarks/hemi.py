"""Time the hemispherical-photo pipeline on the shipped 2272×1704 chestnut photo.

Prints the median wall time (seconds) of: classify + all metrics + gap outlines (the image
already decoded; the pixel geometry cold, i.e. not from the per-camera cache), and, for
reference, the JPEG decode and the overlay PNG. Target: under 2 s on 2 cores.
"""

from __future__ import annotations

import statistics
import sys
import tempfile
import time
from pathlib import Path

# the real photo (the shared data folder, for developers), or the byte-identical copy the Mendoza example ships
PHOTO = next((p for p in (Path(__file__).resolve().parents[2] / "shared/data/fisheye/chestnut_coolpix4500_fc-e8.jpg",
                          Path(__file__).resolve().parents[1] / "examples/mendoza-street/data/fisheye_chestnut_standin.jpg") if p.exists()),
             Path(__file__).resolve().parents[1] / "examples/mendoza-street/data/fisheye_chestnut_standin.jpg")
REPEAT = 5
TARGET_S = 2.0


def main() -> int:
    from radtree.hemi import HemiConfig
    from radtree.hemi.analyse import analyse_loaded
    from radtree.hemi.geometry import clear_pixel_field_cache
    from radtree.hemi.image import load_image
    from radtree.hemi.overlay import write_overlay

    if not PHOTO.exists():
        print(f"hemi benchmark: {PHOTO} not found, skipped")
        return 0
    config = HemiConfig(preset="coolpix4500-fce8")
    t = time.perf_counter()
    image = load_image(PHOTO)
    decode = time.perf_counter() - t
    analyse_loaded(image, config)  # warm up imports

    runs, parts = [], []
    for _ in range(REPEAT):
        clear_pixel_field_cache()
        t = time.perf_counter()
        result = analyse_loaded(image, config)
        runs.append(time.perf_counter() - t)
        parts.append(result.timings)
    with tempfile.TemporaryDirectory() as tmp:
        t = time.perf_counter()
        write_overlay(result, Path(tmp) / "overlay.png")
        overlay = time.perf_counter() - t

    median = statistics.median(runs)
    split = {k: statistics.median(p[k] for p in parts) for k in parts[0]}
    print(f"hemi: {image.width}×{image.height} px photo, {len(result.outlines)} gaps outlined")
    print(
        f"hemi: classify + metrics + outlines: {median:.3f} s median of {REPEAT} "
        f"(min {min(runs):.3f} s; target < {TARGET_S:.1f} s)"
    )
    print("hemi:   " + ", ".join(f"{k} {v:.3f} s" for k, v in split.items()))
    print(f"hemi: JPEG decode {decode:.3f} s, overlay PNG {overlay:.3f} s (not in the figure)")
    return 0


if __name__ == "__main__":
    from _common import print_resources_at_exit  # benchmarks/_common.py

    print_resources_at_exit()
    sys.exit(main())
