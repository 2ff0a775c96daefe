"""``radtree report PROJECT [--open]`` — registered on the main group by radtree.cli."""

from __future__ import annotations

import sys
import traceback

import click

from radtree.errors import RadtreeError

CONTEXT = {"help_option_names": ["-h", "--help"], "max_content_width": 100}


def _debug(ctx: click.Context) -> bool:
    root = ctx.find_root()
    return bool(isinstance(root.obj, dict) and root.obj.get("debug"))


def headline_table(path) -> str:
    """The headline statistics of ``report/statistics.csv`` as aligned text."""
    import pandas as pd

    stats = pd.read_csv(path, dtype={"scenario": str})
    if stats.empty:
        return "no measurements: no statistics (simulated values only)"
    cols = {"scenario": "scenario", "model": "model", "reflection": "reflection",
            "rmse": "nRMSE", "rmse_low": "low", "rmse_high": "high", "mbe": "nMBE", "r": "r",
            "r2": "R²", "n_hours": "n"}
    table = stats[list(cols)].rename(columns=cols)
    table["reflection"] = table["reflection"].fillna("")
    text = table.to_string(index=False, float_format=lambda v: f"{v:.3f}")
    return (text + "\nnRMSE, nMBE: normalised by the mean measured value (nMBE > 0: "
            "under-prediction); low–high: 95 % bootstrap interval on nRMSE")


@click.command("report", context_settings=CONTEXT)
@click.argument("project", type=click.Path())
@click.option("--open", "open_", is_flag=True, help="Open index.html in the default browser.")
@click.pass_context
def report_command(ctx: click.Context, project: str, open_: bool) -> None:
    """Statistics, plots and an HTML report of PROJECT → PROJECT/report/index.html.

    \b
    PROJECT/report/
      index.html  index.md      the report (tables, figures, provenance)
      statistics.csv            scenario, model, reflection, rmse, rmse_low, rmse_high,
                                mbe, r, r2, n_hours (normalised as SPEC.md §3)
      hourly.csv                time, measured_lux, one column per scenario (lux)
      figures/  models/         150 dpi PNG figures, crown-model pictures
    Needs PROJECT/results/illuminance.csv (run `radtree simulate PROJECT` first).
    """
    from radtree.config import load_project
    from radtree.report.build import build_report

    try:
        p = load_project(project)
        index = build_report(p, echo=click.echo)
        click.echo("")
        click.echo(headline_table(index.parent / "statistics.csv"))
    except RadtreeError as exc:
        if _debug(ctx):
            raise
        click.secho(f"error: {exc}", fg="red", err=True)
        sys.exit(2)
    except (ValueError, OSError) as exc:
        if _debug(ctx):
            traceback.print_exc()
        click.secho(f"error: {exc}", fg="red", err=True)
        sys.exit(2)
    click.echo("")
    click.echo(f"report: {index}")
    if open_:
        click.launch(str(index))
