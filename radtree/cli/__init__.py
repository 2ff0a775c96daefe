"""radtree command line: thin commands over the Python API, one command per module.

    radtree build PROJECT      write Radiance build folders (PROJECT/build/<scenario>/)
    radtree simulate PROJECT   trace every scenario × hour → PROJECT/results/illuminance.csv
    radtree report PROJECT     statistics, plots, HTML → PROJECT/report/index.html

PROJECT is a folder holding radtree.toml, or the file itself. Every command runs under the
one error handler of :mod:`radtree.cli.errors` (exit codes 0 ok, 1 bug, 2 bad input,
3 engine failure, 130 interrupted, 143 terminated).
"""

from __future__ import annotations

import click

from radtree import __version__
from radtree.cli.errors import RadtreeGroup
from radtree.cli.options import CONTEXT

__all__ = ["main"]


#: command name → "module:function", imported when the command runs (or ``--help`` lists it):
#: ``radtree doctor`` need not load trimesh, scikit-image and matplotlib
COMMANDS = {
    "new": "radtree.cli.new:new_command",
    "doctor": "radtree.cli.doctor:doctor_command",
    "build": "radtree.cli.build:build_command",
    "simulate": "radtree.cli.simulate:simulate_command",
    "convergence": "radtree.cli.convergence:convergence_command",
    "hemi": "radtree.cli.hemi:hemi_command",
    "report": "radtree.cli.report:report_command",
    "calibrate": "radtree.cli.calibrate:calibrate_command",
    "sweep": "radtree.cli.sweep:sweep_command",
    "diagnose": "radtree.cli.diagnose:diagnose_command",
    "annual": "radtree.cli.annual:annual_command",
    "permeability": "radtree.cli.permeability:permeability_command",
    "verify": "radtree.cli.verify:verify_command",
    "bsdf": "radtree.cli.bsdf:bsdf_command",
    "method": "radtree.cli.method:method_command",
    "export": "radtree.cli.export:export_command",
    "cache": "radtree.cli.cache:cache_command",
    "lidar": "radtree.cli.lidar:lidar_command",
}


class LazyGroup(RadtreeGroup):
    """The main group with its commands imported on first use (:data:`COMMANDS`)."""

    def list_commands(self, ctx: click.Context) -> list[str]:
        return sorted(set(self.commands) | set(COMMANDS))

    def get_command(self, ctx: click.Context, name: str) -> click.Command | None:
        if name not in self.commands and name in COMMANDS:
            import importlib

            module, attr = COMMANDS[name].split(":")
            self.add_command(getattr(importlib.import_module(module), attr), name)
        return super().get_command(ctx, name)


@click.group(cls=LazyGroup, context_settings=CONTEXT)
@click.version_option(__version__, prog_name="radtree")
@click.option("--debug", is_flag=True, help="Show full tracebacks on errors.")
@click.option("-v", "--verbose", is_flag=True, help="Also print detail messages (DEBUG).")
@click.option("-q", "--quiet", is_flag=True,
              help="Print only warnings and the results; no progress bars.")
@click.pass_context
def main(ctx: click.Context, debug: bool, verbose: bool, quiet: bool) -> None:
    """radtree — daylight through street trees onto façades and into rooms.

    \b
    Typical use, on the shipped reference study:
      radtree build examples/mendoza-street      # Radiance files + Makefile per scenario
      radtree simulate examples/mendoza-street   # → results/illuminance.csv
      radtree report examples/mendoza-street     # → report/index.html

    \b
    Exit codes: 0 ok, 1 a bug (rerun with --debug), 2 bad input,
    3 engine failure, 130 interrupted, 143 terminated.

    Conventions: metres; x east, y north, z up; azimuth clockwise from north; lux.
    """
    ctx.ensure_object(dict)
    ctx.obj["debug"] = debug
    _talk(ctx, verbose=verbose, quiet=quiet)


def _talk(ctx: click.Context, *, verbose: bool, quiet: bool) -> None:
    """Install radtree's message handler and progress bars for this command
    (:mod:`radtree.log`); the library alone stays quiet once the command ends."""
    import logging

    from radtree import log

    level = logging.DEBUG if verbose else logging.WARNING if quiet else logging.INFO
    log.enable(level, progress=not quiet)
    ctx.call_on_close(log.disable)
