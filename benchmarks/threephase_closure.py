"""Three-phase closure: the chain Σ_g V_g·T_g·D_g (+ reflection + by-pass) against a direct
``rcontrib`` of the *same* BSDF-crown scene, on a uniform sky (radiance 1 above the horizon,
0 below: the ``h=u`` ground column 0) and on a uniform ground hemisphere (the ground column 1,
the sky 0), per grid and leaf state — the matrices' own error, with no crown representation
in it (issue 40, item 2).

Copies the project (default ``examples/office-block``) into ``--work`` once (kept: the crown
BSDFs and every matrix are cached there, so a rerun only traces what a changed setting
needs), computes the crown BSDFs with ``tree.bsdf.samples = --samples``, and for each facet
grouping in ``--levels`` (:func:`radtree.annual.facets.group_directions`: 0 = the 14
cube directions; k ≥ 1 an icosphere of k − 1 subdivisions; ``facets`` one group per facet
plane, :data:`radtree.annual.facets.FACETS`, the annual default for free crowns) and each
``--up`` choice
(``default``: rfluxmtx's default up; ``material``: the ``BSDF`` material's up vector, the frame
the XML is applied in by rtrace) prints

    grid, state, sky/ground, reference (rcontrib on the BSDF scene), chain, ratio, by-pass,
    transmitted, reflected (each a mean over the grid's sensors, irradiance per unit radiance)

Run: ``nice .venv/bin/python benchmarks/threephase_closure.py [--work DIR] [--samples 50]
[--daylight-samples 100] [--levels facets,0] [--up default,material] [--ad 8192] [--lw 1e-5]
[--xml X] [--rows]
[-j 2]``.

Measured 8 December 2026 (02:50–03:52 UTC, load 2.5–6 on 2 cores; the office, uniform sky,
leaf-on, ``--levels facets --up material --daylight-samples 100 --states leaf_on``, the
crown XMLs of ``--samples 500``; façade / work plane):

* **The reference needs ``-ad 8192 -lw 1e-5``** (the defaults since; they were ``-ad 1024
  -lw 1e-3``): the work-plane reference read 0.00360 there, 0.00418 at ``-ad 8192 -lw
  1e-5``, 0.00416 at ``-ab 8 -ad 32768 -lw 1e-6`` (façade 0.0462, 0.0453, 0.0454); ``-ab 12``
  moved neither. Before the fixes below: 1.094 / 1.133 at the old settings (1.103 / 1.132
  in the lead's run), 1.135 / 1.025 at the new.
* Controlled XMLs (``--xml``-like, before the fixes, ``-ad 8192 -lw 1e-5``): a clear XML
  (T = δ/Λ, R = 0) 1.004 / 1.000 and δ × 0.3 0.993 / 0.991 — the geometry of V and D is
  right; Lambertian (T 0.3, R 0.1) 1.070 / 1.167; the office XML on the wall cap only (the
  bands clear) 1.024 / 1.051, on the bands only 1.013 / 0.949. Per façade row (z 4.0 … 6.0
  m) with the office XMLs: 1.12, 1.40, 1.06, 1.06, 1.03.
* **Cause 1: one facet group across the three crowns.** The envelopes of a row are glued
  into one shell, and the facet-plane grouping put the facets of one orientation of all
  three crowns (8 m apart) into one group, whose daylight matrix is their mean; the sensors
  see the central crown, whose facets next to the façade get less light from inside than
  the end crowns'. One group per crown (:func:`radtree.annual.facets.shell_parts`): 1.034 /
  1.006 (the two lowest façade rows 1.40 → 1.09, 1.12 → 0.98).
* **Cause 2: the room-side daylight matrices looked back into the crown.** rfluxmtx sends a
  sender's rays away from its polygons' normal whatever ``h=±kf``; the room-side sender
  (:func:`radtree.engines.radiance.threephase.sender_text`) was wound to the room with
  ``h=+kf``, so its rays went into the crown and read the light the crown sends into the
  room: Σ Λ·D' of the wall-cap tiles in front of the office 0.0385–0.0399 against rtrace 2 mm
  in front of the cap, facing the glazing, 0.0072–0.0093 (4–5 ×). The chain then reflected
  the crown's own light back at the sensors (R·D' was 6.7 % of the façade's light). Wound
  away from the room: **façade 0.991, work plane 0.950** (``-c 100``; ``-c 400``: 0.994 /
  0.956). Per façade row 0.96, 1.02, 1.01, 1.01, 0.97. At the old reference settings
  (``--ad 1024 --lw 1e-3``, 04:02 UTC) the same chain read 0.953 / 1.043: the reference's
  error there (façade 0.0462, work plane 0.0036) is larger than the claim.
* Not resolved: the work plane's −5 %. With the office XMLs' reflection zeroed (and the
  per-crown grouping) the chain read 0.989 / 0.987, so it sits in the crown's reflection or
  the light it scatters toward the window, not in the sampling of D (``-c`` × 4 moved it by
  0.6 %). Also measured: rtrace's correlated sampling (``-u-``, radtree's fixed seed) reads
  a Lambertian wall cap's transmission 3.5 % low 5 mm in front of it (0.289 × the light 2 mm
  behind it, ``-u+`` 0.300, T = 0.3); on the office XMLs ``-u+`` moved the reference by
  0.6 %.
* **The reflection term's frame and block (helper ``shells2``, 8 December 2026 04:10–04:30 UTC,
  load 2.4–4.3; same settings, ``--xml`` controlled XMLs in a copy of the 500-sample folder).**
  T = 0.3 δ/Λ with R = 0.3 sent into one half of the outgoing hemisphere (Klems patch-centre
  azimuth 0–180°, the material's +y = up, or 180–360°, down), against δ × 0.3 with R = 0
  (reference 0.0999 / 0.0122, chain 0.0974 / 0.0121): reflection up, reference 0.1450 / 0.0174,
  chain 0.1423 / 0.0168 (0.981 / 0.965); down, reference 0.1518 / 0.0174, chain 0.1540 / 0.0181
  (1.015 / 1.043); the reference's work plane does not tell up from down, the chain's does.
  **These XMLs are not reciprocal, and rtrace does not apply them as rmtxop does** (below), so
  they test little. Lambertian XMLs (reciprocal): T 0.3, R 0.1 → 0.998 / 1.088; T 0.3, R 0 →
  1.008 / 1.108: reflection adds 0.0013 to the work-plane reference and 0.0012 to the chain
  (façade 0.0121 and 0.0112) — the reflection term's total is right. The office XMLs' −5 % was
  the mirror of T below; the Lambertian XML's work plane (1.108 with R 0; δ × 0.3: 0.991) is
  not explained by it (a uniform T has no left/right) and stays open. The block is the right
  one: the shell's normals point into the crown, so light from the room's side meets the XML's
  "Reflection Front" (Radiance ``bsdf_m.c`` swaps WINDOW's front and back), which
  ``turned_xml`` + ``room_reflection_xml`` hand to rmtxop.
* **A left/right mirror in T (found; fixed for free crowns).** One 1 × 1 m window (normal down,
  into the room, BSDF ``u=+Y``) in a black ceiling, a glow patch 45° up to one side, two
  sensors 1 m below and 1 m to either side (``benchmarks/klems_handedness.py``): an XML that
  passes light only when both the incident and the outgoing Klems patch have local x > 0
  (azimuth within ±80°; unchanged by reciprocity) lights the sensor on the far side of the
  window from the glow in rtrace (0.0161), the sensor on the glow's side in the chain (``rmtxop
  V T D``, sender ``h=-kf``, receiver ``h=kf``, both ``u=+Y``: 0.0171, the other 0; with the
  receiver ``h=-kf`` too, 0 / 0.0171). Radiance indexes a Klems matrix's incident and outgoing
  patches in one frame (``bsdf_m.c``: fi/bi/fo/bo_getndx all take the propagation direction's
  x, y), while rfluxmtx's ``h=-kf`` sender takes x = −(up × normal) and the ``h=kf`` receiver x
  = +(up × normal) (``rfluxmtx.c`` ``prepare_sampler``, ``klems_full.cal`` ``kbin``). So
  ``V·T·D`` reflects the transmitted light left/right about the up vector. From the frames
  (rtrace's x = normal × up, as measured; derived, not measured on a crown): on the D side for
  free crowns (normals into the crown), on the V side for the dome; the room-side ``V·R·D'``
  (sender wound away from the room, x = up × n on both sides) is in rtrace's frame. The fix for
  free crowns: their outward D sender ``h=+kf`` (``sender_text(material_faces_room=False)``);
  the dome keeps the tutorial convention (its V side stays mirrored, open). **The office
  closure with it (04:32 UTC, load 1.1–2.1, same settings): façade 1.009, work plane 1.014**
  (ground 0.929 / 0.884, 0.0026 / 0.0002 of light); per façade row 0.994, 1.036, 1.018, 1.018,
  0.986 — so the scene or the crown XMLs are not left/right symmetric after all, and the mirror
  was the work plane's −5 %.
* Also seen: an XML whose reflection block on the room's side is all zero ("Reflection Front"
  0, "Reflection Back" up) still gets a reflected term (façade 0.0109 of 0.1413; without it the
  chain would read 1.008 / 1.006): rmtxop's ``cm_loadBTDF`` falls back to the other
  transmission block by reciprocity when the one it reads is absent (Radiance
  ``src/common/cmbsdf.c``; that an all-zero block counts as absent is inferred from this run),
  and ``room_reflection_xml`` puts the other reflection block there. Crown XMLs have both
  blocks, so the office is not affected. The chain reads façade rows 5.0, 5.5 and 6.0 m alike
  (0.0957, 0.0957, 0.0955 for δ × 0.3; the reference 0.0951 … 0.1026): one wall-cap tile fills
  those sensors' view.
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import radtree.log  # noqa: E402
from radtree.annual.closure import (  # noqa: E402
    ClosureSettings,
    closure_sensors,
    closure_table,
)
from radtree.annual.coefficients import TraceParams  # noqa: E402
from radtree.annual.run import annual_ground_reflectance  # noqa: E402
from radtree.annual.threephase import crown_models, state_xmls  # noqa: E402
from radtree.config import load_project  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--project", type=Path, default=ROOT / "examples" / "office-block")
    ap.add_argument("--work", type=Path, default=Path("/tmp/threephase_closure"))
    ap.add_argument("--samples", type=int, default=50, help="tree.bsdf.samples")
    ap.add_argument("--daylight-samples", type=int, default=100, help="rfluxmtx -c of D")
    ap.add_argument("--levels", default="facets,0",
                    help="comma-separated: facets (one group per facet plane) or 0, 1, 2 …")
    ap.add_argument("--up", default="default,material")
    ap.add_argument("--ab", type=int, default=6)
    ap.add_argument("--ad", type=int, default=8192)
    ap.add_argument("--lw", type=float, default=1e-5,
                    help="-lw of V and the reference: at -aa 0 Radiance traces at most "
                         "≈ 0.8 / lw rays per hemisphere whatever -ad says (ambcomp.c)")
    ap.add_argument("--states", default="leaf_on,leaf_off")
    ap.add_argument("--xml", type=Path, default=None,
                    help="tree.bsdf.xml: one given crown XML for every band (no crown BSDF "
                         "computed; the closure compares the chain with a trace of the same "
                         "XML, so any XML serves)")
    ap.add_argument("--tile", type=float, default=0.0,
                    help="the wall cap's tile size, m (0: GROUP_TILE_M)")
    ap.add_argument("--rows", action="store_true",
                    help="also the ratio per sensor row (height) of each grid, uniform sky")
    ap.add_argument("-j", "--processes", type=int, default=2)
    args = ap.parse_args()
    radtree.log.enable(progress=False)   # the rfluxmtx runs, as they go
    work = args.work / args.project.name
    if not work.exists():
        shutil.copytree(args.project, work, ignore=shutil.ignore_patterns("build", "results"))
    over: dict = {"tree.bsdf.samples": args.samples}
    if args.xml is not None:
        over["tree.bsdf.xml"] = str(args.xml.resolve())
    project = load_project(work, overrides=over)
    sc = next(s for s in project.scenarios if s.model == "louvers")
    print(f"closure on {args.project} (scenario {sc.name}) → {work}; load {os.getloadavg()}",
          flush=True)
    t0 = time.perf_counter()
    states = args.states.split(",")
    if "leaf_off" in states:
        xmls = state_xmls(project, sc)
    else:     # leaf-on only: the bare crown's XML is not computed (its model is not traced)
        from radtree.pipeline.crown_bsdf import scenario_xmls

        on = scenario_xmls(project, sc)
        if args.xml is not None:   # a free crown reaching the wall: its cap too
            from radtree.pipeline.crown_bsdf import scenario_tree, wall_half_chord
            from radtree.trees.bsdf_shell import WALL_BAND

            tree, form = scenario_tree(project, sc)
            if form != "dome" and wall_half_chord(tree, project.sensors, project.street) > 0:
                on = [*on, (*WALL_BAND, args.xml.resolve())]
        xmls = {"leaf_on": on, "leaf_off": on}
    models, form = crown_models(project, sc, xmls)
    print(f"BSDFs {time.perf_counter() - t0:.0f} s", flush=True)
    from radtree.pipeline.assemble import make_scene

    bare = make_scene(project, replace(sc, model="none"), dense_grid=False).scene
    grids = [g for g in bare.grids if g != "facade_map"]
    rho = annual_ground_reflectance(project)
    trace = TraceParams(ab=args.ab, ad=args.ad, lw=args.lw, nproc=args.processes)
    pd.set_option("display.width", 200)
    from radtree.annual.facets import FACETS

    levels = [FACETS if x == "facets" else int(x) for x in args.levels.split(",")]
    for level in levels:
        for up in args.up.split(","):
            t1 = time.perf_counter()
            table = closure_table(bare, models=models, form=form, grids=grids, rho=rho,
                                  folder=project.results_dir / "closure",
                                  settings=ClosureSettings(trace, args.daylight_samples, level,
                                                           up == "material", args.tile),
                                  states=tuple(states))
            print(f"\nlevel {level}, up {up} ({time.perf_counter() - t1:.0f} s):")
            print(table.round(4).to_string(index=False), flush=True)
            if args.rows:     # per sensor row (height), uniform sky, from the cached matrices
                ref, parts, _ = closure_sensors(
                    bare, models=models, form=form, grids=grids, rho=rho,
                    folder=project.results_dir / "closure",
                    settings=ClosureSettings(trace, args.daylight_samples, level,
                                             up == "material", args.tile),
                    state=states[0])
                chain = sum(parts.values())
                start = 0
                for g in grids:
                    pts = bare.grids[g].points
                    sel = slice(start, start + len(pts))
                    start += len(pts)
                    r = ref[sel, 1:].sum(axis=1)
                    c = chain[sel, 1:].sum(axis=1)
                    for z in np.unique(pts[:, 2].round(2)):
                        k = pts[:, 2].round(2) == z
                        print(f"    {g} z {z:5.2f} m: reference {r[k].mean():.4f}, chain "
                              f"{c[k].mean():.4f}, ratio {c[k].mean() / r[k].mean():.3f}")
    print(f"load now {os.getloadavg()}")


if __name__ == "__main__":
    from _common import print_resources_at_exit  # benchmarks/_common.py

    print_resources_at_exit()
    main()
