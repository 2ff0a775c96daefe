"""``radtree sweep PROJECT``: run the project once per case and rank the parameters."""

from __future__ import annotations

import time
from typing import TYPE_CHECKING

import click

from radtree.cli.options import CONTEXT, writes
from radtree.engines.registry import ENGINE_CHOICES

if TYPE_CHECKING:
    from radtree.sweep.run import SweepOutcome


@click.command("sweep", context_settings=CONTEXT)
@writes("sweep", out_param="out")
@click.argument("project", type=click.Path())
@click.option("-p", "--param", "params", multiple=True, metavar="FIELD=VALUES",
              help="A swept field: FIELD=low:high:n (n values from low to high) or "
                   "FIELD=v1,v2,... (repeatable). Replaces the [sweep.params] table.")
@click.option("--design", type=click.Choice(["full", "lhs"]), default=None,
              help="Full factorial or Latin hypercube. [default: full]")
@click.option("--samples", type=click.IntRange(min=1), default=None,
              help="Latin hypercube cases. [default: 10 per parameter]")
@click.option("--seed", type=click.IntRange(min=0), default=None,
              help="Latin hypercube seed. [default: 1]")
@click.option("-s", "--scenario", "scenarios", multiple=True,
              help="Only this scenario (repeatable). Default: all.")
@click.option("--hour", "hours", multiple=True, help="Only this hour HH:MM (repeatable).")
@click.option("--engine", type=click.Choice(ENGINE_CHOICES), default=None,
              help="auto = Radiance when found, else NumPy. [default: engine.name]")
@click.option("--scheduler", default=None, metavar="ADDRESS",
              help="A dask scheduler (tcp://host:port), 'local' (a LocalCluster on this "
                   "machine) or 'sequential' (this process). [default: local]")
@click.option("--workers", type=click.IntRange(min=1), default=None,
              help="Worker processes of the local cluster. [default: CPU cores]")
@click.option("--out", type=click.Path(), default=None,
              help="Output folder. [default: PROJECT/sweep]")
@click.option("--set", "fixed", multiple=True, metavar="FIELD=VALUE",
              help="Set a field in every case, e.g. --set sensors.dense_grid=false "
                   "(repeatable).")
@click.option("--no-progress", is_flag=True, help="No progress bar.")
def sweep_command(*, project: str, params: tuple[str, ...], design: str | None,
                  samples: int | None, seed: int | None, scenarios: tuple[str, ...],
                  hours: tuple[str, ...], engine: str | None, scheduler: str | None,
                  workers: int | None, out: str | None, fixed: tuple[str, ...],
                  no_progress: bool) -> None:
    """Run PROJECT once per combination of unknown parameters and rank their effect.

    \b
    Example:
      radtree sweep examples/mendoza-street -s A \\
          --param tree.crown.trunk_distance_m=2:6:5 --param tree.louvers.layers=3,4,5
    Each case is an ordinary project in PROJECT/sweep/cases/<case_hash>/; finished cases
    are skipped on a rerun. Outputs in PROJECT/sweep/: results.csv (every case's rows with
    its parameters), cases.csv, failures.csv, metrics.csv (nRMSE/nMBE and façade means per
    case), sensitivity.csv and tornado.png. Settings may also live in a [sweep] table of the
    project file (command-line options win).
    """
    from radtree.pipeline.options import RunOptions
    from radtree.sweep.design import parse_set
    from radtree.sweep.run import SweepOptions, run_sweep

    if no_progress:
        _no_bars()
    t = time.perf_counter()
    outcome = run_sweep(project, sweep=SweepOptions(
        params=params, design=design, samples=samples, seed=seed, out=out,
        fixed=parse_set(fixed)), run=RunOptions(
        engine=engine, scenarios=scenarios, hours=hours, scheduler=scheduler, workers=workers))
    _print_outcome(outcome, time.perf_counter() - t)


def _no_bars() -> None:
    """``--no-progress``: keep the messages of ``radtree`` (when on), without progress bars."""
    import logging

    from radtree import log

    if log.enabled():
        log.enable(logging.getLogger(log.ROOT).level, progress=False)


def _print_outcome(outcome: SweepOutcome, seconds: float) -> None:
    """What a sweep prints as its result: counts, the ranking per scenario, the files."""
    o = outcome.out_dir
    click.echo(f"{len(outcome.computed)} cases run, {len(outcome.reused)} reused, "
               f"{len(outcome.failed)} failed in {seconds:.1f} s")
    if outcome.failed:
        click.secho(f"failed cases (parameters and errors): {o / 'failures.csv'}",
                    fg="yellow", err=True)
    sens = outcome.sensitivity
    if sens is not None and len(sens):
        metric = "nrmse" if "nrmse" in set(sens["metric"]) else "facade_mean_lux"
        label = {"nrmse": "nRMSE", "facade_mean_lux": "daily mean façade lux"}[metric]
        for sc, g in sens[sens["metric"] == metric].groupby("scenario", sort=True):
            g = g.sort_values("effect_range", ascending=False)
            click.echo(f"scenario {sc}: {label} range by parameter")
            for _, r in g.iterrows():
                fmt = ".3f" if metric == "nrmse" else ",.0f"
                click.echo(f"  {r['parameter']:<40} {r['effect_low']:{fmt}} – "
                           f"{r['effect_high']:{fmt}}  ({r['value_at_low']} → "
                           f"{r['value_at_high']})")
    click.echo(f"results → {outcome.path}")
    if (o / "sensitivity.csv").exists():
        click.echo(f"sensitivity → {o / 'sensitivity.csv'}, {o / 'tornado.png'}")
