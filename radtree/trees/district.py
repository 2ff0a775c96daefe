"""Crowns of a tree inventory: each tree a free-standing crown built by the existing crown
models (:mod:`radtree.trees.volume`, :mod:`radtree.trees.louvers_free`) from its species
(:mod:`radtree.trees.species`) and its inventory row.

Per tree: a spheroid of horizontal semi-axis a = crown_diameter_m / 2 and vertical semi-axis
b = (height_m − crown_base_m) / 2, lowest point at crown_base_m, on a trunk (bark ρ 0.2) of
the row's ``trunk_diameter_m`` (else ``[tree.crown] trunk_diameter_m``) up to base + b/2 — as
:func:`radtree.trees.envelope.crown_row_spec` lays out one crown of the hand-written row.

Leaf optics from the species, by the species library's mapping
(:func:`radtree.trees.species.species_tree`): slat reflectance and transmittance = the leaf's,
specular fraction = its direct share, slat inclination = the mean leaf tilt, and the cover
fraction solved so the crown passes the species' leaf-on permeability. The other louvers fields
(arrangement, slat size, layers/crossings, seed, realisations) are the project's (after the
scenario's switches). Crown sizes: :func:`radtree.trees.species.crown_size` of the row.

Instancing (``[site] instancing = "auto"``): trees of a species share ONE crown per
realisation — built once at the species' median size and aspect, then placed per tree
(:class:`radtree.scene.Instance`: turned by a yaw drawn from the tree id, scaled uniformly to
the tree's crown radius, moved to its trunk). Uniform scaling keeps a crown's optical depth:
λ = ρ s² G L with ρ ∝ k⁻³, s² ∝ k², L ∝ k. The crown's height is then the prototype's aspect
times its radius (the difference to the inventory's height is in the notes). A species used
by one tree only, or ``instancing = "never"``, is built in place with the row's exact sizes
and seed ``louvers.seed + 7919·i`` (i: the tree's index in the inventory), prototypes with
``louvers.seed + 104729·(j + 1)`` (j: the species' index).
"""

from __future__ import annotations

import math
import zlib
from dataclasses import replace

import numpy as np

from radtree.config import Louvers, Project, Tree
from radtree.errors import ConfigError
from radtree.optics import Plastic, Trans
from radtree.scene import Instance, Mesh
from radtree.site.inventory import InventoryTree
from radtree.trees.envelope import CrownRowSpec
from radtree.trees.geometry import polygons_to_mesh
from radtree.trees.louvers import LouverOptics, check_louvers
from radtree.trees.louvers_free import build_free_louvers
from radtree.trees.model import BARK_REFLECTANCE, TRUNK, TreeModel
from radtree.trees.species import Species, known_species, load_species, species_tree
from radtree.trees.volume import build_volume_louvers, recommended_volume_ab

TREE_SEED_STEP = 7919
PROTOTYPE_SEED_STEP = 104729


def species_of(trees: list[InventoryTree], source: str) -> dict[str, Species]:
    """The species record of every tree (by the tree id); ConfigError naming the feature and
    listing the known species otherwise."""
    out: dict[str, Species] = {}
    for t in trees:
        try:
            out[t.id] = load_species(t.species)
        except ConfigError:
            raise ConfigError(f"unknown species {t.species!r} (known: "
                              f"{', '.join(known_species())})", source=source,
                              field=f"feature {t.id!r}") from None
    return out


def species_louvers(tree: Tree, sp: Species) -> Louvers:
    """``tree``'s louvers with the species' leaf optics, slat inclination (mean leaf tilt) and
    the cover fraction that makes the crown pass the species' leaf-on permeability — the
    species library's own mapping (:func:`radtree.trees.species.species_tree`)."""
    return species_tree(tree, sp).louvers


def single_spec(centre: np.ndarray, a: float, b: float, trunk_radius: float,
                trunk_top: float) -> CrownRowSpec:
    """One free-standing crown (no wall clip plane, no neighbour strips)."""
    return CrownRowSpec(centres=np.asarray(centre, float).reshape(1, 3), a=a, b=b,
                        n_clip=-math.inf, strips=np.array([[-np.inf, np.inf]]),
                        trunk_radius=trunk_radius, trunk_top=trunk_top)


def _slats(spec: CrownRowSpec, lv: Louvers, source: str) -> list[np.ndarray]:
    build = build_volume_louvers if lv.arrangement == "volume" else build_free_louvers
    polys, _ = build(spec, lv, source)
    return polys


def yaw_of(tree_id: str) -> float:
    """A repeatable yaw (degrees) for an instanced crown, from the tree id."""
    return float(zlib.crc32(tree_id.encode()) % 3600) / 10.0


def inventory_crowns(project: Project, trees: list[InventoryTree], tree: Tree,
                     instancing: str = "auto") -> TreeModel:
    """The crowns of every inventory tree (louvers model, free form) as one TreeModel;
    ``tree``: the project's [tree] after the scenario's switches."""
    lv = tree.louvers
    source = str(project.source)
    species = species_of(trees, source)
    keys = list(dict.fromkeys(str(species[t.id].key) for t in trees))
    by_key = {k: [t for t in trees if species[t.id].key == k] for k in keys}
    default_rt = project.tree.crown.trunk_diameter_m / 2.0
    materials: dict = {TRUNK: Plastic(TRUNK, BARK_REFLECTANCE)}
    leaves: list[Mesh] = []
    prototypes: dict[str, list[Mesh]] = {}
    instances: list[Instance] = []
    trunks_v, trunks_f, off = [], [], 0
    notes: list[str] = []
    ab = 2
    index = {t.id: i for i, t in enumerate(trees)}
    for j, key in enumerate(keys):
        group = by_key[key]
        slv = species_louvers(tree, species[group[0].id])
        check_louvers(slv, source)
        mat = f"leaf_{key}"
        o = LouverOptics.of(slv)
        materials[mat] = Trans(mat, o.reflectance, o.t_diffuse, o.t_specular)
        if slv.arrangement == "volume":
            ab = max(ab, recommended_volume_ab(slv))
        else:
            ab = max(ab, slv.layers + 2)
        shared = instancing == "auto" and len(group) > 1
        if shared:
            a_ref = float(np.median([t.crown_radius_m for t in group]))
            aspect = float(np.median([t.vertical_radius_m / t.crown_radius_m for t in group]))
            b_ref = a_ref * aspect
            rt_ref = default_rt
            pspec = single_spec(np.zeros(3), a_ref, b_ref, rt_ref, -b_ref + 0.5 * b_ref)
            seed = lv.seed + PROTOTYPE_SEED_STEP * (j + 1)
            v, f = polygons_to_mesh(_slats(pspec, replace(slv, seed=seed), source))
            name = f"crown_{key}_s{lv.seed}"
            prototypes[name] = [Mesh(f"{name}_leaves", mat, v, f)]
            dz = []
            for t in group:
                k = t.crown_radius_m / a_ref
                b_eff = b_ref * k
                instances.append(Instance(name, (t.x, t.y, t.crown_base_m + b_eff),
                                          yaw_of(t.id), k))
                dz.append(t.crown_base_m + 2 * b_eff - t.height_m)
            notes.append(f"{key}: {len(group)} trees share one crown (instanced; median "
                         f"radius {a_ref:.2f} m, aspect b/a {aspect:.2f}, {len(f)} triangles); "
                         f"crown tops differ from the inventory heights by "
                         f"{min(dz):+.2f}…{max(dz):+.2f} m.")
        polys: list[np.ndarray] = []
        for t in group:
            a, b = t.crown_radius_m, t.vertical_radius_m
            if shared:
                b = (t.crown_radius_m / a_ref) * b_ref
            rt = (t.trunk_diameter_m / 2.0) if t.trunk_diameter_m else default_rt
            spec = single_spec(np.array([t.x, t.y, t.crown_base_m + b]), a, b, rt,
                               t.crown_base_m + 0.5 * b)
            if not shared:
                seed = lv.seed + TREE_SEED_STEP * index[t.id]
                polys.extend(_slats(spec, replace(slv, seed=seed), source))
            tv, tf = spec.trunks()
            trunks_v.append(tv)
            trunks_f.append(tf + off)
            off += len(tv)
        if polys:
            v, f = polygons_to_mesh(polys)
            leaves.append(Mesh(f"tree_leaves_{key}", mat, v, f))
            if not shared:
                notes.append(f"{key}: {len(group)} crown(s) built in place ({len(f)} "
                             "triangles).")
        notes.append(f"{key} leaves: " + o.describe_slat() + f"; slats {slv.slat_size_m:g} m "
                     f"at {slv.inclination_deg:g}° (species leaf tilt), permeability "
                     f"{species[group[0].id].permeability_leaf_on:g}.")
    meshes = leaves + [Mesh("tree_trunks", TRUNK, np.vstack(trunks_v), np.vstack(trunks_f))]
    notes.insert(0, f"Tree inventory: {len(trees)} trees of {len(keys)} species "
                    f"({', '.join(f'{k} {len(v)}' for k, v in by_key.items())}); "
                    f"{len(instances)} instanced from {len(prototypes)} prototype crown(s).")
    info = {"trees": float(len(trees)), "species": float(len(keys)),
            "instances": float(len(instances)), "prototypes": float(len(prototypes))}
    return TreeModel(meshes=meshes, materials=materials, notes=notes, recommended_ab=ab,
                     info=info, form="free", model="louvers", prototypes=prototypes,
                     instances=instances)
