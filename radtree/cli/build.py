"""``radtree build PROJECT``: write the Radiance build folders."""

from __future__ import annotations

import time

import click

from radtree.cli.options import CONTEXT, scenarios_option, writes


@click.command("build", context_settings=CONTEXT)
@writes("build")
@click.argument("project", type=click.Path())
@scenarios_option
@click.option("--no-pictures", is_flag=True, help="Skip the PNG picture of each crown model.")
@click.option("--fresh", is_flag=True,
              help="Rebuild every folder, also those that are current (same radtree version, "
                   "parameters, input files and scene files).")
@click.option("--workers", type=click.IntRange(min=1), default=None,
              help="Processes building folders side by side (default: the usable cores, "
                   "when there are 4 crowns or more to build that the build cache lacks).")
def build_command(*, project: str, scenarios: tuple[str, ...], no_pictures: bool,
                  fresh: bool, workers: int | None) -> None:
    """Write the Radiance build folder of PROJECT.

    \b
    PROJECT/build/<scenario>/
      materials.rad  geometry/*.rad  grids/*.pts  skies/<HHMM>.sky  Makefile  manifest.json
    Each Makefile has one target per hour and runs without Python:
      make -j2 -C PROJECT/build/A

    A folder that is current (built by this radtree for the same parameters and input
    files, its scene files unchanged) is kept; --fresh rebuilds it. Crowns built before
    (by any project, keyed by all that shapes them) come from the build cache: see
    `radtree cache` (RADTREE_CACHE_DIR=off turns it off).
    """
    from radtree.config import load_project
    from radtree.pipeline.build import build_project
    from radtree.pipeline.inputs import check_inputs

    t = time.perf_counter()
    p = load_project(project)
    check_inputs(p)
    click.echo(f"building {p.name} ({len(p.scenarios)} scenarios, {len(p.site.hours)} hours)")
    build_project(p, list(scenarios) or None, pictures=not no_pictures, fresh=fresh,
                  workers=workers)
    click.echo(f"build written to {p.build_dir} in {time.perf_counter() - t:.1f} s")
