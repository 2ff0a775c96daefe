"""BSDF crown against the explicit-slat crown for free-standing crowns (the office example).

    PYTHONPATH=. python benchmarks/bsdf_free.py [--samples 200] [--ad 8192] [--hours 10:30,13:30]

Traces the office example's scenario "with" (a row of free volume-louvers crowns in front of
the central office) with Radiance three ways and prints the façade-grid and work-plane means
per hour, their ratios to the explicit crown and the mean over the hours:

* ``explicit`` — the 52 162 slats;
* ``chord`` — ``tree.representation = "bsdf"`` with the envelope BSDF (default
  ``tree.bsdf.crossing = "chord"``: each crossing of the envelope carries the half chord
  R cos θ, slats turned as each band of facets sees them);
* ``slab`` — the same shell with the earlier one-slab BSDF (``crossing = "slab"``: one slab
  R deep at every incidence, slats inclined from the facet normal).

The BSDF crowns are traced at ``--ad`` (default 8192: the Klems sampling of a BSDF shell is
noisier than the slats' specular paths at the project's -ad 2048). The explicit crown's means
can be cached with ``--explicit-cache FILE``.
"""

from __future__ import annotations

import argparse
import time
from dataclasses import replace
from pathlib import Path

import pandas as pd

from radtree.config import load_project
from radtree.pipeline.crown_bsdf import scenario_xmls
from radtree.pipeline.trace import trace_scenario

ROOT = Path(__file__).resolve().parents[1]
GRIDS = ["facade", "workplane"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--samples", type=int, default=200, help="tree.bsdf.samples")
    ap.add_argument("--ad", type=int, default=8192, help="rtrace -ad of the BSDF crowns")
    ap.add_argument("--hours", default="", help="comma-separated HH:MM (default: all 7)")
    ap.add_argument("--variants", default="explicit,chord,slab")
    ap.add_argument("--explicit-cache", default=None, help="CSV of the explicit crown's means")
    ap.add_argument("--project", type=Path, default=ROOT / "examples" / "office-block",
                    help="the office project (a copy reuses its build/bsdf/ cache)")
    args = ap.parse_args()
    over = {"site.hours": args.hours.split(",")} if args.hours else None
    project = load_project(args.project, overrides=over)
    sc = project.scenario("with")
    variants = {"explicit": sc}
    for crossing in ("chord", "slab"):
        # the chord variant keeps the name: `radtree annual --method 3phase` caches the
        # same BSDFs under build/bsdf/with/
        name = sc.name if crossing == "chord" else f"{sc.name}-{crossing}"
        variants[crossing] = replace(sc, name=name, switches={
            **sc.switches, "tree.representation": "bsdf", "bsdf.samples": args.samples,
            "bsdf.crossing": crossing, "engine.ad": args.ad})
    wanted = args.variants.split(",")
    means: dict[str, pd.DataFrame] = {}
    cache = Path(args.explicit_cache) if args.explicit_cache else None
    for label in wanted:
        s = variants[label]
        if label == "explicit" and cache is not None and cache.exists():
            means[label] = pd.read_csv(cache, index_col=0)
            print(f"explicit: read {cache}")
            continue
        if label != "explicit":
            t0 = time.perf_counter()
            xmls = scenario_xmls(project, s)
            print(f"{label}: BSDFs {time.perf_counter() - t0:.0f} s ({len(xmls)} band(s))")
        t0 = time.perf_counter()
        rows = trace_scenario(project, s, "radiance", grids=GRIDS)
        means[label] = rows.groupby(["time", "grid"])["lux"].mean().unstack("grid")[GRIDS]
        print(f"{label}: traced {len(means[label])} hours in {time.perf_counter() - t0:.0f} s")
        if label == "explicit" and cache is not None:
            means[label].to_csv(cache)
    table = pd.concat(means, axis=1).round(1)
    pd.set_option("display.width", 200)
    print("\nmean illuminance (lux) per hour")
    print(table)
    if "explicit" in means:
        ref = means["explicit"]
        for label in [w for w in wanted if w != "explicit"]:
            ratio = means[label] / ref
            print(f"\n{label} / explicit per hour")
            print(ratio.round(3))
            overall = means[label].mean() / ref.mean()
            print(f"{label} / explicit over the hours: " + ", ".join(
                f"{g} {overall[g]:.3f} ({100 * (overall[g] - 1):+.1f} %)" for g in GRIDS))


if __name__ == "__main__":
    from _common import print_resources_at_exit  # benchmarks/_common.py

    print_resources_at_exit()
    main()
