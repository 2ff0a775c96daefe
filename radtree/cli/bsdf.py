"""``radtree bsdf PROJECT -s SCENARIO --out DIR``: the crown layer's leaf-on and leaf-off BSDFs
(Klems XML via rfluxmtx + wrapBSDF, checked with checkBSDF; see :mod:`radtree.bsdf.run`)."""

from __future__ import annotations

from pathlib import Path

import click

from radtree.cli.options import CONTEXT
from radtree.config import load_project


@click.command("bsdf", context_settings=CONTEXT)
@click.argument("project", type=click.Path(exists=True, path_type=Path))
@click.option("-s", "--scenario", default="B", show_default=True,
              help="Scenario whose crown layer is sampled (a louvers crown).")
@click.option("--out", "out", type=click.Path(path_type=Path), default=None,
              help="Output folder [default: PROJECT/results/bsdf/SCENARIO].")
@click.option("--samples", type=click.IntRange(1, 100000), default=None,
              help="rfluxmtx rays per Klems patch (-c) [default: tree.bsdf.samples].")
@click.option("--tensor-tree", type=click.IntRange(0, 6), default=None,
              help="Also write a rank-4 tensor tree of this log2 resolution (4–6).")
@click.option("--leaf-on-only", is_flag=True, help="Skip the leaf-off (branches) state.")
@click.option("--nproc", type=click.IntRange(1, 64), default=1, show_default=True,
              help="rfluxmtx processes (-n).")
def bsdf_command(project: Path, scenario: str, out: Path | None, samples: int | None,
                 tensor_tree: int | None, leaf_on_only: bool, nproc: int) -> None:
    """Compute the BSDF of a scenario's crown layer, leaf-on and leaf-off.

    Sensor dome: its slat shells as a planar periodic stack; free crowns: a slab of the
    fitted slat density. Writes DIR/leaf_on.xml, leaf_off.xml (WINDOW-compatible Klems
    145 × 145), their checkBSDF reports and DIR/summary.csv (hemispherical T and R,
    reciprocity and energy checks). Example:

      radtree bsdf examples/mendoza-street -s B --out results/bsdf
    """
    from radtree.bsdf.run import STATES, compute_crown_bsdfs

    overrides: dict[str, int] = {}
    if samples is not None:
        overrides["tree.bsdf.samples"] = samples
    if tensor_tree is not None:
        overrides["tree.bsdf.tensor_tree"] = tensor_tree
    proj = load_project(project, overrides=overrides)
    sc = proj.scenario(scenario)
    out = out if out is not None else proj.results_dir / "bsdf" / sc.name
    states = ("leaf_on",) if leaf_on_only else STATES
    result = compute_crown_bsdfs(proj, sc, out, states=states, nproc=nproc)
    for _, row in result.summary.iterrows():
        click.echo(f"{row['state']}: T front (normal) {row['t_front_normal']:.4f}, R front "
                   f"{row['r_front_normal']:.4f}; diffuse T {row['t_front_diffuse']:.4f} / "
                   f"{row['t_back_diffuse']:.4f} (front/back); max T+R {row['max_front_t_plus_r']:.3f}"
                   f"; reciprocity (ring exchange) T {row['reciprocity_t']:.3f}; "
                   f"{row['seconds']:.0f} s")
    click.echo(f"Wrote {', '.join(str(r.xml) for r in result.runs.values())} and "
               f"{out / 'summary.csv'}")
