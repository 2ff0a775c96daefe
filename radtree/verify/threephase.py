"""The three-phase check of ``radtree verify --full``: on a small free crown (one volume-louvers
crown in front of the façade sensors), the chain V·T·D of ``radtree annual --method 3phase``
against a direct ``rcontrib`` of the same BSDF-crown scene on a uniform sky
(:mod:`radtree.annual.closure`): façade mean within :data:`CLAIM` (issue 40, item 2). The
crown's BSDF is computed with few rays (``tree.bsdf.samples = 10``): both sides trace the
same XML, so its own accuracy is not what is checked.

The chain is the annual method's default (free crowns: one facet group per facet plane,
:data:`radtree.annual.facets.FACETS`). The view matrix and the reference trace
``-ad 65536 -lw 1e-6``: at ``-aa 0`` Radiance caps a hemisphere's divisions at about
0.8 / ``-lw`` (``samp_hemi`` in ``src/rt/ambcomp.c``, "avoid ray termination"), so at
``-lw 1e-3`` any ``-ad`` above ≈ 800 traced the same ≈ 784 rays and the reference moved by
1 % between seeds (measured, issue 40).
"""

from __future__ import annotations

import logging
import tempfile
from dataclasses import replace
from pathlib import Path

from radtree.verify.checks import Check
from radtree.verify.projects import FREE_TREE, SHORT_STREET, SMALL_CROWN, mendoza_site

log = logging.getLogger(__name__)

#: the relative agreement the chain claims with a direct trace of the same BSDF scene
CLAIM = 0.03

PROJECT = ('[project]\nname = "verify: three-phase closure"\n\n'
           + mendoza_site(date="2024-12-22", hour="12:30") + SHORT_STREET
           + '[light]\ndirect_normal = "dni.csv"\n' + FREE_TREE + SMALL_CROWN + """segments = 12

[tree.louvers]
arrangement = "volume"
crossings = 4
slat_size_m = 0.6

[tree.bsdf]
samples = 10
tiles = 5
bands = 1

[sensors]
dense_grid = false

[[scenario]]
name = "with"
model = "louvers"
""")


def write_project(root: Path) -> Path:
    """:data:`PROJECT` and its (unused: no sun is traced) DNI table written to ``root``."""
    (root / "radtree.toml").write_text(PROJECT)
    (root / "dni.csv").write_text("time,direct_normal_lux\n12:30,0\n")
    return root


def closure_checks(folder: Path | None = None, *, ad: int = 65536, lw: float = 1e-6,
                   samples: int = 200) -> list[Check]:
    """The façade's uniform-sky closure (leaf-on), ``ad`` ambient rays per sensor and the
    weight limit ``lw`` for V and the reference, ``samples`` rays per Klems patch of a
    level-0 group for D; work files in ``folder`` (default a temporary one). Each check is
    logged (INFO) as it is made."""
    from radtree.annual.closure import ClosureSettings, closure_table
    from radtree.annual.coefficients import TraceParams
    from radtree.annual.threephase import GROUP_MATERIAL_UP, crown_models
    from radtree.config import load_project
    from radtree.pipeline.assemble import make_scene
    from radtree.pipeline.crown_bsdf import scenario_xmls

    with tempfile.TemporaryDirectory(prefix="radtree-verify-3phase-") as tmp:
        root = Path(folder) if folder is not None else Path(tmp)
        root.mkdir(parents=True, exist_ok=True)
        write_project(root)
        project = load_project(root)
        sc = project.scenario("with")
        on = scenario_xmls(project, sc)
        models, form = crown_models(project, sc, {"leaf_on": on, "leaf_off": on})
        bare = make_scene(project, replace(sc, model="none"), dense_grid=False).scene
        settings = ClosureSettings(TraceParams(ab=6, ad=ad, lw=lw), samples, None,
                                   GROUP_MATERIAL_UP)
        table = closure_table(bare, models=models, form=form, grids=["facade"],
                              rho=project.street.ground_reflectance, folder=root / "closure",
                              settings=settings)
    out = []
    for _, row in table.iterrows():
        if row["light"] != "sky":
            continue
        name = (f"three-phase chain vs rcontrib, same BSDF crown, uniform sky, "
                f"{row['grid']} mean ({row['state']})")
        out.append(Check(name, "radiance", float(row["reference"]), float(row["chain"]),
                         CLAIM * float(row["reference"]),
                         reference="rcontrib on the same BSDF-crown scene"))
        log.info(f"{name}: reference {row['reference']:.4f}, chain {row['chain']:.4f}")
    return out
