"""A Radiance fisheye picture of a build folder's hour: ``rpict -vta`` (angular fisheye,
equidistant, 180° × 180°) from a view point along a lens axis, with the hour's sun and sky,
then ``pcond -h`` (human-eye tone mapping) and ``ra_bmp`` for an 8-bit image beside the HDR.

The picture people want beside the photo; the binary sky/canopy comparison itself is by ray
casting (:mod:`radtree.photo.render`). Sampling: ``-ab`` as given, ``-ad``, no irradiance cache
(``-aa 0``), as the build's rtrace.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from radtree.engines.radiance.binaries import run
from radtree.engines.radiance.engine import ensure_shared_inputs
from radtree.engines.radiance.writer import BuildPlan


def _xyz(v: np.ndarray) -> list[str]:
    return [f"{float(c):.6g}" for c in v]


def fisheye_command(octree: str, viewpoint: np.ndarray, direction: np.ndarray, up: np.ndarray,
                    size: int, ab: int, ad: int) -> list[str]:
    """The ``rpict`` argument list of a 180° angular fisheye (``-vta``)."""
    return ["rpict", "-vta", "-vp", *_xyz(viewpoint), "-vd", *_xyz(direction),
            "-vu", *_xyz(up), "-vh", "180", "-vv", "180", "-x", str(size), "-y", str(size),
            "-ab", str(ab), "-ad", str(ad), "-aa", "0", "-as", "0", "-lw", "1e-4", octree]


def fisheye_picture(plan: BuildPlan, *, hour: str, viewpoint: np.ndarray,
                    direction: np.ndarray, up: np.ndarray, size: int, ab: int, ad: int,
                    out: Path) -> tuple[Path, Path]:
    """Render ``out``.hdr and ``out``.bmp (tone-mapped) of the plan's hour (label HHMM): a
    ``size`` px fisheye from ``viewpoint`` (m) looking along ``direction``, ``up`` upwards,
    traced with ``-ab ab -ad ad``."""
    folder = plan.folder
    (folder / "octrees").mkdir(exist_ok=True)
    ensure_shared_inputs(plan)   # compiled meshes, prototype octrees
    octree = f"octrees/{hour}.oct"
    steps = [(plan.oconv_command(hour), folder / octree),
             (fisheye_command(octree, viewpoint, direction, up, size, ab, ad),
              out.with_suffix(".hdr"))]
    for argv, target in steps:
        tmp = target.with_name(target.name + ".tmp")
        try:
            run(argv, cwd=folder, stdout_path=tmp)
            os.replace(tmp, target)
        finally:
            if tmp.exists():
                tmp.unlink()
    hdr = out.with_suffix(".hdr")
    mapped = run(["pcond", "-h", str(hdr)])
    bmp = out.with_suffix(".bmp")
    tmp = bmp.with_name(bmp.name + ".tmp")
    try:
        run(["ra_bmp", "-", str(tmp)], stdin=mapped)
        os.replace(tmp, bmp)
    finally:
        if tmp.exists():
            tmp.unlink()
    return hdr, bmp
