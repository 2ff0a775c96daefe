"""``radtree lidar``: trees and crowns from laser scanning point clouds (LAS/LAZ)."""

from __future__ import annotations

from pathlib import Path

import click

from radtree.cli.options import CONTEXT
from radtree.lidar.ground import GROUND_MODES
from radtree.lidar.segment import SegmentConfig

_D = SegmentConfig()   # the defaults shown in --help

_TILE = click.argument("tile", type=click.Path(path_type=Path))


def _settings(f):  # type: ignore[no-untyped-def]
    """The segmentation options shared by ``segment`` and ``clip`` (same options, same ids)."""
    opts = [
        click.option("--ground", type=click.Choice(GROUND_MODES), default=_D.ground,
                     show_default=True,
                     help="Where the ground comes from: 'class' = points classified 2; "
                          "'filter' = a stated simple morphological filter (lowest point per "
                          "1 m cell, opened with a 20 m window) for unclassified tiles; "
                          "'heights' = z already holds heights above ground."),
        click.option("--cell", "cell_m", type=float, default=_D.cell_m, show_default=True,
                     help="Canopy height model cell, m."),
        click.option("--smooth", "smooth_m", type=float, default=_D.smooth_m, show_default=True,
                     help="Gaussian smoothing of the canopy height model (s.d., m; 0 = off)."),
        click.option("--min-height", "min_height_m", type=float, default=_D.min_height_m,
                     show_default=True, help="Lowest tree top and crown cell, m above ground."),
        click.option("--window", "window", type=(float, float), default=(_D.window_base_m, _D.window_slope),
                     show_default=True, metavar="BASE SLOPE",
                     help="Tree-top window diameter ws = BASE + SLOPE × height (m): a top "
                          "is the highest cell within ws. Wider windows merge neighbours, "
                          "narrower ones split crowns."),
        click.option("--prominence", "prominence_m", type=float, default=_D.prominence_m,
                     show_default=True,
                     help="A top must rise this far (m) above the saddle to any higher top: "
                          "the bumps of one rough crown are not trees. 0 = off."),
        click.option("--crown-ratio", type=float, default=_D.crown_ratio, show_default=True,
                     help="A crown keeps the cells at least this fraction of its top's height."),
    ]
    for o in reversed(opts):
        f = o(f)
    return f


def _config(ground, cell_m, smooth_m, min_height_m, window, prominence_m, crown_ratio):  # type: ignore[no-untyped-def]
    return SegmentConfig(ground=ground, cell_m=cell_m, smooth_m=smooth_m,
                         min_height_m=min_height_m, window_base_m=window[0],
                         window_slope=window[1], prominence_m=prominence_m,
                         crown_ratio=crown_ratio)


@click.group("lidar", context_settings=CONTEXT)
def lidar_command() -> None:
    """Trees from airborne laser scanning (ALS) tiles, one tree's points from a tile.

    \b
    A street inventory from a city's ALS tile:
      radtree lidar segment tile.laz --species morus_alba --crs EPSG:25833 --out trees.geojson
      radtree new street-study --trees trees.geojson --buildings footprints.geojson
    One tree's points (for a crown built from its points):
      radtree lidar clip tile.laz --tree L007 --out tree.laz

    Conventions: metres; x east, y north, z up; heights above ground. Reads LAS 1.0–1.4 and
    LAZ (laspy with the lazrs codec).
    """


@lidar_command.command("segment", context_settings=CONTEXT)
@_TILE
@click.option("--out", type=click.Path(dir_okay=False, path_type=Path), required=True,
              help="The inventory GeoJSON to write.")
@click.option("--species", required=True,
              help="Species of every tree (an airborne scan cannot tell it; edit the file per "
                   "tree afterwards), e.g. morus_alba.")
@click.option("--crs", default=None,
              help="CRS of the tile's x, y when the tile records none, e.g. EPSG:25833, or "
                   "'local' when they are already metres from the site origin (x east, "
                   "y north). Overrides the tile's own CRS.")
@_settings
def segment_command(tile: Path, out: Path, species: str, crs: str | None, **settings) -> None:  # type: ignore[no-untyped-def]
    """Find the trees of a tile and write them as an inventory GeoJSON.

    \b
    Steps: heights above ground (ground points: classification 2, or --ground) → canopy
    height model (highest point per --cell, smoothed by --smooth; roofs and noise left out
    by their class) → tree tops (local maxima in a window widening with height, --window,
    rising --prominence above their saddles) → crowns (marker-controlled watershed from the
    tops, --crown-ratio) → per tree: position (the crown's area centroid), top, height_m,
    crown_diameter_m (equal-area circle), crown_base_m (5 % quantile of the crown's returns
    above --min-height: biased high, as ALS sees little under a crown), points, and the
    crown's outline (property crown_outline).

    \b
    The file is what `radtree new --trees` reads, in longitude/latitude when the tile's CRS
    (or --crs) is known. A tile without a CRS keeps its metres: give --crs (or [site] crs)
    before it meets longitude/latitude data.
    """
    from radtree.lidar.geojson import crs_name, write_inventory
    from radtree.lidar.segment import segment_tile
    from radtree.lidar.tile import read_tile

    t = read_tile(tile)
    seg = segment_tile(t, _config(**settings))
    write_inventory(seg, out, species, crs)
    heights = [tr.height_m for tr in seg.trees]
    click.echo(f"{len(seg.trees)} trees ({min(heights):.1f}–{max(heights):.1f} m high) from "
               f"{len(t)} points (spacing {t.spacing_m():.2f} m) → {out}")
    if crs_name(t.crs, crs, t.source) is None:
        click.echo("note: the tile has no CRS and no --crs was given: the inventory's x, y "
                   "are the tile's metres; give --crs (or [site] crs) before `radtree new`.",
                   err=True)


@lidar_command.command("clip", context_settings=CONTEXT)
@_TILE
@click.option("--tree", "tree_id", required=True,
              help="The tree's id, as `radtree lidar segment` wrote it (e.g. L007).")
@click.option("--out", type=click.Path(dir_okay=False, path_type=Path), required=True,
              help="The point file to write (.laz or .las).")
@_settings
def clip_command(tile: Path, tree_id: str, out: Path, **settings) -> None:  # type: ignore[no-untyped-def]
    """Write one tree's points (its crown and the ground around it) to LAS/LAZ.

    The tile is segmented again with the same options as `radtree lidar segment`, so the
    same options give the same ids. Kept: the points of the tree's watershed region and of
    the cells 2 m around it that belong to no other tree (its ground, so heights can be
    found again; the beams that passed beside the crown). The header (point format, scales,
    CRS) is the tile's. Use the file as [tree] points = "tree.laz" (free louvers crowns
    filled voxel by voxel with its plant area density).
    """
    from radtree.lidar.clip import clip_tree

    path, n = clip_tree(tile, tree_id, out, _config(**settings))
    click.echo(f"tree {tree_id}: {n} points → {path}")
