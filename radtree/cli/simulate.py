"""``radtree simulate PROJECT``: trace every scenario × hour (resumable)."""

from __future__ import annotations

import time

import click

from radtree.cli.options import CONTEXT, scenarios_option, writes
from radtree.engines.registry import ENGINE_CHOICES


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
@click.option("--scheduler", default=None, metavar="local|tcp://HOST:PORT",
              help="Distribute scenario × hour × realisation × façade-chunk tasks on Dask "
                   "(local: one worker process per core, or --workers); same resume.")
@click.option("--convergence", is_flag=True,
              help="Run the façade sensors over increasing -ab/-ad and print the change per step.")
def simulate_command(project: str, scenarios: tuple[str, ...], engine: str,
                     hours: tuple[str, ...], workers: int | None, dry_run: bool, fresh: bool,
                     convergence: bool, scheduler: str | None) -> None:
    """Trace every scenario × hour of PROJECT → PROJECT/results/illuminance.csv.

    One row per scenario × hour × grid × sensor: scenario, model, datetime, time, grid,
    sensor, row, x, y, z, lux, lux_stderr, engine, params_hash. Finished hours are kept
    (results/parts/) so an interrupted run resumes; --fresh recomputes all.
    """
    from radtree.config import load_project
    from radtree.pipeline.simulate import resolve_engine, simulate_project

    p = load_project(project)
    if convergence:
        from radtree.convergence import convergence_table, read_convergence, write_convergence

        table = convergence_table(p, list(scenarios) or None, list(hours) or None,
                                  echo=click.echo, engine=engine, workers=workers,
                                  previous=None if fresh else read_convergence(p))
        click.echo(table.to_string(index=False))
        click.echo(f"convergence table → {write_convergence(p, table)}")
        return
    eng = resolve_engine(p, engine)
    click.echo(f"engine: {eng.name}" + (" (auto)" if engine == "auto" else ""))
    t = time.perf_counter()
    executor = None
    if scheduler is not None:
        from functools import partial

        from radtree.sweep.scheduler import map_jobs

        executor = partial(_on_dask, map_jobs, scheduler, workers)
        click.echo(f"scheduler: dask {scheduler}")
    out = simulate_project(p, eng, list(scenarios) or None, list(hours) or None, workers,
                           dry_run=dry_run, echo=click.echo, resume=not fresh,
                           executor=executor)
    if out is None:
        return
    from radtree.pipeline.results import facade_means

    if "facade" in out.table.columns and out.table["facade"].notna().any():
        click.echo("building façade means (lux):")
        click.echo(out.table.groupby(["scenario", "time"])["lux"].mean().unstack("time")
                   .round(0).to_string())
    elif out.table["grid"].astype(str).str.startswith("facade@").any():   # [sensors] heights_m
        click.echo("façade sensor means per height (lux):")
        levels = out.table[out.table["grid"].astype(str).str.startswith("facade@")]
        click.echo(levels.groupby(["scenario", "grid"], sort=False)["lux"].mean()
                   .unstack("grid").round(0).to_string())
    else:
        click.echo("façade sensor means (lux):")
        click.echo(facade_means(out.table).round(0).to_string())
    unit = "tasks" if p.district is not None else "hours"   # inventories: hour × façade chunk
    click.echo(f"{out.computed} {unit} traced, {out.reused} reused, "
               f"{time.perf_counter() - t:.1f} s → {out.path}")


def _on_dask(map_jobs, scheduler, workers, fn, jobs):   # type: ignore[no-untyped-def]
    return map_jobs(fn, jobs, scheduler, workers)
