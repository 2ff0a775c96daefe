"""``radtree export PROJECT --format honeybee|idf|schedule|gltf|obj --out DIR``."""

from __future__ import annotations

import click

from radtree.cli.options import CONTEXT
from radtree.export import FORMATS


@click.command("export", context_settings=CONTEXT)
@click.argument("project", type=click.Path())
@click.option("--format", "fmt", type=click.Choice(FORMATS), required=True,
              help="What to write (see below).")
@click.option("--out", "out", type=click.Path(), required=True, help="Output folder.")
@click.option("-s", "--scenario", default=None,
              help="Scenario to export (default: the first with a crown model).")
@click.option("--rays", default=128, show_default=True, type=click.IntRange(8, 100000),
              help="Rays per hour and crown for the transmittance schedule.")
@click.option("--leaf-on", default=None, help="Leaf-on date MM-DD (default by hemisphere).")
@click.option("--leaf-off", default=None, help="Leaf-off date MM-DD (default by hemisphere).")
@click.option("--no-seasons", is_flag=True, help="Leafed crowns all year (no leaf-off).")
@click.option("--definition", type=click.Choice(["total", "beam"]), default="total",
              show_default=True, help="Schedule transmittance: total (beam + light the crown "
              "scatters forward) or beam (undeviated only).")
def export_command(project: str, fmt: str, out: str, scenario: str | None, rays: int,
                   leaf_on: str | None, leaf_off: str | None, no_seasons: bool,
                   definition: str) -> None:
    """Write PROJECT's crowns or scene for other tools into DIR.

    \b
    honeybee  radtree_crowns.hbjson: crowns as Honeybee ShadeMesh, leaf Radiance modifier,
              hourly transmittance schedule (8760 values) along the sun direction
              (--definition total: beam + forward-scattered light; beam: undeviated only)
    idf       radtree_crowns.idf: the same shades and schedules for EnergyPlus, with
              ShadowCalculation PolygonClipping, frequency 1 (else EnergyPlus may ignore them)
    schedule  crown_transmittance.csv (8760 rows, a column per crown) + Schedule:File .idf
    gltf/obj  <scenario>_scene.glb / .obj: the whole scene for any 3-D viewer
    """
    from pathlib import Path

    from radtree.config import load_project
    from radtree.export.run import export_project

    paths = export_project(load_project(project), fmt, Path(out), scenario, rays, leaf_on,
                           leaf_off, not no_seasons, echo=click.echo, definition=definition)
    for p in paths:
        click.echo(f"wrote {p}")
