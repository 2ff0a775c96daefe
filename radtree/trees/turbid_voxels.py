"""Turbid crowns on voxel grids (``[tree] representation = "turbid"`` with ``[tree] points`` or
``[tree] voxels``), the louvers model's turbid builder.

* ``points`` (one tree's LAS/LAZ): the plant area density grid of
  :func:`radtree.trees.points_crown.points_crown_grid` (Beer–Lambert inversion along vertical
  beams, G of the louvers' leaf angles, wood counted as leaf area; kept inside the returns'
  convex hull on quarter-voxel cells, :mod:`radtree.trees.points_hull`) placed on every trunk
  of the free row exactly as the louvers-from-points crown places its slats: the centre of
  the crown's outline (:func:`radtree.trees.points_hull.crown_centre`) on the trunk axis, its ground at the street, its x along the façade (u) and y away
  from it (n).
* ``voxels`` (a CSV file, :mod:`radtree.trees.voxel_file`): the grid as written, its
  coordinates relative to each trunk base (x along the façade, y away from it, z up).

Each crown is a :class:`radtree.media_voxels.VoxelCrowns` grid (all the row's crowns share one
density array) cut by the row's wall-side plane and the planes shared with neighbours
(:func:`radtree.trees.turbid.row_planes`); leaves as the spheroid turbid crowns
(:func:`radtree.trees.turbid.leaf_kind`: G of the louvers' angles, their clumping, the slats'
``Trans`` optics). The voxel density is used as it is (no clumping inside a voxel beyond the
louvers' ``clumping``). Without ``points`` or ``voxels`` the spheroid turbid crowns are built
(:func:`radtree.trees.turbid.build_turbid`).

The crown's ``info`` (a build's facts) and the manifests of builds and results
(:func:`voxel_record`, under ``crown_voxels``) record the file and its sha256, the voxel size,
the leaf area of one crown and its vertical profile (per layer, uncut).
"""

from __future__ import annotations

import numpy as np

from radtree.config import Sensors, Street, Tree
from radtree.errors import ConfigError
from radtree.media_voxels import VoxelCrowns
from radtree.optics import Plastic
from radtree.scene import Mesh
from radtree.site.frame import FacadeFrame
from radtree.trees.envelope import CrownRowSpec, crown_row_spec, row_notes
from radtree.trees.louvers import LouverOptics, check_louvers
from radtree.trees.model import BARK_REFLECTANCE, LEAF, TRUNK, TreeModel
from radtree.trees.turbid import build_turbid, leaf_kind, row_planes
from radtree.trees.volume import recommended_volume_ab


def build_turbid_crowns(tree: Tree, *, sensors: Sensors, street: Street, frame: FacadeFrame,
                        form: str, source: str | None = None) -> TreeModel:
    """The louvers model's turbid crowns: voxel grids from ``points`` or ``voxels``, else
    the spheroids of :func:`radtree.trees.turbid.build_turbid`."""
    if tree.points is None and tree.voxels is None:
        return build_turbid(tree, sensors, street, frame, form, source)
    return build_voxel_turbid(tree, sensors=sensors, street=street, frame=frame, form=form,
                              source=source)


def _grid(tree: Tree, source: str | None) -> tuple[np.ndarray, float, np.ndarray, dict, str]:
    """(density grid, voxel side m, lower corner of voxel (0, 0, 0) relative to the trunk
    base in the façade frame (u, n, z) m, info, what it is for the notes)."""
    if tree.points is not None:
        from radtree.trees.points_crown import points_crown_grid
        from radtree.trees.points_hull import crown_centre

        inv, g, unreached = points_crown_grid(tree, source)
        cxy = crown_centre(g)
        corner = np.array([g.x0 - cxy[0], g.y0 - cxy[1], 0.0])
        info = {"points_voxel_m": inv.size_m, "points_spacing_m": g.spacing_m,
                "points_g_vertical": g.g, "points_leaf_area_m2": g.leaf_area_m2,
                "points_inverted_leaf_area_m2": inv.leaf_area_m2, "points_cell_m": g.size_m,
                "points_hull_unreached": float(unreached),
                "points_height_m": float(inv.pad.shape[2] * inv.size_m)}
        what = (f"the point cloud {tree.points.name}: Beer–Lambert inversion along vertical "
                f"beams on {inv.size_m:g} m voxels (mean point spacing {g.spacing_m:.2f} m, "
                f"G = {g.g:.3f} of the leaf angles; wood counted as leaf area; "
                f"{inv.leaf_area_m2:.1f} m²), kept inside the returns' convex hull on "
                f"{g.size_m:g} m cells, the centre of its outline on each trunk")
        return g.pad, g.size_m, corner, info, what
    from radtree.trees.voxel_file import read_voxel_file

    assert tree.voxels is not None
    vf = read_voxel_file(tree.voxels, tree.voxels_size_m)
    info = {"voxels_size_m": vf.size_m, "voxels_rows": float(vf.rows),
            "voxels_leaf_area_m2": float(vf.pad.sum() * vf.size_m ** 3)}
    what = (f"the voxel file {tree.voxels.name} ({vf.rows} voxels listed"
            f"{'' if tree.voxels_size_m else ', side from their spacing'}), placed by its "
            "coordinates from each trunk base")
    return vf.pad, vf.size_m, vf.corner, info, what


def voxel_record(tree: Tree, source: str | None = None) -> dict | None:
    """The manifest's record of a turbid voxel crown (module text); None for other crowns."""
    path = tree.points if tree.points is not None else tree.voxels
    if tree.representation != "turbid" or path is None:
        return None
    from radtree.fileio import file_sha256

    pad, size, corner, _, _ = _grid(tree, source)
    per = pad.sum(axis=(0, 1)) * size ** 3
    bottoms = corner[2] + np.arange(len(per)) * size
    return {"file": str(path), "sha256": file_sha256(path), "voxel_size_m": size,
            "voxels": list(pad.shape), "leaf_area_m2_per_crown": float(per.sum()),
            "profile": [{"z_bottom_m": round(float(z), 6), "z_top_m": round(float(z + size), 6),
                         "leaf_area_m2": float(a)} for z, a in zip(bottoms, per)]}


def voxel_row(spec: CrownRowSpec, frame: FacadeFrame, *, pad: np.ndarray, size_m: float,
              corner: np.ndarray, kind_material: str, tree: Tree) -> VoxelCrowns:
    """One voxel crown per trunk of the row, sharing ``pad``: voxel (0, 0, 0) at ``corner``
    from each trunk base (façade frame), axes along u, n, z, cut like the spheroid row."""
    bases = np.column_stack([spec.centres[:, :2], np.zeros(spec.count)])
    origins = frame.to_world(bases + corner)
    kind = leaf_kind(tree.louvers, kind_material)
    return VoxelCrowns.of(origins, size_m=size_m, pads=[pad], kinds=[kind],
                          planes=row_planes(spec, frame), axis_i=frame.along[:2])


def build_voxel_turbid(tree: Tree, *, sensors: Sensors, street: Street, frame: FacadeFrame,
                       form: str, source: str | None = None) -> TreeModel:
    """The free row's crowns as voxel grids (module text), trunks as meshes."""
    what_field = "tree.points" if tree.points is not None else "tree.voxels"
    if form != "free":
        raise ConfigError(f"a turbid crown from {what_field} is free-standing: use tree.form = "
                          "\"free\" (or a scenario form \"free\")", source=source,
                          field=what_field)
    lv = tree.louvers
    check_louvers(lv, source)
    spec = crown_row_spec(tree, sensors, street, source)
    pad, size, corner, info, what = _grid(tree, source)
    media = voxel_row(spec, frame, pad=pad, size_m=size, corner=corner, kind_material=LEAF,
                      tree=tree)
    optics = LouverOptics.of(lv)
    kind = media.kinds[0]
    z, area = media.profile(0)
    prefix = "points" if tree.points is not None else "voxels"
    for zk, ak in zip(z + corner[2], area):
        info[f"{prefix}_leaf_area_m2_z{zk:.2f}_{zk + size:.2f}"] = float(ak)
    total = media.leaf_area()
    nx, ny, nz = pad.shape
    info.update({"turbid_crowns": float(spec.count), "voxels_per_crown": float(pad.size),
                 "leaf_area_m2": total, "slat_count": 0.0,
                 "extinction_vertical_per_pad": float(kind.g(np.array([1.0]))[0]),
                 "extinction_horizontal_per_pad": float(kind.g(np.array([0.0]))[0])})
    top = np.argsort(-area)[:3]
    peak = ", ".join(f"{z[k] + corner[2]:.2f}–{z[k] + corner[2] + size:.2f} m: {area[k]:.1f} m²"
                     for k in top)
    notes = [*row_notes(spec, tree, sensors),
             f"Turbid voxel crowns (representation 'turbid') from {what}: {spec.count} "
             f"grid(s) of {nx} × {ny} × {nz} voxels of {size:g} m, "
             f"{float(pad.sum() * size ** 3):.1f} m² of leaf area per crown uncut "
             f"({total:.1f} m² in all after the wall-side and shared cuts); densest layers "
             f"{peak}; extinction per unit density G·Ω vertically "
             f"{info['extinction_vertical_per_pad']:.3f}, horizontally "
             f"{info['extinction_horizontal_per_pad']:.3f}; no slats are built.",
             "Leaf optics, " + optics.describe_slat() + "."]
    tv, tf = spec.trunks()
    model = TreeModel(meshes=[Mesh("tree_trunks", TRUNK, frame.to_world(tv), tf)],
                      materials={LEAF: optics.material(),
                                 TRUNK: Plastic(TRUNK, BARK_REFLECTANCE)},
                      notes=notes, recommended_ab=recommended_volume_ab(lv), info=info,
                      form=form, model="louvers")
    model.media = media
    return model
