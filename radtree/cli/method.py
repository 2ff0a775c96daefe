"""``radtree method PROJECT``: the study's method emulated with one setting changed at a time,
and the dome-radius scan (see :mod:`radtree.verify.method`); writes ``PROJECT/method/``."""

from __future__ import annotations

from pathlib import Path

import click

from radtree.cli.options import CONTEXT


@click.command("method", context_settings=CONTEXT)
@click.argument("project", type=click.Path(exists=True, file_okay=False, path_type=Path))
@click.option("--photons", type=click.IntRange(1000), default=1_000_000, show_default=True,
              help="Forward photons per hour (the project's own count is the study's reading).")
@click.option("--radii", default="0.5,1,1.5,2,3,4", show_default=True,
              help="Dome radii (m) scanned under the project's settings, comma-separated.")
@click.option("-s", "--scenario", "scenarios", multiple=True,
              help="Scenario(s) traced (default A–E).")
@click.option("--variant", "variants", multiple=True,
              help="Variant(s) traced (default all: study, threshold 0.005, no threshold, "
                   "whole-scene sun, dome / free crown).")
@click.option("--file", "file", default="hourly.csv", show_default=True,
              help="CSV name in PROJECT/method/ (parallel runs write different files).")
def method_command(project: Path, photons: int, radii: str, scenarios: tuple[str, ...],
                   variants: tuple[str, ...], file: str) -> None:
    """What the study's numbers owe to its method: scenarios A–E traced as the project sets
    them (the study's TracePro method in examples/mendoza-tracepro), with the threshold, the
    beam and the crown form changed one at a time, and at every dome radius of RADII. Writes
    PROJECT/method/FILE; `radtree report` then shows the section."""
    from radtree.verify.method import SCENARIOS, run_method_study

    try:
        rs = [float(v) for v in radii.split(",") if v.strip()]
    except ValueError:
        raise click.BadParameter(f"{radii!r}: expected r1,r2,... (m)", param_hint="--radii") \
            from None
    out = run_method_study(project, photons=photons, radii=rs,
                           scenarios=list(scenarios) or list(SCENARIOS),
                           variants=list(variants) or None, file=file)
    click.echo(f"wrote {out}")
