"""Tree attribution checked by removal, on the synthetic Mendoza district (``examples/district``).

For each hour asked, the ``trees`` scenario's scene is traced with the NumPy engine's tree
attribution (:mod:`radtree.engines.numpy.attribution`: paired paths with and without the trees;
each tree gets what removing it alone gives back). The 5 trees that take the most light from
one façade (each tree's most affected façade) are then removed one at a time and the scene
re-traced (without the tree minus with all trees, paired paths of another seed, so the two
estimates are independent: :func:`radtree.pipeline.tree_impact.removal_check`). Printed per
tree: the façade-mean illuminance attributed to it, the change on removal, their standard
errors, the difference in standard errors z (≈ N(0, 1): |z| > 2 one time in 20), and the
removal re-traced with the attribution's own seed minus the attribution ("same seed": 0 when
the attribution is the removal path for path).

    .venv/bin/python benchmarks/tree_impact.py [--rays 1024] [--hour 12:30 --hour 15:30]

Measured 2026-12-07 on the shared 2-core machine (load ≈ 22; wall 813 s, CPU 132 s), defaults
(1024 paths/sensor, -ab 2, seed 1; removal seed 2), façade means in lux:

     hour  tree  façade  attributed lx   removal lx     diff      z  same seed
    12:30  T020   B02:0     1684 ±  15   1692 ±  15       -8  -0.37   +4.5e-13
    12:30  T022   B03:0     1214 ±  24   1227 ±  26      -13  -0.37      +0.25
    12:30  T057   B10:3     1099 ±  38   1169 ±  44      -70  -1.19   +2.3e-13
    12:30  T050   B04:0     1060 ±  28   1049 ±  25      +12  +0.31         +0
    12:30  T058   B10:3      942 ±  33    966 ±  32      -23  -0.51   -1.1e-13
    15:30  T058   B10:3     6822 ±  35   6956 ±  32     -134  -2.84         +0
    15:30  T022   B03:0     1162 ±  25   1229 ±  25      -67  -1.93     +0.081
    15:30  T015   B01:0     1097 ±  19   1119 ±  17      -22  -0.87      -0.78
    15:30  T057   B10:3     1059 ±  44   1074 ±  41      -15  -0.24         +0
    15:30  T062   B07:0      980 ±  24   1054 ±  27      -74  -2.06      +0.41
    8 of 10 within 2 standard errors; max |z| 2.84

With the same seed the removal is the attribution to < 1 lux (a few paths of the re-traced
ones cross a leaf edge differently: the skip-one caster's Embree frame is not the full
scene's). Across seeds the differences share a sign within an hour: every tree's estimate
shares that seed's with-trees trace, so the seeds' errors are correlated across the trees.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from _common import print_resources_at_exit

from radtree.config import effective_project, load_project
from radtree.engines.registry import attributing_engine
from radtree.light.hours import hour_states
from radtree.pipeline.assemble import make_scene
from radtree.pipeline.tree_impact import removal_check

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "district"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rays", type=int, default=1024, help="paths per sensor (default 1024)")
    ap.add_argument("--hour", action="append", help="HH:MM (repeatable; default 12:30, 15:30)")
    ap.add_argument("--top", type=int, default=5)
    args = ap.parse_args()
    hours = args.hour or ["12:30", "15:30"]
    project = load_project(EXAMPLE, {"engine.rays": args.rays})
    sc = project.scenario("trees")
    built = make_scene(project, sc, dense_grid=False)
    engine = attributing_engine()
    assert engine is not None, "no engine attributes light to trees"
    params = effective_project(project, sc).engine
    print(f"{EXAMPLE.name}: {len(built.scene.owners())} trees, -ab {built.ab}, {args.rays} "
          f"paths/sensor, {engine.name} engine, seed {params.seed} (removal: seed "
          f"{params.seed + 1})")
    print(f"{'hour':>5} {'tree':>5} {'façade':>7} {'attributed lx':>14} {'removal lx':>12} "
          f"{'diff':>8} {'z':>6} {'same seed':>10}")
    zs = []
    for st in hour_states(project, sc, hours):
        table = removal_check(engine, built.scene, st, params, built.ab, args.top)
        for r in table.itertuples():
            zs.append(r.z)
            print(f"{r.time:>5} {r.tree:>5} {r.target:>7} {r.attributed:8.0f} ± {r.attributed_se:3.0f}"
                  f" {r.removal:6.0f} ± {r.removal_se:3.0f} {r.attributed - r.removal:+8.0f}"
                  f" {r.z:+6.2f} {r.same_seed:+10.2g}")
    inside = sum(abs(z) <= 2 for z in zs)
    print(f"{inside} of {len(zs)} within 2 standard errors; max |z| "
          f"{max(abs(z) for z in zs):.2f}")


if __name__ == "__main__":
    print_resources_at_exit()
    main()
