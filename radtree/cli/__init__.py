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
from radtree.cli.annual import annual_command
from radtree.cli.build import build_command
from radtree.cli.calibrate import calibrate_command
from radtree.cli.diagnose import diagnose_command
from radtree.cli.doctor import doctor_command
from radtree.cli.errors import RadtreeGroup
from radtree.cli.hemi import hemi_command
from radtree.cli.new import new_command
from radtree.cli.options import CONTEXT
from radtree.cli.permeability import permeability_command
from radtree.cli.report import report_command
from radtree.cli.simulate import simulate_command
from radtree.cli.sweep import sweep_command
from radtree.cli.verify import verify_command

__all__ = ["main"]


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

    \b
    Exit codes: 0 ok, 1 a bug (rerun with --debug), 2 bad input,
    3 engine failure, 130 interrupted, 143 terminated.

    Conventions: metres; x east, y north, z up; azimuth clockwise from north; lux.
    """
    ctx.ensure_object(dict)
    ctx.obj["debug"] = debug


main.add_command(new_command)   # radtree new (cli/new.py), apart from the tuple other branches extend
for _command in (doctor_command, build_command, simulate_command, hemi_command, report_command,
                 calibrate_command, sweep_command, diagnose_command, annual_command,
                 permeability_command, verify_command):
    main.add_command(_command)
