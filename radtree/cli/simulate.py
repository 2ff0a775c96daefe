"""``radtree simulate PROJECT``: trace every scenario × hour (resumable)."""

from __future__ import annotations

import logging
import time
from typing import TYPE_CHECKING

import click

from radtree.cli.options import CONTEXT, scenarios_option, writes
from radtree.engines.registry import ENGINE_CHOICES

if TYPE_CHECKING:
    import pandas as pd

log = logging.getLogger(__name__)


@click.command("simulate", context_settings=CONTEXT)
@writes("results", "build")
@click.argument("project", type=click.Path())
@scenarios_option
@click.option("--engine", type=click.Choice(ENGINE_CHOICES), default="auto",
              show_default=True, help="auto = Radiance when found, else the NumPy engine.")
@click.option("--hour", "hours", multiple=True, help="Only this hour HH:MM (repeatable).")
@click.option("--workers", type=int, default=None, help="Parallel hours (default: engine.workers).")
@click.option("--dry-run", is_flag=True, help="Print the commands, run nothing.")
@click.option("--fresh", is_flag=True, help="Recompute every hour (ignore finished parts).")
@click.option("--tree-impact/--no-tree-impact", default=True, show_default=True,
              help="Attribute the light each tree takes (results/tree_impact.csv, when the "
                   "project has a scenario without trees). The NumPy engine does it, tracing "
                   "each hour two to three times more: --no-tree-impact when only the "
                   "illuminance is wanted.")
@click.option("--scheduler", default=None, metavar="local|tcp://HOST:PORT",
              help="Distribute scenario × hour × realisation × façade-chunk tasks on Dask "
                   "(local: one worker process per core, or --workers); same resume.")
@click.option("--convergence", is_flag=True,
              help="Deprecated: use `radtree convergence PROJECT` (same options).")
def simulate_command(*, project: str, scenarios: tuple[str, ...], engine: str,
                     hours: tuple[str, ...], workers: int | None, dry_run: bool, fresh: bool,
                     convergence: bool, scheduler: str | None, tree_impact: bool) -> None:
    """Trace every scenario × hour of PROJECT → PROJECT/results/illuminance.csv.

    One row per scenario × hour × grid × sensor: scenario, model, datetime, time, grid,
    sensor, row, x, y, z, lux, lux_stderr, engine, params_hash. Finished hours are kept
    (results/parts/) so an interrupted run resumes; --fresh recomputes all.
    """
    from radtree.config import load_project
    from radtree.pipeline.options import RunOptions
    from radtree.pipeline.simulate import dry_run_commands, resolve_engine, simulate_project

    options = RunOptions(engine=engine, scenarios=scenarios, hours=hours, workers=workers,
                         scheduler=scheduler, fresh=fresh)
    if convergence:
        from radtree.cli.convergence import DEPRECATED, run_convergence

        log.warning(DEPRECATED)
        run_convergence(project, options)
        return
    p = load_project(project)
    eng = resolve_engine(p, engine)
    click.echo(f"engine: {eng.name}" + (" (auto)" if engine == "auto" else ""))
    options = RunOptions(engine=eng, scenarios=scenarios, hours=hours, workers=workers,
                         scheduler=scheduler, fresh=fresh, tree_impact=tree_impact)
    if dry_run:
        for line in dry_run_commands(p, options=options):
            click.echo(line)
        return
    t = time.perf_counter()
    if scheduler is not None:
        click.echo(f"scheduler: {options.executor(1).describe}")   # dask local, …
    out = simulate_project(p, options=options)
    click.echo(_facade_means(out.table))
    unit = "tasks" if p.district is not None else "hours"   # inventories: hour × façade chunk
    click.echo(f"{out.computed} {unit} traced, {out.reused} reused, "
               f"{time.perf_counter() - t:.1f} s → {out.path}")


def _facade_means(table: pd.DataFrame) -> str:
    """The façade means (lux) a run prints: per building, per sensor height or per scenario."""
    from radtree.pipeline.results import facade_means

    if "facade" in table.columns and table["facade"].notna().any():
        return ("building façade means (lux):\n" + table.groupby(["scenario", "time"])["lux"]
                .mean().unstack("time").round(0).to_string())
    if table["grid"].astype(str).str.startswith("facade@").any():   # [sensors] heights_m
        levels = table[table["grid"].astype(str).str.startswith("facade@")]
        return ("façade sensor means per height (lux):\n"
                + levels.groupby(["scenario", "grid"], sort=False)["lux"].mean()
                .unstack("grid").round(0).to_string())
    return "façade sensor means (lux):\n" + facade_means(table).round(0).to_string()
