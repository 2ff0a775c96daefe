"""``radtree export PROJECT --format FORMAT --out DIR``: the formats of
:mod:`radtree.export.registry`."""

from __future__ import annotations

import textwrap

import click

from radtree.cli.options import CONTEXT
from radtree.export.registry import EXPORT_FORMATS, FORMATS, formats_needing
from radtree.export.schedule_options import DEFINITIONS


def _help() -> str:
    """The command's help: a line per format of the registry."""
    width = max(map(len, EXPORT_FORMATS)) + 1
    rows = "\n".join(textwrap.fill(fmt.summary, 92, initial_indent=f"{name:<{width}} ",
                                   subsequent_indent=" " * (width + 1))
                     for name, fmt in EXPORT_FORMATS.items())
    traced = textwrap.fill(f"{', '.join(formats_needing('schedules'))}: each crown's "
                           "transmittance along the sun for 8760 hours (--definition total: "
                           "beam + forward-scattered light; beam: undeviated only).", 92)
    return f"Write PROJECT's crowns or scene for other tools into DIR.\n\n\b\n{rows}\n\n\b\n{traced}"


@click.command("export", context_settings=CONTEXT, help=_help())
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
@click.option("--definition", type=click.Choice(DEFINITIONS), default=DEFINITIONS[0],
              show_default=True, help="Schedule transmittance: total (beam + light the crown "
              "scatters forward) or beam (undeviated only).")
def export_command(*, project: str, fmt: str, out: str, scenario: str | None, rays: int,
                   leaf_on: str | None, leaf_off: str | None, no_seasons: bool,
                   definition: str) -> None:
    """Write PROJECT's crowns or scene for other tools into DIR (help: :func:`_help`)."""
    from pathlib import Path

    from radtree.config import load_project
    from radtree.export.run import ExportOptions, export_project
    from radtree.export.schedule_options import ScheduleOptions

    schedule = ScheduleOptions(rays=rays, leaf_on=leaf_on, leaf_off=leaf_off,
                               seasons=not no_seasons, definition=definition)
    options = ExportOptions(fmt, Path(out), scenario=scenario, schedule=schedule)
    for p in export_project(load_project(project), options=options):
        click.echo(f"wrote {p}")
