"""``radtree hemi``: analyse hemispherical (fisheye) photos from the command line."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import click

from radtree.cli.errors import BAD_INPUT
from radtree.cli.hemi_photo import HemiGroup, check_command, render_command
from radtree.cli.options import CONTEXT
from radtree.errors import ConfigError
from radtree.hemi.analyse import HemiConfig
from radtree.hemi.batch import run_batch
from radtree.hemi.classify import ThresholdSpec
from radtree.hemi.image import CHANNELS
from radtree.hemi.lens import Projection, get_lens, parse_polynomial
from radtree.hemi.mask import CAMERA_PRESETS, parse_mask
from radtree.hemi.metrics import DEFAULT_GAP_FLOOR, RingGrid

HELP = f"""Analyse a fisheye photo, or every JPEG/PNG/TIFF in a folder.

\b
Writes into --out (default ./hemi-out):
  summary.csv              one row per image
  rings.csv                gap fraction per zenith ring x azimuth segment (numbered from 1)
  <image>_gaps.geojson     sky-gap outlines, coordinates [azimuth_deg, zenith_deg]
  gaps.geojson             all images' gaps (each feature names its image)
  <image>_overlay.png      classified sky, mask, rings, segments, gap outlines

\b
Conventions: angles in degrees; azimuth clockwise from north; pixel x right, y down,
from the image's top-left corner. Upward photos are mirrored (east appears left of
north); --north DEG says where true north lies in the image, clockwise from image-up.
--axis horizontal: photos taken from a facade looking out; "zenith" is then the angle
from the lens axis and "azimuth" the angle around it, clockwise from up as seen looking
out (no mirror, --north = where world-up lies in the image).

\b
Metrics (T_ij: sky share of the solid angle of ring i, segment j; T_i their mean):
  gap_fraction  share of sky pixels in the analysed zenith range (image plane)
  openness      sum(Omega_ij T_ij) / sum(Omega_ij): sky share of the analysed solid angle
  svf           sky view factor: integral(gap cos(z) sin(z)) / integral(cos(z) sin(z)) over
                the analysed range, pixel by pixel (0-90 deg: horizontal surface, uniform sky)
  difn          diffuse non-interceptance, percent: 100 sum W'_i T_i / sum W'_i with the
                LAI-2000/2200 cosine ring weights W'_i (ring-quadrature version of svf)
  lai_eff       Miller: 2 sum W_i (-ln T_i) cos(z_i), W_i solid-angle weights of the rings
  lai           Lang-Xiang: as lai_eff with -mean_j ln T_ij (log-averaged segments)
  clumping_lx   lai_eff / lai
  ellipsoid_x   Campbell ellipsoidal leaf-angle parameter fitted to the ring contact numbers
  mean_tilt_deg mean leaf tilt from x (Campbell 1990)
Gap fractions are floored at --gap-floor (default {DEFAULT_GAP_FLOOR:g}) before logarithms.
When --zenith stops short of 90, openness and svf are normalised over the analysed range
(open sky = 1) and the LAI weights are renormalised over the analysed rings. The LAI
quantities assume an upward view and are empty for --axis horizontal.
"""


def _lens(value: str | None) -> Projection | None:
    return get_lens(value) if value else None


@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path),
              default=Path("hemi-out"), show_default=True, help="Output folder.")
@click.option("--preset", type=click.Choice(sorted(CAMERA_PRESETS), case_sensitive=False),
              help="Camera + converter: sets lens and mask (an explicit --lens/--mask wins).")
@click.option("--lens", "lens_name", metavar="NAME",
              help="equidistant (default), equisolid, stereographic, orthographic, FC-E8, FC-E9.")
@click.option("--polynomial", metavar="A1,A2,A3",
              help="Polynomial lens r/R = a1 x + a2 x^2 + ..., x = zenith/90 deg (overrides --lens).")
@click.option("--mask", "mask_text", metavar="CX,CY,R|auto", default="auto", show_default=True,
              help="90-degree circle in pixels, or 'auto' to detect the image circle.")
@click.option("--full-frame", is_flag=True,
              help="The 90-degree circle may extend past the frame (full-frame or cropped "
                   "circle); default mask: frame centre, radius half the diagonal.")
@click.option("--channel", type=click.Choice(CHANNELS, case_sensitive=False), default="blue",
              show_default=True, help="Channel to classify (grayscale images need luma).")
@click.option("--gamma", type=float, default=2.2, show_default=True,
              help="Gamma back-correction: v = 255 (v/255)^gamma (1 = off).")
@click.option("--threshold", default="otsu", show_default=True, metavar="otsu|isodata|zonal|N",
              help="Sky if value > threshold (0-255 scale of the processed channel).")
@click.option("--rings", type=int, default=9, show_default=True, help="Zenith rings.")
@click.option("--segments", type=int, default=8, show_default=True, help="Azimuth segments.")
@click.option("--zenith", "zenith_text", default="0,90", show_default=True, metavar="START,END",
              help="Analysed zenith range, degrees.")
@click.option("--north", type=float, default=0.0, show_default=True,
              help="Where true north lies in the image, degrees clockwise from image-up.")
@click.option("--mirror/--no-mirror", default=None,
              help="East-west mirror of upward photos (default: on for --axis up, off for "
                   "horizontal).")
@click.option("--axis", type=click.Choice(["up", "horizontal"]), default="up", show_default=True,
              help="Lens axis: up (canopy photo) or horizontal (from a facade, looking out).")
@click.option("--gap-floor", type=float, default=DEFAULT_GAP_FLOOR, show_default=True,
              help="Smallest gap fraction used in logarithms (LAI).")
@click.option("--outline-tolerance", type=float, default=1.0, show_default=True,
              help="Gap outline simplification tolerance, pixels.")
@click.option("--min-gap-area", type=float, default=4.0, show_default=True,
              help="Gaps and holes smaller than this many pixels are not outlined.")
@click.option("--no-overlay", is_flag=True, help="Do not draw the overlay PNGs.")
@click.option("--keep-going", is_flag=True,
              help="In a folder, skip images that fail (each a warning) instead of stopping.")
@click.argument("source", metavar="IMAGE_OR_FOLDER",
                type=click.Path(exists=True, path_type=Path))
def _hemi(*, source: Path, out_dir: Path, no_overlay: bool, keep_going: bool,
          **options: Any) -> None:
    config = _config(**options)
    report = run_batch(
        source, out_dir, config, overlay=not no_overlay, keep_going=keep_going)
    for row in report.rows:
        click.echo(
            f"{row['image']}: threshold {row['threshold']:.1f}  gap {row['gap_fraction']:.4f}  "
            f"openness {row['openness']:.4f}  svf {row['svf']:.4f}  difn {row['difn']:.2f} %  "
            f"lai_eff {row['lai_eff']:.3f}  lai {row['lai']:.3f}"
        )
    click.echo(f"wrote {len(report.written)} files to {out_dir}")
    if report.failures:
        click.echo(f"{len(report.failures)} image(s) skipped", err=True)
        raise click.exceptions.Exit(BAD_INPUT)


def _config(
    *, preset: str | None, lens_name: str | None, polynomial: str | None, mask_text: str,
    full_frame: bool, channel: str, gamma: float, threshold: str, rings: int, segments: int,
    zenith_text: str, north: float, mirror: bool | None, axis: str, gap_floor: float,
    outline_tolerance: float, min_gap_area: float,
) -> HemiConfig:
    """The analysis settings from the command's options (keywords as click names them)."""
    lens = parse_polynomial(polynomial) if polynomial else _lens(lens_name)
    mask = None if mask_text.strip().lower() == "auto" else parse_mask(mask_text)
    try:
        start, end = (float(v) for v in zenith_text.split(","))
    except ValueError:
        raise ConfigError(
            f"cannot read --zenith '{zenith_text}': expected START,END in degrees, e.g. 0,75"
        ) from None
    return HemiConfig(
        lens=lens, mask=mask, preset=preset.lower() if preset else None, full_frame=full_frame,
        channel=channel, gamma=gamma, threshold=ThresholdSpec.parse(threshold),
        grid=RingGrid(rings, segments, start, end), axis=axis, north_deg=north, mirror=mirror,
        gap_floor=gap_floor, outline_tolerance_px=outline_tolerance,
        outline_min_area_px=min_gap_area,
    )


hemi_analyse = click.command("analyse", help=HELP, context_settings=CONTEXT)(_hemi)
hemi_command = HemiGroup("hemi", help=HELP + """

Sub-commands (radtree hemi COMMAND --help):
  render PROJECT -s SCENARIO   synthetic fisheye of the scenario's crown from its photo point
  check PROJECT -s SCENARIO    the crown against its photo -> results/photo_check.csv
""", context_settings=CONTEXT, commands=[hemi_analyse, render_command, check_command])
