"""Louvers crowns filled voxel by voxel from a tree's point cloud (``[tree] points``).

The points (LAS/LAZ of one tree with its ground points, e.g. from ``radtree lidar clip``)
become a grid of plant area density (:mod:`radtree.lidar.voxels`: Beer–Lambert inversion, voxel
size ``tree.points_voxel_m`` or 5 point spacings; airborne files along each beam rebuilt from
its LAS scan angle and flight line when the file gives them (``tree.points_beams`` =
"scan_angle", the default; :mod:`radtree.lidar.scan_angle`; ``benchmarks/lidar_als_user.py``:
the 20 street trees clipped from the synthetic tile within 10 % for 20/20 trees against 9/20
as vertical columns, scanner seed 0), else along vertical beams; or, for terrestrial
scans whose positions ``tree.points_scans`` lists, along every beam from its scanner,
:mod:`radtree.lidar.beams`, voxel size ``tree.points_voxel_m`` or :data:`TLS_VOXEL_M`; the
projection G of the slats' own leaf angles — ``louvers.inclination_deg`` or its ellipsoidal distribution, which
the species fills — so inversion and crown use the same leaves; wood counted as leaf area).

Every voxel of density PAD (m²/m³) and volume v³ receives PAD·v³ / s² slats of side s
(``louvers.slat_size_m``; one-sided leaf area s² each; the fraction rounded up with a seeded
draw), centres at the heights uniform in the voxel and horizontally at one of the voxel's
returns drawn at random ± half a point spacing (kept in the voxel; uniform where the voxel
holds no return), so the crown keeps its shape inside a voxel; normals at random azimuths and the louvers' inclination
(fixed or drawn from the ellipsoidal distribution). So the crown's leaf area is the scan's,
voxel by voxel; ``cover_fraction`` plays no part (the slats' optics do: the gap reading, with
near-opaque real leaves, is the consistent one). Before filling, the grid is kept inside the
convex hull of the crown's returns on cells of a quarter voxel (:func:`points_crown_grid`,
:mod:`radtree.trees.points_hull`: the rim stays sharp, and each rim voxel's measured gap is
held by the part of it inside the hull — re-inverted on the beams through that part, vertical
or along the scan-angle beams, :mod:`radtree.trees.points_rim`), and the slats fill those cells. The cloud is placed on
every trunk of the row: the centre of the crown's outline seen from above
(:func:`radtree.trees.points_hull.crown_centre`) on the trunk axis, its ground at the street
(z = 0), its x along the façade (u) and y away from it (n). Slats are then clipped like the volume arrangement's
(:mod:`radtree.trees.crown_clip`: trunk, wall-side plane, planes shared with neighbours).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from radtree.config import Louvers, Tree
from radtree.errors import ConfigError
from radtree.lidar.voxels import VoxelGrid, tree_voxels
from radtree.trees.crown_clip import cut_to_share, touches_share, trunk_clash
from radtree.trees.envelope import CrownRowSpec
from radtree.trees.leaf_angles import draw_inclinations, mean_projection, projection_g
from radtree.trees.volume import MAX_VOLUME_SLATS, mean_cos, slat_edges

#: voxel size (m) of crowns from terrestrial scans when ``tree.points_voxel_m`` is unset (their
#: point spacing says nothing of the leaves; benchmarks/lidar_tls.py: one crown's leaf area
#: +3.4 / −0.1 / −2.8 % at 0.5 / 0.75 / 1 m)
TLS_VOXEL_M = 1.0


def airborne_beams(tree: Tree) -> bool:
    """Whether the airborne ``tree.points`` are inverted along their beams from the file's
    scan angles and flight lines (``tree.points_beams`` = "scan_angle" and the geometry
    derivable, :mod:`radtree.lidar.scan_angle`), not in vertical columns."""
    if tree.points is None or tree.points_scans is not None:
        return False
    if tree.points_beams != "scan_angle":
        return False
    from radtree.lidar.scan_angle import scan_angle_origins
    from radtree.lidar.tile import read_tile

    return scan_angle_origins(read_tile(tree.points)) is not None


def _g_of_mu(lv: Louvers) -> Any:
    def g_of_mu(mu: np.ndarray) -> np.ndarray:
        if lv.inclination_distribution == "ellipsoidal":
            return mean_projection(mu, lv.ellipsoid_x)
        return projection_g(mu, lv.inclination_deg)
    return g_of_mu


def _origins(tile: Any) -> np.ndarray:
    from radtree.lidar.scan_angle import HEIGHT_RANGE_M, scan_angle_origins

    o = scan_angle_origins(tile)
    return tile.xyz + [0.0, 0.0, HEIGHT_RANGE_M[1]] if o is None else o


def points_grid(tree: Tree, source: str | None = None) -> VoxelGrid:
    """The plant area density grid of ``tree.points`` with the louvers' projection G: along
    every beam of the terrestrial scans ``tree.points_scans``, along the airborne beams of the
    file's scan angles (:func:`airborne_beams`), or along vertical beams."""
    assert tree.points is not None
    lv = tree.louvers
    g = mean_cos(lv)
    if tree.points_scans is not None:
        from radtree.lidar.tls import read_scans, tls_beams

        size = tree.points_voxel_m or TLS_VOXEL_M
        return tree_voxels(tree.points, max(g, 1e-6), size, g_of_mu=_g_of_mu(lv),
                           **tls_beams(read_scans(tree.points_scans)))
    if airborne_beams(tree):
        return tree_voxels(tree.points, max(g, 1e-6), tree.points_voxel_m,
                           origins=_origins, g_of_mu=_g_of_mu(lv))
    if g < 1e-6:
        raise ConfigError("vertical slats (inclination 90°) intercept no vertical beam: the "
                          "inversion is undefined", source=source,
                          field="tree.louvers.inclination_deg")
    return tree_voxels(tree.points, g, tree.points_voxel_m)


def points_crown_grid(tree: Tree, source: str | None = None) -> tuple[VoxelGrid, VoxelGrid, int]:
    """(the inversion grid of :func:`points_grid`, the crown's grid kept inside the returns'
    hull on cells of 1/:data:`~radtree.trees.points_hull.SUB` voxel — what the crowns are
    filled from and placed by —, voxels with leaves no beam through their hull part reached):
    :func:`radtree.trees.points_hull.sharpen`, re-inverted on the beams through each voxel's
    hull part for airborne scans (vertical, or along the scan-angle beams:
    :func:`radtree.trees.points_rim.beam_footprint_density`)."""
    from radtree.trees.points_hull import sharpen, vertical_beams

    grid = points_grid(tree, source)
    assert tree.points is not None
    tilted = airborne_beams(tree)
    vertical = tree.points_scans is None and not tilted
    beams = vertical_beams(tree.points) if vertical else None
    density = None
    if tilted:
        from radtree.trees.points_rim import beam_footprint_density, tilted_beams

        rays, g_of_mu = tilted_beams(tree.points), _g_of_mu(tree.louvers)

        def density(gr: VoxelGrid, ins: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            return beam_footprint_density(gr, ins, beams=rays, g_of_mu=g_of_mu)
    fine, unreached = sharpen(grid, beams=beams, density=density)
    return grid, fine, unreached


def layer_profile(inv: VoxelGrid, fine: VoxelGrid) -> tuple[np.ndarray, np.ndarray]:
    """(layer bottoms m, plant area m²) of the crown grid ``fine`` on the layers of the
    inversion grid ``inv`` (the manifest's profile)."""
    z, area = fine.profile()
    k = np.floor(z / inv.size_m + 1e-6).astype(np.int64)
    per = np.bincount(k, weights=area, minlength=inv.pad.shape[2])
    return np.arange(len(per)) * inv.size_m, per


def _corners(centres: np.ndarray, phi: np.ndarray, tilt: Any, s: float) -> np.ndarray:
    e1, e2 = slat_edges(phi, tilt)
    h1 = np.array([-0.5, 0.5, 0.5, -0.5]) * s
    h2 = np.array([-0.5, -0.5, 0.5, 0.5]) * s
    return (centres[:, None, :] + h1[None, :, None] * e1[:, None, :]
            + h2[None, :, None] * e2[:, None, :])


def voxel_slats(grid: VoxelGrid, lv: Louvers, rng: np.random.Generator,
                origin: np.ndarray) -> tuple[np.ndarray, np.ndarray, Any]:
    """Slat centres (k, 3), azimuths and inclinations of one crown: PAD·v³/s² per voxel
    (module text); ``origin`` is where the crown's centre
    (:func:`radtree.trees.points_hull.crown_centre`) stands (u, n, 0)."""
    from radtree.trees.points_hull import crown_centre

    s, v = lv.slat_size_m, grid.size_m
    expected = grid.pad * v**3 / (s * s)
    n = np.floor(expected).astype(np.int64)
    n += rng.random(expected.shape) < (expected - n)
    idx = np.repeat(np.arange(n.size), n.ravel())
    i, j, k = np.unravel_index(idx, n.shape)
    cxy = crown_centre(grid)
    corner = np.column_stack([grid.x0 + i * v - cxy[0], grid.y0 + j * v - cxy[1], k * v])
    centres = origin + corner + rng.random((len(idx), 3)) * v
    # horizontally, slats go where the voxel's returns are (± half a point spacing), so the
    # crown keeps its shape inside a voxel (a rim by the wall stays a rim)
    xy, has = grid.returns_in(i, j, k, rng)
    jitter = (rng.random((len(idx), 2)) - 0.5) * grid.spacing_m
    lo = np.column_stack([grid.x0 + i * v, grid.y0 + j * v])
    near = np.clip(xy + jitter, lo, lo + v)
    centres[has, :2] = origin[:2] + near[has] - cxy
    phi = rng.uniform(0.0, 2.0 * math.pi, len(idx))
    tilt: Any = math.radians(lv.inclination_deg)
    if lv.inclination_distribution == "ellipsoidal":
        tilt = draw_inclinations(rng, len(idx), lv.ellipsoid_x)
    return centres, phi, tilt


def build_points_louvers(spec: CrownRowSpec, tree: Tree, source: str | None = None
                         ) -> tuple[list[np.ndarray], dict[str, float], VoxelGrid]:
    """Slat polygons (local coordinates) of the row's crowns from ``tree.points``, geometry
    info (voxel size, leaf area, its vertical profile) and the grid."""
    lv = tree.louvers
    inv, grid, unreached = points_crown_grid(tree, source)
    per = grid.leaf_area_m2 / lv.slat_size_m**2
    if per * spec.count > MAX_VOLUME_SLATS:
        raise ConfigError(f"the crowns from {tree.points} would need {per * spec.count:.0f} "
                          f"slats (limit {MAX_VOLUME_SLATS}): use larger slats "
                          "(tree.louvers.slat_size_m)", source=source,
                          field="tree.louvers.slat_size_m")
    polys: list[np.ndarray] = []
    cut = dropped = 0
    for ti, child in enumerate(np.random.SeedSequence(lv.seed).spawn(spec.count)):
        rng = np.random.default_rng(child)
        c = spec.centres[ti]
        lo, hi = spec.strips[ti]
        centres, phi, tilt = voxel_slats(grid, lv, rng, np.array([c[0], c[1], 0.0]))
        corners = _corners(centres, phi, tilt, lv.slat_size_m)
        rho = np.hypot(centres[:, 0] - c[0], centres[:, 1] - c[1])
        clash = trunk_clash(rho, corners[:, :, 2].min(axis=1), spec, lv.slat_size_m)
        ok = touches_share(corners, spec, lo, hi) & ~clash
        dropped += int(clash.sum())
        kept, n_cut = cut_to_share(corners[ok], spec, lo, hi)
        polys.extend(kept)
        cut += n_cut
    z, area = layer_profile(inv, grid)
    info = {"points_voxel_m": inv.size_m, "points_spacing_m": grid.spacing_m,
            "points_g_vertical": grid.g, "points_leaf_area_m2": grid.leaf_area_m2,
            "points_inverted_leaf_area_m2": inv.leaf_area_m2, "points_cell_m": grid.size_m,
            "points_hull_unreached": float(unreached),
            "points_scan_positions": float(scan_positions(tree)),
            "points_airborne_beams": float(airborne_beams(tree)),
            "points_height_m": float(len(z) * inv.size_m), "slats_cut": float(cut),
            "slats_dropped": float(dropped), "slat_mean_area_m2": lv.slat_size_m**2}
    for zk, ak in zip(z, area):
        info[f"points_leaf_area_m2_z{zk:.2f}_{zk + inv.size_m:.2f}"] = float(ak)
    return polys, info, grid


def scan_positions(tree: Tree) -> int:
    """How many terrestrial scan positions ``tree.points_scans`` lists (0: airborne)."""
    if tree.points_scans is None:
        return 0
    from radtree.lidar.tls import read_scans

    return len(read_scans(tree.points_scans))


def points_note(tree: Tree, info: dict[str, float], slats: int) -> str:
    """What the points crown is, for the notes."""
    z = [k for k in info if k.startswith("points_leaf_area_m2_z")]
    top = sorted(z, key=lambda k: -info[k])[:3]
    peak = ", ".join(f"{k.split('_z')[1].replace('_', '–')} m: {info[k]:.1f} m²" for k in top)
    return (f"Crowns from the point cloud {tree.points.name if tree.points else ''}: plant area "
            f"density on {info['points_voxel_m']:g} m voxels (mean point spacing "
            f"{info['points_spacing_m']:.2f} m) by Beer–Lambert inversion along "
            f"{_beams_text(info)} "
            f"(G = {info['points_g_vertical']:.3f} of the slats' leaf angles; wood counted as "
            f"leaf area), kept inside the returns' convex hull on "
            f"{info.get('points_cell_m', info['points_voxel_m']):g} m cells (inverted "
            f"{info.get('points_inverted_leaf_area_m2', info['points_leaf_area_m2']):.1f} m²): "
            f"{info['points_leaf_area_m2']:.1f} m² per crown, "
            f"{info['points_height_m']:.1f} m high; densest layers {peak}. {slats} slats of "
            f"{tree.louvers.slat_size_m:g} m fill it cell by cell "
            f"({int(info['slats_cut'])} cut at the wall-side or shared planes, "
            f"{int(info['slats_dropped'])} dropped at the trunks).")


def points_record(points: str | Path | None, info: dict[str, float]) -> dict[str, Any] | None:
    """The build manifest's record of a crown from points (None for other crowns): the point
    file (name, SHA-256), voxel size (m), mean point spacing (m), projection G, total leaf
    (plant) area (m², one crown) and its vertical profile — per layer of one voxel, bottom and
    top (m above the street), leaf area (m²) and leaf area per metre of height (m²/m)."""
    if points is None or "points_leaf_area_m2" not in info:
        return None
    from radtree.fileio import file_sha256

    path = Path(points)
    v = float(info["points_voxel_m"])
    layers = sorted((float(k.split("_z")[1].split("_")[0]), float(val))
                    for k, val in info.items() if k.startswith("points_leaf_area_m2_z"))
    return {
        "file": path.name,
        "sha256": file_sha256(path) if path.is_file() else None,
        "voxel_m": round(v, 6), "point_spacing_m": float(info["points_spacing_m"]),
        "g_vertical": float(info["points_g_vertical"]),
        "leaf_area_m2": float(info["points_leaf_area_m2"]),
        "profile": {"z_bottom_m": [round(z, 4) for z, _ in layers],
                    "z_top_m": [round(z + v, 4) for z, _ in layers],
                    "leaf_area_m2": [a for _, a in layers],
                    "leaf_area_m2_per_m": [a / v for _, a in layers]},
    }


def _beams_text(info: dict[str, float]) -> str:
    n = int(info.get("points_scan_positions", 0))
    if n:
        return (f"every beam of {n} terrestrial scan position{'s' if n > 1 else ''} (sky shots "
                "included)")
    if info.get("points_airborne_beams"):
        return "each airborne beam from its scan angle and flight line"
    return "vertical beams"
