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

#: command name → the first sentence of its help: what `radtree --help` lists, without
#: importing every command (tests/test_cli_help.py checks them against the commands)
SUMMARIES = {
    "new": ("Write FOLDER/radtree.toml — every field with its unit and default — and copy the "
            "inputs into FOLDER/data/."),
    "doctor": "Which engines are usable, with versions.",
    "build": "Write the Radiance build folder of PROJECT.",
    "simulate": "Trace every scenario × hour of PROJECT → PROJECT/results/illuminance.csv.",
    "convergence": ("Trace the façade sensors of PROJECT over increasing -ab (1, 2, 3, 4, 6, 8 "
                    "and the crown model's own) and print the façade mean and its change per "
                    "step."),
    "hemi": "Analyse a fisheye photo, or every JPEG/PNG/TIFF in a folder.",
    "report": "Statistics, plots and an HTML report of PROJECT → PROJECT/report/index.html.",
    "calibrate": ("Calibrate the crown of PROJECT (a folder with radtree.toml, or the file) to a"
                  " target permeability by tracing straight rays from the façade sensors through"
                  " the built crown."),
    "sweep": "Run PROJECT once per combination of unknown parameters and rank their effect.",
    "diagnose": ("Find where simulation and measurement disagree, name the missing effect, add "
                 "it."),
    "annual": ("Annual daylight (8760 h) with a deciduous tree: UDI, DA, sDA, ASE, monthly "
               "means."),
    "permeability": ("How a scenario's fit depends on the crown's global permeability (measured:"
                     " 5–6 %)."),
    "verify": ("Physics checks: uncollided transmission through random leaf layers against "
               "exp(−G·LAI/cos θ) and under floating spheres against its numerical integral, "
               "energy conservation, turbid, voxel and mist crowns, forward vs backward engines "
               "on the reduced Mendoza louvers dome and a free volume crown; then every output "
               "path beyond the engines: annual, Honeybee and EnergyPlus exports, glTF, the "
               "photo round trip, the diagnose self-test."),
    "bsdf": "Compute the BSDF of a scenario's crown layer, leaf-on and leaf-off.",
    "method": ("What the study's numbers owe to its method: scenarios A–E traced as the project "
               "sets them (the study's TracePro method in examples/mendoza-tracepro), with the "
               "threshold, the beam and the crown form changed one at a time, and at every dome "
               "radius of RADII."),
    "export": "Write PROJECT's crowns or scene for other tools into DIR.",
    "cache": "Show the build cache: crowns and their OBJ mesh text kept between builds.",
    "lidar": "Trees from airborne laser scanning (ALS) tiles, one tree's points from a tile.",
}


class LazyGroup(RadtreeGroup):
    """The main group with its commands imported on first use (:data:`COMMANDS`); its
    ``--help`` lists them from :data:`SUMMARIES`, importing none."""

    def list_commands(self, ctx: click.Context) -> list[str]:
        return sorted(set(self.commands) | set(COMMANDS))

    def format_commands(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        """The "Commands" section, as click writes it (its short-help rule, the width)."""
        from click.utils import make_default_short_help

        names = self.list_commands(ctx)
        if not names:
            return
        limit = formatter.width - 6 - max(len(n) for n in names)
        rows = []
        for name in names:
            if name in SUMMARIES:
                rows.append((name, make_default_short_help(SUMMARIES[name], limit)))
            elif (cmd := self.get_command(ctx, name)) is not None and not cmd.hidden:
                rows.append((name, cmd.get_short_help_str(limit)))   # added outside COMMANDS
        with formatter.section("Commands"):
            formatter.write_dl(rows)

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
