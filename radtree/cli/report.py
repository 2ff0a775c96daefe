"""``radtree report PROJECT [--open]``: statistics, figures and the HTML report."""

from __future__ import annotations

import click

from radtree.cli.options import CONTEXT, writes


@click.command("report", context_settings=CONTEXT)
@writes("report")
@click.argument("project", type=click.Path())
@click.option("--open", "open_", is_flag=True, help="Open index.html in the default browser.")
def report_command(project: str, open_: bool) -> None:
    """Statistics, plots and an HTML report of PROJECT → PROJECT/report/index.html.

    \b
    PROJECT/report/
      index.html  index.md      the report (tables, figures, provenance)
      statistics.csv            scenario, model, reflection, rmse, rmse_low, rmse_high,
                                mbe, r, r2, n_hours (normalised as reference case §3)
      hourly.csv                time, measured_lux, one column per scenario (lux)
      figures/  models/         150 dpi PNG figures, crown-model pictures
    Needs PROJECT/results/illuminance.csv (run `radtree simulate PROJECT` first).
    """
    from radtree.config import load_project
    from radtree.report.build import build_report
    from radtree.report.tables import headline_table

    p = load_project(project)
    index = build_report(p)
    click.echo("")
    click.echo(headline_table(index.parent / "statistics.csv"))
    click.echo("")
    click.echo(f"report: {index}")
    if open_:
        click.launch(str(index))
