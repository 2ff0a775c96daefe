"""``radtree convergence PROJECT``: façade means over increasing ``-ab``, change per step.

It was ``radtree simulate PROJECT --convergence``, which still works (with a one-line
deprecation note) and does the same.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import click

from radtree.cli.options import CONTEXT, scenarios_option, writes
from radtree.engines.registry import ENGINE_CHOICES

if TYPE_CHECKING:
    from radtree.pipeline.options import RunOptions

#: what ``radtree simulate --convergence`` says before it runs this command's work
DEPRECATED = "`radtree simulate --convergence` is now `radtree convergence`"


@click.command("convergence", context_settings=CONTEXT)
@writes("results", "build")
@click.argument("project", type=click.Path())
@scenarios_option
@click.option("--engine", type=click.Choice(ENGINE_CHOICES), default="auto",
              show_default=True, help="auto = the project's engine.name (Radiance when found, "
                                      "else the NumPy engine).")
@click.option("--hour", "hours", multiple=True,
              help="Only this hour HH:MM (repeatable). Default: the project's first hour.")
@click.option("--workers", type=click.IntRange(min=1), default=None,
              help="Runs at once for an engine that runs programs (default: engine.workers).")
@click.option("--fresh", is_flag=True,
              help="Trace every step again (ignore results/convergence.csv).")
def convergence_command(*, project: str, scenarios: tuple[str, ...], engine: str,
                        hours: tuple[str, ...], workers: int | None, fresh: bool) -> None:
    """Trace the façade sensors of PROJECT over increasing -ab (1, 2, 3, 4, 6, 8 and the
    crown model's own) and print the façade mean and its change per step.

    One row per scenario × hour × -ab → PROJECT/results/convergence.csv (read by the report).
    Steps traced before with the same scenario, hour, -ab, -ad, engine and parameters are
    reused from that file unless --fresh. A scenario with several crown realisations is
    checked on its first one.
    """
    from radtree.pipeline.options import RunOptions

    run_convergence(project, RunOptions(engine=engine, scenarios=scenarios, hours=hours,
                                        workers=workers, fresh=fresh))


def run_convergence(project: str, options: RunOptions) -> None:
    """The command's work (shared with ``simulate --convergence``): trace, print, write."""
    from radtree.config import load_project
    from radtree.convergence import convergence_table, read_convergence, write_convergence

    p = load_project(project)
    table = convergence_table(p, options=options,
                              previous=None if options.fresh else read_convergence(p))
    click.echo(table.to_string(index=False))
    click.echo(f"convergence table → {write_convergence(p, table)}")
