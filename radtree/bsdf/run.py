"""The leaf-on and leaf-off BSDFs of a scenario's crown layer (``radtree bsdf``).

Leaf-on: :func:`radtree.pipeline.crown_bsdf.leaf_on_sample`. Leaf-off: a slab of opaque bark
sticks (:func:`radtree.trees.slab.branch_slab`) as deep as the leaf-on sample, whose plan-view
cover is that of the bare crown radtree grows for the annual runs
(:func:`radtree.annual.branches.build_leaf_off`, ``branch_vertical_cover``): the dome is crossed
once, so its slab takes the whole cover C; a free crown is crossed twice, so each slab takes
1 − √(1 − C). Sticks are as thick as the geometric mean of the scaffold and last-order branch
diameters of :class:`~radtree.annual.branches.BranchParams` (pipe model), at its branch
inclination. Each XML is written by wrapBSDF, accepted by checkBSDF, and read back to report
its hemispherical transmission and reflection, reciprocity and energy balance.
"""

from __future__ import annotations

import math
import shutil
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from radtree.annual.branches import BranchParams, build_leaf_off
from radtree.bsdf.klems import KlemsBsdf, read_klems
from radtree.config import Project, Scenario
from radtree.engines.radiance.bsdf import BsdfRun
from radtree.fileio import atomic_path, write_text
from radtree.pipeline.assemble import facade_frame
from radtree.pipeline.crown_bsdf import (
    CHORD_MIN_SLATS,
    ensure_bsdf,
    flux_settings,
    leaf_on_sample,
    scenario_tree,
    slab_depth,
)
from radtree.trees.slab import RingSamples, SlabSample, branch_slab, chord_samples

STATES = ("leaf_on", "leaf_off")
SUMMARY_COLUMNS = ["state", "xml", "thickness_m", "t_front_normal", "r_front_normal",
                   "t_back_normal", "r_back_normal", "t_front_diffuse", "r_front_diffuse",
                   "t_back_diffuse", "r_back_diffuse", "max_front_t_plus_r",
                   "max_back_t_plus_r", "reciprocity_r_front", "reciprocity_r_back",
                   "reciprocity_t", "seconds"]


def leaf_off_sample(project: Project, scenario: Scenario, leaf_on: SlabSample | RingSamples
                    ) -> SlabSample | RingSamples:
    """The bare-crown slab matching ``leaf_on`` (see the module text; a free crown's chord
    envelope: per Klems ring the plan cover of the optical depth −ln(1 − C₁) · cos² θ, C₁ the
    cover of one crossing)."""
    tree, form = scenario_tree(project, scenario)
    params = BranchParams()
    bare = build_leaf_off(project, scenario, facade_frame(project), params)
    cover = bare.info["branch_vertical_cover"]
    per_slab = cover if form == "dome" else 1.0 - math.sqrt(1.0 - cover)
    depth = leaf_on.thickness if form == "dome" else slab_depth(tree)
    last = params.base_diameter_m / math.sqrt(params.fork) ** (params.orders - 1)
    diameter = math.sqrt(params.base_diameter_m * last)
    cell = max(leaf_on.width, leaf_on.height)
    note = (f"Bare crown cover {100 * cover:.1f} % "
            f"({'one crossing' if form == 'dome' else 'two crossings'}).")
    if isinstance(leaf_on, RingSamples):
        tau = -math.log(1.0 - per_slab)

        def ring(d: float, c: float) -> SlabSample:
            return branch_slab(1.0 - math.exp(-tau * c * d / depth), d, params.inclination_deg,
                               diameter, params.seed, cell_m=cell, min_sticks=12)

        first = ring(depth, 1.0)
        return chord_samples(ring, depth, CHORD_MIN_SLATS * tree.louvers.slat_size_m,
                             "leaf_off", [*first.notes, note])
    sample = branch_slab(per_slab, depth, params.inclination_deg, diameter, params.seed,
                         cell_m=cell)
    sample.notes.append(note)
    return sample


@dataclass
class CrownBsdfs:
    """The written XMLs by state, their read-back matrices and the summary table."""

    runs: dict[str, BsdfRun]
    matrices: dict[str, KlemsBsdf]
    samples: dict[str, SlabSample | RingSamples]
    summary: pd.DataFrame


def summary_row(state: str, run: BsdfRun, k: KlemsBsdf) -> dict:
    rec, en = k.reciprocity_error(), k.energy_excess()
    row = {"state": state, "xml": str(run.xml), "thickness_m": k.thickness_m,
           "seconds": run.seconds}
    for key, name in (("tf", "t_front"), ("rf", "r_front"), ("tb", "t_back"), ("rb", "r_back")):
        row[f"{name}_normal"] = float(k.hemispherical(key)[0])
        row[f"{name}_diffuse"] = k.diffuse_hemispherical(key)
    row["max_front_t_plus_r"] = 1.0 + en["f"]
    row["max_back_t_plus_r"] = 1.0 + en["b"]
    row["reciprocity_r_front"], row["reciprocity_r_back"] = rec["rf"], rec["rb"]
    row["reciprocity_t"] = rec["t"]
    return row


def compute_crown_bsdfs(project: Project, scenario: Scenario, out: Path, *,
                        states: tuple[str, ...] = STATES, nproc: int = 1) -> CrownBsdfs:
    """Leaf-on/off XMLs of ``scenario`` in ``out`` (``<state>.xml``, work files in
    ``out/work/<state>/``) and ``out/summary.csv``; ``nproc`` rfluxmtx processes. The
    commands run are logged (INFO)."""
    tree, form = scenario_tree(project, scenario)
    settings = flux_settings(tree, form, nproc)
    on = leaf_on_sample(project, scenario)
    samples = {"leaf_on": on}
    if "leaf_off" in states:
        samples["leaf_off"] = leaf_off_sample(project, scenario, on)
    runs, mats, rows = {}, {}, []
    out.mkdir(parents=True, exist_ok=True)
    for state in states:
        run = ensure_bsdf(samples[state], settings, out / "work" / state, state)
        final = out / f"{state}.xml"
        with atomic_path(final) as tmp:
            shutil.copyfile(run.xml, tmp)
        if run.tensor_xml is not None:
            shutil.copyfile(run.tensor_xml, out / f"{state}_t4.xml")
        run = BsdfRun(final, run.check, run.seconds, run.tensor_xml)
        write_text(out / f"{state}_checkBSDF.txt", run.check)
        runs[state], mats[state] = run, read_klems(final)
        rows.append(summary_row(state, run, mats[state]))
    summary = pd.DataFrame(rows, columns=SUMMARY_COLUMNS)
    write_text(out / "summary.csv", summary.to_csv(index=False, float_format="%.6g"))
    notes = [f"# Crown BSDFs of scenario {scenario.name} ({form})", ""]
    for state in states:
        notes += [f"## {state}", *samples[state].notes, ""]
    notes.append(f"rfluxmtx: {' '.join(settings.options())}, {settings.tiles} × "
                 f"{settings.tiles} periodic tiles.")
    write_text(out / "README.md", "\n".join(notes) + "\n")
    return CrownBsdfs(runs, mats, samples, summary)
