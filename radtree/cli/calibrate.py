"""``radtree calibrate PROJECT``: set the crown's density to reach a target permeability."""

from __future__ import annotations

from pathlib import Path

import click

from radtree.calibrate.direct import PERMEABILITY_DEFINITION, calibrate, write_calibrated_toml
from radtree.cli.options import CONTEXT
from radtree.config import load_project
from radtree.errors import RadtreeError
from radtree.trees.registry import calibrated_models


@click.command("calibrate", context_settings=CONTEXT)
@click.argument("project", type=click.Path(exists=True, path_type=Path))
@click.option("--target", type=float, default=None,
              help="Target permeability as a fraction (default: tree.homogeneous.permeability "
                   "of the project, e.g. 0.055).")
@click.option("--model", "model", type=click.Choice(calibrated_models()),
              default="louvers", show_default=True, help="Crown model to calibrate.")
@click.option("--form", type=click.Choice(["dome", "free"]), default=None,
              help="Crown form (default: tree.form of the project).")
@click.option("--photo-openness", is_flag=True,
              help="Use the openness of tree.perforated.photo as the target.")
@click.option("--directions", type=click.IntRange(64, 65536), default=2048, show_default=True,
              help="Cosine-weighted rays per sensor.")
@click.option("--tolerance", type=click.FloatRange(1e-5, 0.05), default=0.001, show_default=True,
              help="Accepted |traced − target| (fraction).")
@click.option("--global", "global_", is_flag=True,
              help="Louvers: choose the integer layer count (dome, layered crowns) or the "
                   "slat density `crossings` (free crowns, arrangement = \"volume\") whose "
                   "*global* permeability (façade illuminance with the crown / open street, "
                   "every light path, NumPy engine) is closest to the target.")
@click.option("--realisations", type=click.IntRange(1, 64), default=8, show_default=True,
              help="--global with free volume crowns: crown realisations (louvers.seed 1…N) "
                   "averaged per density (one realisation scatters by ≈ 10 %).")
@click.option("--write/--no-write", default=False, show_default=True,
              help="Write <project>.calibrated.toml beside the project file (never the project "
                   "file itself).")
def calibrate_command(*, project: Path, target: float | None, model: str, form: str | None,
                      photo_openness: bool, directions: int, tolerance: float,
                      global_: bool, realisations: int, write: bool) -> None:
    """Calibrate the crown of PROJECT (a folder with radtree.toml, or the file) to a target
    permeability by tracing straight rays from the façade sensors through the built crown.

    Permeability here is the direct (specular) crown transmission seen by the sensors,
    cosine-weighted over each sensor's hemisphere; diffuse transmission and reflections are
    excluded. Louvers: the layer count and cover fraction are chosen; perforated: the openness
    of the random gaps; homogeneous: its transmittance (analytically).
    """
    proj = load_project(project)
    if global_:
        from radtree.calibrate.permeability import GLOBAL_DEFINITION, calibrate_global

        click.echo(GLOBAL_DEFINITION)
        click.echo(calibrate_global(proj, target, form, realisations).summary())
        return
    result = calibrate(proj, model=model, target=target, form=form,
                       photo_openness=photo_openness, directions=directions,
                       tolerance=tolerance)
    click.echo(f"Calibrating the {result.model} crown ({result.form} form) of "
               f"{proj.source}")
    click.echo(f"Target permeability {100 * result.target:.3f} % ({result.target_source}).")
    click.echo(f"Permeability = {PERMEABILITY_DEFINITION}.")
    click.echo("")
    click.echo("Candidates tried:")
    click.echo(result.table())
    click.echo("")
    for note in result.notes:
        click.echo(note)
    chosen = ", ".join(f"{k} = {v}" for k, v in result.parameters.items())
    click.echo(f"Chosen: [{result.section}] {chosen} → permeability "
               f"{100 * result.achieved:.3f} % (target {100 * result.target:.3f} %, "
               f"off by {100 * abs(result.achieved - result.target):.3f} points).")
    if not result.reached:
        raise RadtreeError(
            f"the target permeability {100 * result.target:.3f} % was not reached "
            f"(best {100 * result.achieved:.3f} %); nothing written")
    if write:
        out = write_calibrated_toml(proj, result)
        click.echo(f"Wrote {out} (your {Path(proj.source).name} is unchanged).")
