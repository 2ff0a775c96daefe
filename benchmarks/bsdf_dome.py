"""BSDF crown against the explicit-slat crown on the Mendoza sensor dome (scenario B's set-up).

    PYTHONPATH=. python benchmarks/bsdf_dome.py [--samples N] [--hours 7]

Traces scenario B (explicit slats, Radiance) and the same scenario with
``tree.representation = "bsdf"`` (the dome as a shell of the crown layer's Klems BSDF) at the
project's hours and prints the façade means per hour, their ratio and the 7-hour mean
(``--curvature planar``: the flat stack's BSDF without the traced view from the centre); then
what the BSDF cannot represent: the lateral displacement of light inside the 2.2 m thick slat
stack (see :func:`lateral_displacement`).
"""

from __future__ import annotations

import argparse
import math
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd

from radtree.bsdf.klems import read_klems
from radtree.config import load_project
from radtree.pipeline.crown_bsdf import leaf_on_sample, scenario_xmls
from radtree.pipeline.trace import trace_scenario
from radtree.trees.envelope import dome_spec
from radtree.trees.louvers_dome import dome_layer_radii

ROOT = Path(__file__).resolve().parents[1]


def lateral_displacement(project, sc, xml: Path) -> dict[str, float]:
    """How far light moves sideways inside the stack, which a BSDF (a surface) cannot do.

    Direct (undeviated) light keeps its straight line, as through the BSDF shell. Light
    scattered diffusely in layer k leaves the stack's inner face (d_k from it) displaced by
    d_k·tan θ, Lambertian θ: mean tan θ = π/2, so by π/2 · mean d over the layers. The share of
    the normal-incidence transmission that is scattered (off the Klems diagonal) says how much
    of the light that concerns."""
    k = read_klems(xml)
    flux = k.flux("tf")
    t_normal = float(flux[:, 0].sum())
    direct = float(flux[0, 0])
    spec = dome_spec(project.tree, project.sensors, project.street)
    radii = dome_layer_radii(spec, project.tree.louvers, project.sensors)
    depths = radii - radii[0]
    return {"t_normal": t_normal, "scattered_share": 1.0 - direct / t_normal,
            "stack_m": float(radii[-1] - radii[0]),
            "mean_shift_m": math.pi / 2 * float(depths.mean()),
            "mean_shift_deg_on_inner_shell": math.degrees(math.pi / 2 * float(depths.mean())
                                                          / float(radii[0]))}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--samples", type=int, default=500)
    ap.add_argument("--scenario", default="B")
    ap.add_argument("--bands", type=int, default=3, help="elevation bands of the dome shell")
    ap.add_argument("--ad", type=int, default=8192, help="rtrace -ad of the BSDF crown")
    ap.add_argument("--curvature", default="traced", choices=("traced", "planar"),
                    help="tree.bsdf.curvature: the centre's view traced through the curved "
                         "dome (default) or the flat stack's")
    ap.add_argument("--explicit-cache", default=None,
                    help="CSV of the explicit run's hourly façade means (read if present)")
    args = ap.parse_args()
    project = load_project(ROOT / "examples" / "mendoza-street")
    sc = project.scenario(args.scenario)
    # the BSDF shell's Klems sampling is noisier than the slats' specular paths at the
    # project's -ad 2048 (±10 % per hour): the BSDF crown is traced with -ad 8192
    bs = replace(sc, name=f"{sc.name}-bsdf", switches={
        **sc.switches, "tree.representation": "bsdf", "bsdf.samples": args.samples,
        "bsdf.bands": args.bands, "engine.ad": args.ad,
        "bsdf.curvature": args.curvature})
    t0 = time.perf_counter()
    bands = scenario_xmls(project, bs, progress=print)
    t_bsdf = time.perf_counter() - t0
    print(f"crown BSDFs ({t_bsdf:.0f} s): " + "; ".join(
        f"|elevation| {lo:g}–{hi:g}°: {xml}" for lo, hi, xml in bands))
    print(leaf_on_sample(project, bs, 0.5 * (bands[0][0] + bands[0][1])).notes[0][:200] + "…")
    out = {}
    cache = Path(args.explicit_cache) if args.explicit_cache else None
    for label, s in (("explicit", sc), ("bsdf", bs)):
        if label == "explicit" and cache is not None and cache.exists():
            out[label] = pd.read_csv(cache, index_col=0)["lux"]
            print(f"explicit: read {cache}")
            continue
        t0 = time.perf_counter()
        rows = trace_scenario(project, s, "radiance", grids=["facade"])
        out[label] = rows.groupby("time")["lux"].mean()
        print(f"{label}: {time.perf_counter() - t0:.0f} s for {len(out[label])} hours")
        if label == "explicit" and cache is not None:
            out[label].to_csv(cache)
    print(f"{'time':>6} {'explicit':>9} {'bsdf':>9} {'ratio':>6}")
    for t in out["explicit"].index:
        e, b = out["explicit"][t], out["bsdf"][t]
        print(f"{t:>6} {e:9.1f} {b:9.1f} {b / e:6.3f}")
    e, b = float(out["explicit"].mean()), float(out["bsdf"].mean())
    print(f"{'mean':>6} {e:9.1f} {b:9.1f} {b / e:6.3f}  ({100 * (b / e - 1):+.1f} %)")
    worst = float(np.max(np.abs(out["bsdf"] / out["explicit"] - 1.0)))
    print(f"largest hourly difference {100 * worst:.1f} %")
    lat = lateral_displacement(project, bs, bands[len(bands) // 2][2])
    print(f"lateral displacement: stack {lat['stack_m']:.2f} m thick; "
          f"{100 * lat['scattered_share']:.0f} % of the normal transmission "
          f"({lat['t_normal']:.4f}) is scattered, and scattered light leaves the stack "
          f"≈ {lat['mean_shift_m']:.2f} m (≈ {lat['mean_shift_deg_on_inner_shell']:.0f}° on the "
          "inner shell) from where it entered — the BSDF shell releases it where it entered")


if __name__ == "__main__":
    from _common import print_resources_at_exit  # benchmarks/_common.py

    print_resources_at_exit()
    main()
