"""``radtree annual PROJECT``: climate-based daylight over a year, with and without the tree."""

from __future__ import annotations

from pathlib import Path

import click

from radtree.annual.run import DEFAULT_SUN_MF
from radtree.annual.schedule import leaf_season, parse_occupancy
from radtree.cli.options import CONTEXT, writes


@click.command("annual", context_settings=CONTEXT)
@writes("results")
@click.argument("project", type=click.Path(exists=True, path_type=Path))
@click.option("--leaf-on", metavar="MM-DD",
              help="First day the crown is in leaf. Default: [tree] leaf_on, else the "
                   "species' phenology in the site's hemisphere (between the tropics the "
                   "species must be evergreen or the dates given).")
@click.option("--leaf-off", metavar="MM-DD",
              help="First day the crown is bare (branches only); with --leaf-on.")
@click.option("--mf", default=1, show_default=True, type=click.IntRange(1, 8),
              help="Reinhart sky subdivision (1 = 145 patches + ground).")
@click.option("--sun-mf", default=DEFAULT_SUN_MF, show_default=True, type=click.IntRange(1, 8),
              help="Reinhart subdivision of the unit suns for reflected sunlight. Behind a "
                   "louvers crown at low sun its interpolation reads −7 … +11 % of the exact "
                   "sun's at 1, −6 … +3 % at 2, −3 … +3 % at 4. Its unit suns (office "
                   "year: 80 at 1, 266 at 2, 679 at 4) set the reflected-sun run's time: "
                   "behind the office's crowns 2 takes 3.8 × as long as 1, the whole office "
                   "annual ≈ 2.3 h instead of 37 min with -j 1.")
@click.option("--occupancy", default="8-18", show_default=True, metavar="START-END",
              help="Occupied hours, local standard time, every day.")
@click.option("--epw", type=click.Path(exists=True, dir_okay=False, path_type=Path),
              help="Weather file (default: [light] epw, else a generated clear-sky year).")
@click.option("--with", "with_scenario", metavar="SCENARIO",
              help="Scenario with the leafed tree (default: the project's louvers scenario).")
@click.option("--without", "without_scenario", metavar="SCENARIO",
              help="Scenario without tree (default: the project's model 'none' scenario).")
@click.option("--ab", type=click.IntRange(0, 20), help="Ambient bounces (default: project).")
@click.option("--ad", type=click.IntRange(1, 1_000_000), help="Ambient divisions.")
@click.option("--lw", type=float, help="Ray weight limit.")
@click.option("--sun-ad", type=click.IntRange(1, 1_000_000),
              help="Ambient divisions of the reflected-sun run (default: --ad ÷ 4, at least "
                   "128). Its Monte Carlo noise sets how far work-plane UDI moves between two "
                   "runs (office, leaf-on, defaults: UDI <100 by 3.5 pp; --sun-lw 1e-4 cuts "
                   "the noise 1.6× for 5× the time).")
@click.option("--sun-lw", type=float,
              help="Ray weight limit of the reflected-sun run (default: --lw, at least 1e-3).")
@click.option("-j", "--processes", default=2, show_default=True, type=click.IntRange(1, 64),
              help="rcontrib processes.")
@click.option("--replicates", type=click.IntRange(1, 64),
              help="Trace every Monte Carlo run R times with independent samples (R × the "
                   "time): the result is their mean (as precise as about R × --ad) and the "
                   "metrics' Monte Carlo standard errors are printed and written to "
                   "results/annual/uncertainty.csv. Default: 4 (dc), 1 (3phase); 1 halves "
                   "the time and reports no errors.")
@click.option("--no-figures", is_flag=True, help="Skip the PNG figures.")
@click.option("--dates", "use_dates", is_flag=True,
              help="With [tree] species: use the --leaf-on/--leaf-off switch instead of the "
                   "species' hourly phenology (leaf area ramps).")
@click.option("--method", type=click.Choice(["dc", "3phase"]), default="dc", show_default=True,
              help="dc: daylight coefficients of the explicit crown; 3phase: view matrix · "
                   "crown BSDF (leaf-on/off) · daylight matrix · sky (rfluxmtx, dctimestep).")
@click.option("--sun-crown", type=click.Choice(["explicit", "bsdf", "fivephase"]),
              default="explicit", show_default=True,
              help="3phase: the hourly sun traced through the explicit crown (its gaps and "
                   "slats, as the dc method does), through the BSDF crown, or by the "
                   "five-phase idea (the sun reflected by the surroundings through the BSDF "
                   "crown, the sun through the crown itself from its explicit geometry). "
                   "Measured against the explicit-crown annual (benchmarks/threephase.py): "
                   "explicit within 0.5 pp on every UDI band; bsdf up to 14 pp and fivephase "
                   "up to 15 pp off (noise of the crown BSDF's straight-through patch).")
@click.option("--sunlight-date", default="03-21", show_default=True, metavar="MM-DD",
              help="EN 17037 exposure to sunlight: the date (1 February – 21 March).")
def annual_command(*, project: Path, leaf_on: str | None, leaf_off: str | None, mf: int,
                   sun_mf: int, occupancy: str, epw: Path | None, with_scenario: str | None,
                   without_scenario: str | None, ab: int | None, ad: int | None,
                   lw: float | None, processes: int, no_figures: bool,
                   sun_ad: int | None = None, sun_lw: float | None = None,
                   use_dates: bool = False, method: str = "dc", replicates: int | None = None,
                   sun_crown: str = "explicit", sunlight_date: str = "03-21") -> None:
    """Annual daylight (8760 h) with a deciduous tree: UDI, DA, sDA, ASE, monthly means.

    The crown is in leaf from --leaf-on to --leaf-off; with ``[tree] species`` each hour
    instead weighs the leafed and the bare crown by the species' leaf area (leaf-out and
    leaf-fall ramps; --dates keeps the switch).

    Writes PROJECT/results/annual.csv, annual_summary.csv, annual_monthly.csv and
    results/annual/ (hourly arrays, coefficients, figures, standards.csv: EN 17037 daylight
    provision and exposure to sunlight, LEED v4.1 sDA/ASE, with and without trees).
    """
    from radtree.annual.methods import run as run_annual
    from radtree.annual.run import AnnualOptions
    from radtree.config import load_project

    proj = load_project(project)
    options = AnnualOptions(
        leaf=leaf_season(proj, leaf_on, leaf_off), mf=mf, sun_mf=sun_mf,
        occupancy=parse_occupancy(occupancy), ab=ab, ad=ad, lw=lw, sun_ad=sun_ad,
        sun_lw=sun_lw, nproc=processes, replicates=replicates,
        with_scenario=with_scenario, without_scenario=without_scenario, epw=epw,
        species_phenology=not use_dates, method=method, sun_crown=sun_crown,
        sunlight_date=sunlight_date)
    click.echo(f"annual: {proj.name}; leaf season {options.season.describe()}")
    out = run_annual(proj, options=options, figures=not no_figures)
    from radtree.annual.report import grid_summary

    for row in grid_summary(proj).itertuples(index=False):
        click.echo(f"  {row.grid:>10} {row.tree:>7} tree: sDA300/50% {row.sda_300_50:5.1f} %, "
                   f"ASE1000,250 {row.ase_1000_250:5.1f} %, UDI <100 {row.udi_below_100:5.1f} "
                   f"/ 100–300 {row.udi_100_300:5.1f} / 300–3000 {row.udi_300_3000:5.1f} / "
                   f">3000 {row.udi_above_3000:5.1f} %")
    spread = out.result.uncertainty
    if spread is not None:
        click.echo(f"  Monte Carlo standard errors ({out.result.trace.replicates} replicates):")
        shown = spread[spread.tree.isin(["with", "without"])]
        for (grid, tree), rows in shown.groupby(["grid", "tree"], sort=False):
            se = dict(zip(rows.metric, rows.se))
            click.echo(f"  {grid:>10} {tree:>7} tree: sDA ± {se['sDA']:.1f}, DA ± "
                       f"{se['DA300']:.1f}, UDI <100 ± {se['UDI<100']:.1f}, 100–3000 ± "
                       f"{se['UDI100-3000']:.1f}, >3000 ± {se['UDI>3000']:.1f} pp")
    if out.result.weather.generated:
        click.secho("  weather: GENERATED clear-sky year (not measured): "
                    f"{out.result.weather.path}", fg="yellow")
    click.echo(f"→ {out.annual_csv}\n→ {out.summary_csv}\n→ {out.monthly_csv}\n"
               f"→ {out.annual_csv.parent / 'annual' / 'standards.csv'}")
    for f in out.figures:
        click.echo(f"→ {f}")
