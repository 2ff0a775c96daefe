"""``radtree hemi render`` / ``radtree hemi check``: a crown model's synthetic fisheye from its
photo point, and the crown against its photo (``results/photo_check.csv``). ``radtree hemi
IMAGE`` (no sub-command) still analyses photos (:mod:`radtree.cli.hemi`)."""

from __future__ import annotations

from pathlib import Path

import click

from radtree.cli.options import CONTEXT, scenarios_option


class HemiGroup(click.Group):
    """``radtree hemi``: the sub-commands ``render`` and ``check``, else the photo analysis
    (``radtree hemi IMAGE_OR_FOLDER [OPTIONS]``)."""

    default_command = "analyse"

    def parse_args(self, ctx: click.Context, args: list[str]) -> list[str]:
        if args and args[0] not in self.commands and args[0] not in ("-h", "--help"):
            args = [self.default_command, *args]
        return super().parse_args(ctx, args)


def _photo_scenarios(project, names: tuple[str, ...]) -> list:
    from radtree.errors import ConfigError
    from radtree.trees.build import apply_switches

    chosen = [project.scenario(n) for n in names] if names else [
        sc for sc in project.scenarios
        if (t := apply_switches(project.tree, dict(sc.switches))[0]).photo is not None
        or t.perforated.photo is not None]
    if not chosen:
        raise ConfigError("no scenario has a photo ([tree] photo or the switch \"tree.photo\")",
                          source=str(project.source), field="tree.photo")
    return chosen


@click.command("render", context_settings=CONTEXT)
@click.argument("project", type=click.Path())
@scenarios_option
@click.option("--size", type=int, default=1000, show_default=True,
              help="Image side in pixels (the 90° circle fills the frame).")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path),
              default=None, help="Output folder (default PROJECT/results/photo_render).")
@click.option("--radiance", "radiance_hour", metavar="HH:MM", default=None,
              help="Also a Radiance rpict -vta fisheye (180°, equidistant) with that hour's "
                   "sun and sky: <scenario>_<HHMM>.hdr and .bmp.")
@click.option("--radiance-size", type=int, default=512, show_default=True,
              help="Side of the Radiance picture, pixels.")
@click.option("--radiance-ab", type=int, default=None,
              help="Ambient bounces of the picture (default: the crown model's -ab).")
def render_command(project: str, scenarios: tuple[str, ...], size: int,
                   out_dir: Path | None, radiance_hour: str | None, radiance_size: int,
                   radiance_ab: int | None) -> None:
    """Render each scenario's crown as a binary sky/canopy fisheye (255 sky, 0 canopy) from
    its photo point through its photo's lens, by ray casting; write <scenario>.png and the
    radtree hemi analysis of it (summary.csv, rings.csv) into --out."""
    from radtree.config import load_project
    from radtree.hemi.batch import run_batch
    from radtree.hemi.synthetic import save_png
    from radtree.photo.render import render_scenario

    p = load_project(project)
    out = out_dir or p.results_dir / "photo_render"
    out.mkdir(parents=True, exist_ok=True)
    for sc in _photo_scenarios(p, scenarios):
        r = render_scenario(p, sc, size)
        path = save_png(r.image, out / f"{sc.name}.png")
        res = r.analyse()
        run_batch(path, out / sc.name, res.config, overlay=False)
        m = res.metrics
        click.echo(f"{sc.name}: {path} ({size}×{size} px, {r.source.lens} lens, "
                   f"{r.source.direction} photo point {r.camera.round(2).tolist()} m); "
                   f"cast {r.seconds['cast']:.2f} s; openness {m.openness:.4f}  "
                   f"lai_eff {m.lai_eff:.3f}")
        if radiance_hour:
            from radtree.photo.render import radiance_picture

            hdr, bmp = radiance_picture(p, sc, radiance_hour, radiance_size,
                                        out / f"{sc.name}_{radiance_hour.replace(':', '')}",
                                        ab=radiance_ab)
            click.echo(f"{sc.name}: Radiance fisheye {hdr} and {bmp}")


@click.command("check", context_settings=CONTEXT)
@click.argument("project", type=click.Path())
@scenarios_option
@click.option("--size", type=int, default=1000, show_default=True,
              help="Rendering side in pixels.")
def check_command(project: str, scenarios: tuple[str, ...], size: int) -> None:
    """Each scenario's crown against its photo → PROJECT/results/photo_check.csv (scenario,
    ring, segment, zenith_min_deg, zenith_max_deg, gap_fraction_photo, gap_fraction_model:
    one row per ring × segment of the photo analysis), photo_check_metrics.csv and the two
    fisheyes in results/photo_check/; prints the RMS differences."""
    from radtree.config import load_project
    from radtree.photo.check import check_scenario, write_check

    p = load_project(project)
    outcomes = []
    for sc in _photo_scenarios(p, scenarios):
        o = check_scenario(p, sc, size)
        outcomes.append(o)
        ph = o.photos[0].metrics
        click.echo(f"{sc.name}: gap-fraction RMS {o.rms:.4f} (ring × segment), "
                   f"{o.ring_rms:.4f} (per ring); LAI_eff photo {ph.lai_eff:.3f} model "
                   f"{o.model.metrics.lai_eff:.3f}; openness photo {ph.openness:.4f} model "
                   f"{o.model.metrics.openness:.4f}")
    write_check(p, outcomes)
    click.echo(f"wrote {p.results_dir / 'photo_check.csv'}")
