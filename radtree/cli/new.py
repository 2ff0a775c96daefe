"""``radtree new DIR``: start a project from one's own data (a commented radtree.toml)."""

from __future__ import annotations

from pathlib import Path

import click

from radtree.cli.options import CONTEXT

_FILE = click.Path(exists=True, dir_okay=False, path_type=Path)


@click.command("new", context_settings=CONTEXT)
@click.argument("folder", type=click.Path(file_okay=False, path_type=Path))
@click.option("--trees", type=_FILE, help="Tree inventory: GeoJSON points or CSV (species, "
              "height_m, crown_diameter_m, crown_base_m).")
@click.option("--buildings", type=_FILE, help="Building footprints: GeoJSON with height_m.")
@click.option("--honeybee", type=_FILE, help="A Honeybee model (HBJSON).")
@click.option("--epw", type=_FILE, help="Weather file: the site's latitude, longitude, time "
              "zone and elevation come from it (else a clear-sky year is generated).")
@click.option("--template", type=click.Choice(["street", "office", "district"]),
              help="street canyon, office block, or inventory district (default: district "
                   "with --buildings, else street).")
def new_command(folder: Path, trees: Path | None, buildings: Path | None,
                honeybee: Path | None, epw: Path | None, template: str | None) -> None:
    """Write FOLDER/radtree.toml — every field with its unit and default — and copy the
    inputs into FOLDER/data/. The file loads as written: `radtree build FOLDER` next.
    """
    from radtree.site.starter import new_project

    out = new_project(folder, trees=trees, buildings=buildings, honeybee=honeybee, epw=epw,
                      template=template)
    s = out.site
    click.echo(f"new project ({out.template} template): {out.path}")
    click.echo(f"  site: latitude {s['latitude']}, longitude {s['longitude']}, UTC"
               f"{s['utc_offset_hours']:+g} h, elevation {s['elevation_m']:g} m — "
               f"{out.site_source}")
    for line in out.inputs.lines():
        click.echo(f"  {line}")
    if out.generated_epw:
        click.secho("  weather: GENERATED clear-sky year (not measured) → "
                    "data/generated_clear_sky.epw", fg="yellow")
    click.echo(f"next: radtree build {folder}")
