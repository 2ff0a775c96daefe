"""Turbid-medium crowns (``[tree] representation = "turbid"``): the free volume louvers crowns
as turbid media (:mod:`radtree.media`) instead of slats.

Equal leaf area density, angles, clumping and optics as the explicit volume slats
(:mod:`radtree.trees.volume`), so that the two representations differ only in how the leaves
are placed:

* leaf area density u = ρ · s² (m²/m³), ρ the slats per m³ of :func:`~radtree.trees.volume.
  volume_density` (crossings · cover on a vertical line through the crown centre), s the slat
  side;
* G(μ): the slats' own projection (:func:`radtree.trees.volume.slat_g`: the fixed inclination
  ``louvers.inclination_deg``, or Campbell's ellipsoidal distribution ``ellipsoid_x`` —
  with a species, its mean leaf tilt, :func:`radtree.trees.species.species_tree`), tabulated on
  :data:`MU_NODES` values of μ = |Ω_z|;
* clumping: G·Ω_c(G) of the slat clusters (:func:`radtree.trees.clumping.clumped_g`, the
  Boolean-model gap of ``louvers.clumping`` at ``cluster_radius_m`` and slat size), so that
  the mean gap along a path equals the clumped slats';
* optics: the slats' ``Trans`` material (R, T_d, T_s: the bi-Lambertian leaf plus its
  undeviated share);
* envelope: the crown spheroids of the row (:class:`radtree.trees.envelope.CrownRowSpec`) cut
  at the wall-side plane and the planes shared with neighbours; trunks as with slats.

A turbid crown costs a few numbers whatever its leaf count: a 1 000-tree district holds 1 000
rows of :class:`radtree.media.TurbidCrowns` instead of ≈ 26 000 slats per crown. The
differences that remain: explicit slats are finite squares (a slat's corners stand up to
s/√2 out of the spheroid, slats at the trunk are dropped, cut slats lose area) and a fixed
realisation; turbid leaves are points of the statistical law. The photo-fitted crown and the
layered arrangement have no turbid form (ConfigError).

The NumPy and forward engines trace media (:mod:`radtree.engines.common.turbid`), leaf
scattering included; the Radiance engine writes each crown as a ``mist`` volume
(:mod:`radtree.engines.radiance.mist`): the same extinction along one direction and the sun's
exact uncollided beam, but no leaf-scattered light (Radiance's mist scatters only light
sources and lets their shadow rays through the scattered share) — its façade light is below
the NumPy engine's by 4–16 % on the reference street and 29–36 % at the office example, most
of it the leaf-scattered share (``benchmarks/turbid_radiance.py``).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from radtree.config import Louvers, Project, Sensors, Street, Tree
from radtree.errors import ConfigError
from radtree.media import LeafKind, TurbidCrowns
from radtree.optics import Plastic
from radtree.scene import Mesh
from radtree.site.frame import FacadeFrame
from radtree.site.inventory import InventoryTree
from radtree.trees.clumping import clumped_g
from radtree.trees.district import leaf_material, single_spec, species_louvers, species_of
from radtree.trees.envelope import CrownRowSpec, crown_row_spec, row_notes
from radtree.trees.leaf_angles import BINS, inclination_pdf
from radtree.trees.louvers import LouverOptics, check_louvers
from radtree.trees.model import BARK_REFLECTANCE, LEAF, TRUNK, TreeModel
from radtree.trees.volume import recommended_volume_ab, slat_g, volume_density

MU_NODES = 201   # μ nodes of the tabulated G·Ω_c


def leaf_kind(lv: Louvers, material: str) -> LeafKind:
    """The leaves of ``lv`` as a turbid medium's :class:`~radtree.media.LeafKind`."""
    mu = np.linspace(0.0, 1.0, MU_NODES)
    g = np.array([slat_g(float(m), lv) for m in mu])
    g_eff = clumped_g(g, lv.clumping, lv.cluster_radius_m, lv.slat_size_m)
    if lv.inclination_distribution == "ellipsoidal":
        edges = np.linspace(0.0, 0.5 * math.pi, BINS + 1)
        cdf = np.concatenate([[0.0], np.cumsum(inclination_pdf(lv.ellipsoid_x)[1])])
        cdf /= cdf[-1]
    else:
        a = math.radians(lv.inclination_deg)
        edges, cdf = np.array([a, a]), np.array([0.0, 1.0])
    return LeafKind(material, mu, np.asarray(g_eff, float), edges, cdf, float(lv.clumping))


def leaf_area_density(lv: Louvers, b: float) -> float:
    """u = ρ s² (m²/m³) of volume slats in a crown of vertical semi-axis ``b``."""
    return volume_density(lv, b) * lv.slat_size_m ** 2


def _check(lv: Louvers, tree: Tree, source: str | None) -> None:
    if lv.arrangement != "volume":
        raise ConfigError(f"got arrangement {lv.arrangement!r} with representation 'turbid': a "
                          "turbid crown has the volume slats' density", source=source,
                          field="tree.louvers.arrangement")
    if tree.photo is not None:
        raise ConfigError("the photo-fitted crown has no turbid form (not implemented): use "
                          "representation = \"explicit\"", source=source,
                          field="tree.representation")


def row_planes(spec: CrownRowSpec, frame: FacadeFrame) -> np.ndarray:
    """(count, 3, 4) world half-spaces n·x ≥ c of each crown of the row: the wall-side plane
    (local n ≥ n_clip) and its strip's limits (lo ≤ u ≤ hi; ±∞: a row that keeps all)."""
    o = np.array([frame.origin_x, frame.origin_y, 0.0])
    nrm, along = frame.normal, frame.along
    out = np.zeros((spec.count, 3, 4))
    out[:, :, 3] = -1.0
    if math.isfinite(spec.n_clip):
        out[:, 0, :3] = nrm
        out[:, 0, 3] = spec.n_clip + nrm @ o
    for i, (lo, hi) in enumerate(spec.strips):
        if math.isfinite(lo):
            out[i, 1] = [*along, lo + along @ o]
        if math.isfinite(hi):
            out[i, 2] = [*(-along), -hi - along @ o]
    return out


def turbid_note(lv: Louvers, u: float, kind: LeafKind, count: int) -> str:
    """What a turbid row holds, for the notes."""
    g_v, g_h = float(kind.g(np.array([1.0]))[0]), float(kind.g(np.array([0.0]))[0])
    return (f"Turbid-medium crowns (representation 'turbid'): {count} spheroid(s) of leaf area "
            f"density {u:.3f} m²/m³ (the volume slats' {lv.slat_size_m:g} m slats at "
            f"crossings {lv.crossings if lv.crossings > 0 else lv.layers:g} × cover "
            f"{lv.cover_fraction:g}), G·Ω vertical {g_v:.3f}, horizontal {g_h:.3f} (clumping "
            f"{lv.clumping:g}): extinction {u * g_v:.3f}/m vertically, {u * g_h:.3f}/m "
            "horizontally; no slats are built.")


def build_turbid(tree: Tree, sensors: Sensors, street: Street, frame: FacadeFrame, form: str,
                 source: str | None = None) -> TreeModel:
    """The free crown row of ``tree`` as turbid crowns (trunks as meshes)."""
    if form != "free":
        raise ConfigError("representation 'turbid' needs free-standing crowns (tree.form = "
                          "\"free\")", source=source, field="tree.representation")
    lv = tree.louvers
    check_louvers(lv, source)
    _check(lv, tree, source)
    spec = crown_row_spec(tree, sensors, street, source)
    optics = LouverOptics.of(lv)
    kind = leaf_kind(lv, LEAF)
    u = leaf_area_density(lv, spec.b)
    media = TurbidCrowns.of(frame.to_world(spec.centres), spec.a, spec.b, u, 0, [kind],
                         row_planes(spec, frame))
    tv, tf = spec.trunks()
    meshes = [Mesh("tree_trunks", TRUNK, frame.to_world(tv), tf)]
    notes = [*row_notes(spec, tree, sensors), turbid_note(lv, u, kind, spec.count),
             "Leaf optics, " + optics.describe_slat() + "."]
    info = {"turbid_crowns": float(spec.count), "leaf_area_density_m2_m3": u,
            "leaf_area_m2": media.leaf_area(), "slat_count": 0.0,
            "extinction_vertical_per_m": u * float(kind.g(np.array([1.0]))[0]),
            "extinction_horizontal_per_m": u * float(kind.g(np.array([0.0]))[0])}
    model = TreeModel(meshes=meshes, materials={LEAF: optics.material(),
                                                TRUNK: Plastic(TRUNK, BARK_REFLECTANCE)},
                      notes=notes, recommended_ab=recommended_volume_ab(lv), info=info,
                      form=form, model="louvers")
    model.media = media
    return model


def inventory_turbid(project: Project, trees: list[InventoryTree], tree: Tree) -> TreeModel:
    """Every inventory tree as one turbid crown of its own size (no instancing needed), leaf
    optics, tilt and density from its species (:func:`radtree.trees.district.species_louvers`),
    trunks as meshes (:func:`radtree.trees.district.inventory_crowns` with slats)."""
    source = str(project.source)
    _check(tree.louvers, tree, source)
    species = species_of(trees, source)
    keys = list(dict.fromkeys(str(species[t.id].key) for t in trees))
    default_rt = project.tree.crown.trunk_diameter_m / 2.0
    materials: dict = {TRUNK: Plastic(TRUNK, BARK_REFLECTANCE)}
    kinds: list[LeafKind] = []
    lvs: dict[str, Louvers] = {}
    notes: list[str] = []
    for key in keys:
        group = [t for t in trees if species[t.id].key == key]
        slv = replace(species_louvers(tree, species[group[0].id]), arrangement="volume")
        mat, o, material = leaf_material(slv, key, source)
        materials[mat] = material
        kinds.append(leaf_kind(slv, mat))
        lvs[key] = slv
        notes.append(f"{key}: {len(group)} turbid crown(s); leaves " + o.describe_slat()
                     + f", tilt {slv.inclination_deg:g}° (species), G·Ω vertical "
                     f"{float(kinds[-1].g(np.array([1.0]))[0]):.3f}.")
    n = len(trees)
    centres, a, b, lad, kind = np.zeros((n, 3)), np.zeros(n), np.zeros(n), np.zeros(n), \
        np.zeros(n, np.int64)
    tv_all, tf_all, off = [], [], 0
    for i, t in enumerate(trees):
        key = str(species[t.id].key)
        a[i], b[i] = t.crown_radius_m, t.vertical_radius_m
        centres[i] = (t.x, t.y, t.crown_base_m + b[i])
        kind[i] = keys.index(key)
        lad[i] = leaf_area_density(lvs[key], b[i])
        rt = (t.trunk_diameter_m / 2.0) if t.trunk_diameter_m else default_rt
        tv, tf = single_spec(centres[i], a[i], b[i], rt, t.crown_base_m + 0.5 * b[i]).trunks()
        tv_all.append(tv)
        tf_all.append(tf + off)
        off += len(tv)
    media = TurbidCrowns.of(centres, a, b, lad, kind, kinds)
    meshes = [Mesh("tree_trunks", TRUNK, np.vstack(tv_all), np.vstack(tf_all))]
    notes.insert(0, f"Tree inventory: {n} trees of {len(keys)} species as turbid-medium crowns "
                    f"(representation 'turbid'; leaf area density "
                    f"{lad.min():.2f}–{lad.max():.2f} m²/m³, total leaf area "
                    f"{media.leaf_area():.0f} m²); no slats are built.")
    ab = max(recommended_volume_ab(lv) for lv in lvs.values())
    info = {"trees": float(n), "species": float(len(keys)), "turbid_crowns": float(n),
            "instances": 0.0, "prototypes": 0.0}
    model = TreeModel(meshes=meshes, materials=materials, notes=notes, recommended_ab=ab,
                      info=info, form="free", model="louvers")
    model.media = media
    return model
