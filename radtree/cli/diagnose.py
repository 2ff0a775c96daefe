"""``radtree diagnose``: name the missing physical effect, add it, re-simulate (reference case §6).

    radtree diagnose run PROJECT [--measured FILE.csv] [-s B] [--engine numpy] [--units lux]
    radtree diagnose run PROJECT --campaign FILE       # against a campaign's readings
    radtree diagnose selftest PROJECT [--effects a,b,c] [--noise 0.03] [--campaign FILE]
    radtree diagnose next PROJECT [--campaign FILE] [--candidates FILE]
    radtree diagnose list-effects [PROJECT [-s B]]

The old one-command form is an alias of these, with a one-line deprecation note:
``radtree diagnose PROJECT`` is ``run``, ``--selftest`` is ``selftest``,
``--next-measurement`` is ``next`` and ``--list-effects`` is ``list-effects`` (the flag is
taken out, everything else is passed on to the subcommand, which refuses the options it does
not have; a project folder named like a subcommand, e.g. ``next``, is written ``./next``).
Expected failures raise :class:`radtree.errors.RadtreeError` (the one handler of
:mod:`radtree.cli.errors` prints one line and exits 2, or 3 for an engine failure); the
self-test exits 1 when a distinguishable hidden effect was misnamed.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Any

import click

from radtree.cli.errors import CHECK_FAILED
from radtree.cli.options import CONTEXT, writes
from radtree.diagnose.registry import EFFECT_REGISTRY
from radtree.engines.registry import ENGINES

log = logging.getLogger(__name__)

#: the old mode flags of ``radtree diagnose PROJECT`` → the subcommand each stands for
LEGACY_FLAGS = {"--selftest": "selftest", "--next-measurement": "next",
                "--list-effects": "list-effects"}


class _Modes(click.Group):
    """The ``diagnose`` group: arguments that do not start with a subcommand's name are the
    old one-command form, rewritten to the subcommand its mode flag names (default ``run``)."""

    def parse_args(self, ctx: click.Context, args: list[str]) -> list[str]:
        if args and args[0] not in self.commands and args[0] not in ctx.help_option_names:
            args = legacy_args(args)
        return super().parse_args(ctx, args)


def legacy_args(args: list[str]) -> list[str]:
    """The subcommand form of old-style ``diagnose`` arguments, with a deprecation note."""
    flag = next((a for a in args if a in LEGACY_FLAGS), None)
    name = LEGACY_FLAGS[flag] if flag is not None else "run"
    rest = [a for a in args if a != flag]
    log.warning("`radtree diagnose %s` is deprecated: use `radtree diagnose %s ...`",
                flag or "PROJECT", name)
    return [name, *rest]


Decorator = Callable[[Callable[..., Any]], Callable[..., Any]]


def _stack(*decorators: Decorator) -> Decorator:
    def apply(f: Callable[..., Any]) -> Callable[..., Any]:
        for d in reversed(decorators):
            f = d(f)
        return f

    return apply


_common = _stack(
    click.argument("project", type=click.Path(exists=True)),
    click.option("-s", "--scenario", help="Scenario to start from. Default: the project's first."),
    click.option("--engine", type=click.Choice(list(ENGINES)), default=None,
                 help="Engine for the diagnosis runs. Default: numpy (seeded: one seed gives "
                      "every switched run the same random numbers, so signatures carry little "
                      "noise)."),
    click.option("--rays", type=click.IntRange(min=1),
                 help="NumPy engine rays per sensor (default 1024)."),
    click.option("--seed", type=int, help="Seed of every run (default: the project's "
                                          "engine.seed)."),
    click.option("--effects", help="Comma-separated effect names (default: the whole "
                                   "catalogue): " + ", ".join(EFFECT_REGISTRY) + "."),
    click.option("--campaign", type=click.Path(dir_okay=False, exists=True),
                 help="Measurement campaign TOML (days, hours, sensor groups, noise). Default: "
                      "the project's façade grid mean at its hours."),
    click.option("--out", type=click.Path(file_okay=False),
                 help="Output folder. Default: PROJECT/diagnose."),
)

_loop = _stack(
    click.option("--margin", type=click.FloatRange(0, 1, max_open=True), default=0.05,
                 show_default=True, help="Relative CV-RMSE improvement a step must bring."),
    click.option("--max-steps", type=click.IntRange(min=1), default=4, show_default=True),
    click.option("--workers", type=click.IntRange(min=1), default=None,
                 help="Processes tracing ahead (each step's candidate signatures; in the "
                      "self-test also the hidden effects' diagnoses); the same numbers as 1 "
                      "[default: the usable cores, at most 4]."),
)


def _options(project: str, **given: Any) -> Any:
    """The :class:`~radtree.diagnose.options.DiagnoseOptions` of a subcommand's options."""
    from pathlib import Path

    from radtree.diagnose.effects import parse_effects
    from radtree.diagnose.options import DiagnoseOptions

    campaign = given.pop("campaign", None)
    if campaign is not None:
        from radtree.config import load_project
        from radtree.diagnose.campaign import load_campaign

        campaign = load_campaign(campaign, load_project(project))
    out = given.pop("out", None)
    effects = given.pop("effects", None)
    return DiagnoseOptions(**given, campaign=campaign, out_dir=Path(out) if out else None,
                           effects=parse_effects(effects) if effects is not None else None)


@click.group("diagnose", cls=_Modes, context_settings=CONTEXT)
def diagnose_command() -> None:
    """Find where simulation and measurement disagree, name the missing effect, add it.

    \b
    run:          the diagnosis → PROJECT/diagnose/ steps.csv, residuals.csv, candidates.csv,
                  index.html (+ PNG), radtree.step<k>.toml (your project file is unchanged)
    selftest:     hide each effect in synthetic measurements, check it is named
                  → selftest.csv, selftest.html
    next:         rank what to measure next → next_measurement.csv, campaign-next.toml
    list-effects: the effect catalogue
    The old form `radtree diagnose PROJECT [--selftest | --next-measurement | --list-effects]`
    still works (deprecated).
    """


@diagnose_command.command("run", context_settings=CONTEXT)
@writes("diagnose", out_param="out")
@_common
@click.option("--measured", type=click.Path(dir_okay=False),
              help="Measured CSV (time,measured_lux | time,row,lux | time,sensor,lux). "
                   "Default: the project's [project] measured.")
@click.option("--units", type=click.Choice(["lux", "klux"]),
              help="Units of the measured file when it does not state them ('# Units: lux').")
@_loop
def run_command(*, project: str, measured: str | None, units: str | None, **given: Any) -> None:
    """Diagnose PROJECT against its measurements (or a campaign's readings)."""
    from radtree.diagnose.run import diagnose, format_steps

    res = diagnose(project, measured=measured, units=units, options=_options(project, **given))
    for line in format_steps(res.loop):
        click.echo(line)
    click.echo(f"done in {res.seconds:.0f} s ({res.simulations} simulations): {res.out_dir}")


@diagnose_command.command("selftest", context_settings=CONTEXT)
@writes("diagnose", out_param="out")
@_common
@click.option("--noise", type=click.FloatRange(0, 1, max_open=True), default=None,
              help="Relative noise on each synthetic value [default: the campaign's, else "
                   "0.03].")
@_loop
def selftest_command(*, project: str, noise: float | None, **given: Any) -> None:
    """Hide each effect (--effects: the ones to hide) in synthetic measurements of PROJECT and
    check the diagnosis names it; exit 1 when a distinguishable one is misnamed."""
    from radtree.diagnose.hidden import selftest

    res = selftest(project, noise=noise, options=_options(project, **given))
    table = res.table()
    click.echo("")
    cols = ["hidden_effect", "distinguishable", "named_effect", "rmse_before", "rmse_after",
            "gap_shrinks"]
    click.echo(table[[c for c in cols if c in table.columns]].to_string(
        index=False, float_format="%.3f"))
    n_dist = sum(c.distinguishable for c in res.cases)
    if res.passed:
        click.echo(f"self-test passed: {n_dist} distinguishable hidden effect(s), all named "
                   f"correctly ({res.seconds:.0f} s)")
        return
    click.secho("self-test FAILED: misnamed distinguishable effect(s): "
                + ", ".join(f"{c.effect} → {c.named}" for c in res.misnamed), fg="red",
                err=True)
    raise SystemExit(CHECK_FAILED)


@diagnose_command.command("next", context_settings=CONTEXT)
@writes("diagnose", out_param="out")
@_common
@click.option("--candidates", type=click.Path(dir_okay=False, exists=True),
              help="A campaign TOML whose groups/hours/days are the candidates (default: "
                   "generated).")
def next_command(*, project: str, candidates: str | None, **given: Any) -> None:
    """Rank candidate additions to the campaign (--campaign, default the project's own
    measurement) by how well they separate the confounded effects."""
    from radtree.diagnose.design import next_measurement

    design = next_measurement(project, candidates_file=candidates,
                              options=_options(project, **given))
    for line in design.lines():
        click.echo(line)


@diagnose_command.command("list-effects", context_settings=CONTEXT)
@click.argument("project", required=False, type=click.Path(exists=True))
@click.option("-s", "--scenario", help="With PROJECT: the scenario whose state is shown "
                                       "(default: the project's first).")
def list_effects_command(*, project: str | None, scenario: str | None) -> None:
    """Print the effect catalogue (with PROJECT: which effects are on, off or not applicable)."""
    from radtree.diagnose.effects import EffectContext, catalogue_lines

    ctx, sc = None, None
    if project is not None:
        from radtree.config import load_project

        proj = load_project(project)
        ctx = EffectContext(proj)
        sc = proj.scenario(scenario) if scenario else proj.scenarios[0]
    for line in catalogue_lines(ctx, sc):
        click.echo(line)
