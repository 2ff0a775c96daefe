"""``radtree new DIR --lat --lon --tz``: start a project at one's own site, from one's own data."""

from __future__ import annotations

from pathlib import Path

import click

from radtree.cli.options import CONTEXT

_FILE = click.Path(exists=True, dir_okay=False, path_type=Path)


@click.command("new", context_settings=CONTEXT)
@click.argument("folder", type=click.Path(file_okay=False, path_type=Path))
@click.option("--lat", "latitude", type=float, metavar="DEG",
              help="Site latitude, degrees north (south negative), e.g. 40.42.")
@click.option("--lon", "longitude", type=float, metavar="DEG",
              help="Site longitude, degrees east (west negative), e.g. -3.70.")
@click.option("--tz", "tz", metavar="AREA/CITY",
              help="IANA time zone, e.g. Europe/Madrid: hours are local clock time with "
                   "daylight saving. Default: looked up from --lat/--lon.")
@click.option("--utc", "utc", type=float, metavar="±H",
              help="A fixed UTC offset in hours instead of --tz (no daylight saving).")
@click.option("--elevation", "elevation", type=float, metavar="M",
              help="Site elevation, metres above sea level (default: the EPW's, else 0).")
@click.option("--date", "date", metavar="YYYY-MM-DD",
              help="The day to simulate (default: the summer solstice of the site's "
                   "hemisphere). Hours are every whole hour with the sun ≥ 5° high.")
@click.option("--trees", type=_FILE, help="Tree inventory: GeoJSON points or CSV (species, "
              "height_m, crown_diameter_m, crown_base_m).")
@click.option("--buildings", type=_FILE, help="Building footprints: GeoJSON with height_m.")
@click.option("--honeybee", type=_FILE, help="A Honeybee model (HBJSON).")
@click.option("--epw", type=_FILE, help="Weather file of the site (checked against it). "
              "Default: no file, the site's clear sky ([light] weather = \"clear-sky\").")
@click.option("--template", type=click.Choice(["street", "office", "district"]),
              help="street canyon, office block, or inventory district (default: district "
                   "with --buildings, else street).")
def new_command(*, folder: Path, latitude: float | None, longitude: float | None,
                tz: str | None, utc: float | None, elevation: float | None, date: str | None,
                trees: Path | None, buildings: Path | None, honeybee: Path | None,
                epw: Path | None, template: str | None) -> None:
    """Write FOLDER/radtree.toml — every field with its unit and default — and copy the
    inputs into FOLDER/data/. The inputs are checked as `radtree build` checks them; the
    file loads as written: `radtree build FOLDER` next.

    \b
    Example (a street in Madrid, clear-sky weather, 21 June):
      radtree new my-street --lat 40.42 --lon -3.70 --tz Europe/Madrid
    """
    from radtree.config.timezone import fixed_name
    from radtree.errors import ConfigError
    from radtree.pipeline.inputs import check_inputs
    from radtree.site.starter import Location, new_project

    if tz is not None and utc is not None:
        raise ConfigError("give --tz or --utc, not both")
    where = Location(latitude, longitude, tz if utc is None else fixed_name(utc), elevation,
                     date)
    out = new_project(folder, trees=trees, buildings=buildings, honeybee=honeybee, epw=epw,
                      template=template, where=where, validate=check_inputs)
    s = out.site
    click.echo(f"new project ({out.template} template): {out.path}")
    click.echo(f"  site: latitude {s['latitude']}, longitude {s['longitude']}, time zone "
               f"{s['time_zone']}, elevation {s['elevation_m']:g} m")
    if latitude is None:
        click.secho(f"  SITE NOT GIVEN ON THE COMMAND LINE — {out.site_source}. "
                    "Check it (or pass --lat/--lon/--tz).", fg="yellow", bold=True)
    else:
        click.echo(f"  ({out.site_source})")
    for line in out.inputs.lines():
        click.echo(f"  {line}")
    if out.weather == "clear-sky":
        click.echo("  weather: clear sky of the site and date (pvlib, no file); set [light] "
                   "epw for measured or typical-year weather")
    click.echo(f"next: radtree build {folder}")
