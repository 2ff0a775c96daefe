"""radtree command line: thin commands over the Python API.

    radtree build PROJECT      write Radiance build folders (PROJECT/build/<scenario>/)
    radtree simulate PROJECT   trace every scenario × hour → PROJECT/results/illuminance.csv
    radtree report PROJECT     statistics, plots, HTML → PROJECT/report/index.html

PROJECT is a folder holding radtree.toml, or the file itself.
"""

from __future__ import annotations

import sys
import traceback

import click

from radtree import __version__
from radtree.engines.registry import ENGINE_CHOICES
from radtree.errors import RadtreeError

CONTEXT = {"help_option_names": ["-h", "--help"], "max_content_width": 100}


class RadtreeGroup(click.Group):
    """Turns expected failures into one clear line (traceback only with --debug)."""

    def invoke(self, ctx: click.Context):
        try:
            return super().invoke(ctx)
        except RadtreeError as exc:
            if ctx.obj and ctx.obj.get("debug"):
                traceback.print_exc()
            click.secho(f"error: {exc}", fg="red", err=True)
            sys.exit(2)
        except (ValueError, OSError) as exc:
            if ctx.obj and ctx.obj.get("debug"):
                traceback.print_exc()
            click.secho(f"error: {exc}", fg="red", err=True)
            sys.exit(2)
        except KeyboardInterrupt:
            click.secho("interrupted: finished hours are kept in results/parts/; "
                        "run the same command again to resume", fg="yellow", err=True)
            sys.exit(130)


@click.group(cls=RadtreeGroup, context_settings=CONTEXT)
@click.version_option(__version__, prog_name="radtree")
@click.option("--debug", is_flag=True, help="Show full tracebacks on errors.")
@click.pass_context
def main(ctx: click.Context, debug: bool) -> None:
    """radtree — daylight through street trees onto façades and into rooms.

    \b
    Typical use, on the shipped reference study:
      radtree build examples/mendoza-street      # Radiance files + Makefile per scenario
      radtree simulate examples/mendoza-street   # → results/illuminance.csv
      radtree report examples/mendoza-street     # → report/index.html

    Conventions: metres; x east, y north, z up; azimuth clockwise from north; lux.
    """
    ctx.ensure_object(dict)
    ctx.obj["debug"] = debug


def _scenarios_option(f):
    return click.option("-s", "--scenario", "scenarios", multiple=True,
                        help="Only this scenario (repeatable). Default: all.")(f)


@main.command(context_settings=CONTEXT)
def doctor() -> None:
    """Which engines are usable, with versions. Exits non-zero only when none is."""
    from radtree.engines.radiance.binaries import find_radiance, version

    install = find_radiance()
    ok = False
    if install is not None:
        v = version()
        click.echo(f"radiance: {v or 'found but not runnable'} ({install.origin}: {install.bin_dir})")
        click.echo(f"  RAYPATH: {install.raypath}")
        ok = ok or v is not None
    else:
        click.echo("radiance: not found (pip install pyradiance, or put Radiance on PATH)")
    try:
        from radtree.engines.numpy import engine as npe

        click.echo(f"numpy: available ({npe.describe()})")
        ok = True
    except ImportError as exc:
        click.echo(f"numpy: not available ({exc})")
    if not ok:
        raise RadtreeError("no usable engine")


@main.command(context_settings=CONTEXT)
@click.argument("project", type=click.Path())
@_scenarios_option
@click.option("--no-pictures", is_flag=True, help="Skip the PNG picture of each crown model.")
def build(project: str, scenarios: tuple[str, ...], no_pictures: bool) -> None:
    """Write the Radiance build folder of PROJECT.

    \b
    PROJECT/build/<scenario>/
      materials.rad  geometry/*.rad  grids/*.pts  skies/<HHMM>.sky  Makefile  manifest.json
    Each Makefile has one target per hour and runs without Python:
      make -j2 -C PROJECT/build/A
    """
    import time

    from radtree.config import load_project
    from radtree.pipeline.build import build_project

    t = time.perf_counter()
    p = load_project(project)
    click.echo(f"building {p.name} ({len(p.scenarios)} scenarios, {len(p.site.hours)} hours)")
    build_project(p, list(scenarios) or None, echo=click.echo, pictures=not no_pictures)
    click.echo(f"build written to {p.build_dir} in {time.perf_counter() - t:.1f} s")


@main.command(context_settings=CONTEXT)
@click.argument("project", type=click.Path())
@_scenarios_option
@click.option("--engine", type=click.Choice(ENGINE_CHOICES), default="auto",
              show_default=True, help="auto = Radiance when found, else the NumPy engine.")
@click.option("--hour", "hours", multiple=True, help="Only this hour HH:MM (repeatable).")
@click.option("--workers", type=int, default=None, help="Parallel hours (default: engine.workers).")
@click.option("--dry-run", is_flag=True, help="Print the commands, run nothing.")
@click.option("--fresh", is_flag=True, help="Recompute every hour (ignore finished parts).")
@click.option("--convergence", is_flag=True,
              help="Run the façade sensors over increasing -ab/-ad and print the change per step.")
def simulate(project: str, scenarios: tuple[str, ...], engine: str, hours: tuple[str, ...],
             workers: int | None, dry_run: bool, fresh: bool, convergence: bool) -> None:
    """Trace every scenario × hour of PROJECT → PROJECT/results/illuminance.csv.

    One row per scenario × hour × grid × sensor: scenario, model, datetime, time, grid,
    sensor, row, x, y, z, lux, lux_stderr, engine, params_hash. Finished hours are kept
    (results/parts/) so an interrupted run resumes; --fresh recomputes all.
    """
    import time

    from radtree.config import load_project
    from radtree.pipeline.simulate import resolve_engine, simulate_project

    p = load_project(project)
    if convergence:
        from radtree.convergence import convergence_table
        from radtree.fileio import atomic_path

        table = convergence_table(p, list(scenarios) or None, list(hours) or None,
                                  echo=click.echo)
        click.echo(table.to_string(index=False))
        conv_path = p.results_dir / "convergence.csv"
        with atomic_path(conv_path) as tmp:
            table.to_csv(tmp, index=False)
        click.echo(f"convergence table → {conv_path}")
        return
    eng = resolve_engine(p, engine)
    click.echo(f"engine: {eng.name}" + (" (auto)" if engine == "auto" else ""))
    t = time.perf_counter()
    out = simulate_project(p, eng, list(scenarios) or None, list(hours) or None, workers,
                           dry_run=dry_run, echo=click.echo, resume=not fresh)
    if out is None:
        return
    facade = out.table[out.table["grid"] == "facade"]
    means = facade.groupby(["scenario", "time"], sort=False)["lux"].mean().unstack("time")
    click.echo("façade sensor means (lux):")
    click.echo(means.round(0).to_string())
    click.echo(f"{out.computed} hours traced, {out.reused} reused, "
               f"{time.perf_counter() - t:.1f} s → {out.path}")





def _register_commands() -> None:
    """Commands that live beside their subject (hemi, report, …)."""
    from radtree.annual.cli import annual_command
    from radtree.diagnose.cli import diagnose_command
    from radtree.hemi.cli import hemi_command
    from radtree.permeability_cli import permeability_command
    from radtree.report.cli import report_command
    from radtree.sweep.cli import sweep_command
    from radtree.trees.cli import calibrate_command

    for cmd in (hemi_command, report_command, calibrate_command, sweep_command,
                diagnose_command, annual_command, permeability_command):
        main.add_command(cmd)
    main.add_command(__import__("radtree.verify.command", fromlist=["_"]).verify_command)


_register_commands()

if __name__ == "__main__":  # pragma: no cover
    main()
