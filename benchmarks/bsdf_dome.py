"""BSDF crown against the explicit-slat crown on the Mendoza sensor dome (scenario B's set-up).

    PYTHONPATH=. python benchmarks/bsdf_dome.py [--samples N] [--bands 3] [--segments 0]
        [--sectors 0] [--ads 8192,12000,16384,24000]
        [--explicit-ads 2048,1810,1963,2290,2463] [--project DIR] [--explicit-cache CSV]

Traces scenario B (explicit slats, Radiance) and the same scenario with
``tree.representation = "bsdf"`` (the dome as a shell of the crown layer's Klems BSDF) at the
project's hours and prints the façade means per hour, their ratio and the 7-hour mean
(``--curvature rings``: the traced row only rescaled ring by ring; ``planar``: the flat
stack's BSDF without the traced view from the centre; ``--sectors N``: each band's row traced
in N sectors of the horizontal angle from the façade normal); then what the BSDF cannot
represent: the lateral displacement of light inside the 2.2 m thick slat stack (see
:func:`lateral_displacement`).

Noise: rtrace runs with ``-u-`` (the same octree and options give the same numbers), so each
crown is traced once per ``-ad`` of ``--ads`` / ``--explicit-ads`` — values that give
different ambient divisions (Radiance rounds -ad to n_θ × n_φ strata: 2047 and 2048 trace
alike, and above ≈ 25 000 the BSDF crown's numbers stop changing) — and the table gives the
mean over them with the standard deviation of one run (sd) per hour. One BSDF run scatters by
2–4 % per hour (3–4 % at 10:30), so 4 runs leave ≈ ±2 % and a 5 % test needs ≈ 24 (session
13: 8 runs read 10:30 +5.6 ± 1.6 %, 24 runs +4.1 ± 0.7 %). ``--segments``: the BSDF shell's
``tree.bsdf.segments`` (rings = segments / 4; 0: the project's, default 192; the slat dome
does not use it).
Run it on a copy of the example (``--project``) when others use its build folder.
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


def ads(text: str) -> list[int]:
    return [int(a) for a in text.split(",") if a.strip()]


def repeats(project, sc, ad_values: list[int], label: str) -> pd.DataFrame:
    """Façade mean per hour (rows) and -ad (columns) of scenario ``sc``."""
    cols = {}
    for ad in ad_values:
        s = replace(sc, switches={**sc.switches, "engine.ad": ad})
        t0 = time.perf_counter()
        rows = trace_scenario(project, s, "radiance", grids=["facade"])
        cols[ad] = rows.groupby("time")["lux"].mean()
        print(f"{label} -ad {ad}: {time.perf_counter() - t0:.0f} s, "
              + " ".join(f"{v:.0f}" for v in cols[ad]), flush=True)
    return pd.DataFrame(cols)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--project", default=str(ROOT / "examples" / "mendoza-street"))
    ap.add_argument("--samples", type=int, default=500)
    ap.add_argument("--scenario", default="B")
    ap.add_argument("--bands", type=int, default=3, help="elevation bands of the dome shell")
    ap.add_argument("--sectors", type=int, default=0,
                    help="tree.bsdf.sectors: each band cut into this many sectors of the "
                         "horizontal angle from the façade normal, each with its own traced "
                         "row (0: the project's)")
    ap.add_argument("--segments", type=int, default=0,
                    help="tree.bsdf.segments: the BSDF shell's segments around (rings = "
                         "segments / 4; 0: the project's)")
    ap.add_argument("--ads", type=ads, default=[8192, 12000, 16384, 24000, 9000, 10000, 14000,
                                                20000, 6000, 6900, 7800, 8700, 9600, 10500,
                                                11400, 12300, 13200, 15000, 15900, 16800,
                                                17700, 18600, 19500, 21000],
                    help="rtrace -ad of the BSDF crown, one run each (24: see the module text)")
    ap.add_argument("--explicit-ads", type=ads, default=[2048, 1810, 1963, 2290, 2463],
                    help="rtrace -ad of the explicit slats, one run each")
    ap.add_argument("--curvature", default="traced", choices=("traced", "rings", "planar"),
                    help="tree.bsdf.curvature: the centre's view traced through the curved "
                         "dome per patch (default), per ring, or the flat stack's")
    ap.add_argument("--explicit-cache", default=None,
                    help="CSV of the explicit runs' hourly façade means (read if present)")
    args = ap.parse_args()
    project = load_project(Path(args.project))
    sc = project.scenario(args.scenario)
    # the BSDF crown's hours scatter by 1–5 % between -ad values (the sampling of the shell's
    # Klems BSDF): several runs are averaged (see the module text)
    bs = replace(sc, name=f"{sc.name}-bsdf", switches={
        **sc.switches, "tree.representation": "bsdf", "bsdf.samples": args.samples,
        "bsdf.bands": args.bands, "bsdf.curvature": args.curvature,
        **({"bsdf.segments": args.segments} if args.segments else {}),
        **({"bsdf.sectors": args.sectors} if args.sectors else {})})
    t0 = time.perf_counter()
    bands = scenario_xmls(project, bs)
    t_bsdf = time.perf_counter() - t0
    print(f"crown BSDFs ({t_bsdf:.0f} s): " + "; ".join(
        f"|elevation| {lo:g}–{hi:g}°: {xml}" for lo, hi, xml in bands))
    print(leaf_on_sample(project, bs, 0.5 * (bands[0][0] + bands[0][1])).notes[0][:200] + "…")
    cache = Path(args.explicit_cache) if args.explicit_cache else None
    if cache is not None and cache.exists():
        explicit = pd.read_csv(cache, index_col=0)
        explicit.columns = [int(c) for c in explicit.columns]
        print(f"explicit: read {cache}")
    else:
        explicit = repeats(project, sc, args.explicit_ads, "explicit")
        if cache is not None:
            explicit.to_csv(cache)
    bsdf = repeats(project, bs, args.ads, "bsdf")
    e_m, b_m = explicit.mean(axis=1), bsdf.mean(axis=1)
    e_sd = explicit.std(axis=1, ddof=1) if explicit.shape[1] > 1 else 0 * e_m
    b_sd = bsdf.std(axis=1, ddof=1) if bsdf.shape[1] > 1 else 0 * b_m
    # standard error of the ratio of the two means
    se = (b_m / e_m) * np.sqrt((b_sd / b_m) ** 2 / bsdf.shape[1]
                               + (e_sd / e_m) ** 2 / explicit.shape[1])
    print(f"{'time':>6} {'explicit':>9} {'sd %':>5} {'bsdf':>9} {'sd %':>5} {'ratio':>6} "
          f"{'± s.e.':>6}")
    for t in e_m.index:
        print(f"{t:>6} {e_m[t]:9.1f} {100 * e_sd[t] / e_m[t]:5.1f} {b_m[t]:9.1f} "
              f"{100 * b_sd[t] / b_m[t]:5.1f} {b_m[t] / e_m[t]:6.3f} {se[t]:6.3f}")
    e, b = float(e_m.mean()), float(b_m.mean())
    print(f"{'mean':>6} {e:9.1f} {'':>5} {b:9.1f} {'':>5} {b / e:6.3f}  "
          f"({100 * (b / e - 1):+.1f} %; {len(args.explicit_ads)} explicit and "
          f"{len(args.ads)} BSDF runs)")
    worst = float(np.max(np.abs(b_m / e_m - 1.0)))
    print(f"largest hourly difference {100 * worst:.1f} %; hours within 5 %: "
          f"{int(np.sum(np.abs(b_m / e_m - 1.0) <= 0.05))} of {len(e_m)}")
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
