"""``radtree diagnose``: name the missing physical effect, add it, re-simulate (reference case §6).

    radtree diagnose PROJECT [--measured FILE.csv] [--scenario B] [--engine numpy] [--units lux]
    radtree diagnose PROJECT --campaign FILE          # against a campaign's readings
    radtree diagnose PROJECT --selftest [--effects a,b,c] [--noise 0.03] [--campaign FILE]
    radtree diagnose PROJECT --next-measurement [--campaign FILE] [--candidates FILE]
    radtree diagnose --list-effects [PROJECT [--scenario B]]

Expected failures raise :class:`radtree.errors.RadtreeError` (the one handler of
:mod:`radtree.cli.errors` prints one line and exits 2, or 3 for an engine failure); the
self-test exits 1 when a distinguishable hidden effect was misnamed.
"""

from __future__ import annotations

import click

from radtree.cli.errors import CHECK_FAILED
from radtree.cli.options import CONTEXT, writes
from radtree.engines.registry import ENGINES


@click.command("diagnose", context_settings=CONTEXT)
@writes("diagnose", out_param="out")
@click.argument("project", required=False, type=click.Path(exists=True))
@click.option("--measured", type=click.Path(dir_okay=False),
              help="Measured CSV (time,measured_lux | time,row,lux | time,sensor,lux). "
                   "Default: the project's [project] measured.")
@click.option("--units", type=click.Choice(["lux", "klux"]),
              help="Units of the measured file when it does not state them ('# Units: lux').")
@click.option("-s", "--scenario", help="Scenario to start from. Default: the project's first.")
@click.option("--engine", type=click.Choice(list(ENGINES)), default=None,
              help="Engine for the diagnosis runs. Default: numpy (seeded: one seed gives "
                   "every switched run the same random numbers, so signatures carry little noise).")
@click.option("--rays", type=click.IntRange(min=1),
              help="NumPy engine rays per sensor (default 1024).")
@click.option("--seed", type=int, help="Seed of every run (default: the project's engine.seed).")
@click.option("--margin", type=click.FloatRange(0, 1, max_open=True), default=0.05,
              show_default=True, help="Relative CV-RMSE improvement a step must bring.")
@click.option("--max-steps", type=click.IntRange(min=1), default=4, show_default=True)
@click.option("--effects", help="Comma-separated effect names: with --selftest the effects to "
                                "hide; otherwise the candidates (default: the whole catalogue).")
@click.option("--selftest", is_flag=True,
              help="Hide each effect in synthetic measurements and check it is named.")
@click.option("--noise", type=click.FloatRange(0, 1, max_open=True), default=None,
              help="Self-test: relative noise on each synthetic value [default: the "
                   "campaign's, else 0.03].")
@click.option("--campaign", type=click.Path(dir_okay=False, exists=True),
              help="Measurement campaign TOML (days, hours, sensor groups, noise): the "
                   "self-test measures what it measures; --next-measurement starts from it. "
                   "Default: the project's façade grid mean at its hours.")
@click.option("--next-measurement", "next_measurement", is_flag=True,
              help="Rank candidate additions to the campaign by how well they separate the "
                   "confounded effects → diagnose/next_measurement.csv.")
@click.option("--candidates", type=click.Path(dir_okay=False, exists=True),
              help="With --next-measurement: a campaign TOML whose groups/hours/days are the "
                   "candidates (default: generated).")
@click.option("--workers", type=click.IntRange(min=1), default=None,
              help="Processes tracing ahead: each step's candidate signatures (and, with "
                   "--selftest, the hidden effects' diagnoses); the same numbers as 1 "
                   "[default: the usable cores, at most 4].")
@click.option("--out", type=click.Path(file_okay=False),
              help="Output folder. Default: PROJECT/diagnose.")
@click.option("--list-effects", is_flag=True, help="Print the effect catalogue and exit.")
def diagnose_command(project: str | None, measured: str | None, units: str | None,
                     scenario: str | None, engine: str | None, rays: int | None, seed: int | None,
                     margin: float, max_steps: int, effects: str | None, selftest: bool,
                     noise: float | None, campaign: str | None, next_measurement: bool,
                     candidates: str | None, out: str | None, list_effects: bool,
                     workers: int | None = None) -> None:
    """Find where simulation and measurement disagree, name the missing effect, add it.

    \b
    Writes PROJECT/diagnose/: steps.csv, residuals.csv, candidates.csv, index.html (+ PNG),
    radtree.step<k>.toml (the user's project file is never changed). With --selftest:
    selftest.csv and selftest.html.
    """
    from radtree.diagnose.effects import EffectContext, catalogue_lines, parse_effects
    from radtree.errors import ConfigError

    if list_effects:
        ctx, sc = None, None
        if project is not None:
            from radtree.config import load_project

            proj = load_project(project)
            ctx = EffectContext(proj)
            sc = proj.scenario(scenario) if scenario else proj.scenarios[0]
        for line in catalogue_lines(ctx, sc):
            click.echo(line)
        return
    if project is None:
        raise click.UsageError("PROJECT is required (except with --list-effects)")
    chosen = parse_effects(effects)
    camp = None
    if campaign is not None:
        from radtree.config import load_project
        from radtree.diagnose.campaign import load_campaign

        camp = load_campaign(campaign, load_project(project))
    if candidates is not None and not next_measurement:
        raise ConfigError("--candidates goes with --next-measurement")
    if next_measurement:
        if selftest or measured is not None:
            raise ConfigError("--next-measurement goes without --selftest and --measured")
        from radtree.diagnose.design import next_measurement as run_design

        design = run_design(project, scenario, camp, candidates, engine, rays, seed, chosen,
                            out, echo=click.echo)
        for line in design.lines():
            click.echo(line)
        return
    if selftest:
        if measured is not None:
            raise ConfigError("--measured does not go with --selftest (the self-test makes "
                               "its own synthetic measurements)")
        from radtree.diagnose.hidden import selftest as run_selftest

        res = run_selftest(project, scenario, chosen, noise, engine, rays, seed, margin,
                           max_steps, out, echo=click.echo, campaign=camp,
                           workers=workers)
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
    from radtree.diagnose.run import diagnose, format_steps

    res_d = diagnose(project, measured, units, scenario, engine, rays, seed, margin, max_steps,
                     chosen, out, echo=click.echo, campaign=camp, workers=workers)
    for line in format_steps(res_d.loop):
        click.echo(line)
    click.echo(f"done in {res_d.seconds:.0f} s ({res_d.simulations} simulations): "
               f"{res_d.out_dir}")
