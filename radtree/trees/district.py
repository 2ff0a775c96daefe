"""Crowns of a tree inventory: each tree a free-standing crown built by the existing crown
models (:mod:`radtree.trees.volume`, :mod:`radtree.trees.louvers_free`) from its species
(:mod:`radtree.trees.species`) and its inventory row.

Per tree: a spheroid of horizontal semi-axis a = crown_diameter_m / 2 and vertical semi-axis
b = (height_m − crown_base_m) / 2, lowest point at crown_base_m, on a trunk (bark ρ 0.2) of
the row's ``trunk_diameter_m`` (else ``[tree.crown] trunk_diameter_m``) up to base + b/2 — as
:func:`radtree.trees.envelope.crown_row_spec` lays out one crown of the hand-written row.
A tree with a ``crown_outline`` that is not round follows it instead (the spheroid's vertical
profile scaled into the outline, :mod:`radtree.trees.outline`; built in place, never
instanced; turbid crowns stay spheroids).

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
from dataclasses import dataclass, field, replace
from functools import lru_cache

import numpy as np

from radtree.config import Louvers, Project, Tree
from radtree.errors import ConfigError
from radtree.optics import Plastic, Trans
from radtree.scene import Instance, Mesh
from radtree.site.buildings import WallContact
from radtree.site.frame import FacadeFrame
from radtree.site.inventory import InventoryTree
from radtree.trees.envelope import CrownRowSpec, clip_plane
from radtree.trees.geometry import polygons_to_mesh
from radtree.trees.louvers import LouverOptics, check_louvers
from radtree.trees.louvers_free import build_free_louvers
from radtree.trees.model import BARK_REFLECTANCE, TRUNK, TreeModel
from radtree.trees.outline import ROUND_TOLERANCE, CrownOutline, contains
from radtree.trees.species import Species, known_species, load_species, species_tree
from radtree.trees.volume import build_volume_louvers, recommended_volume_ab
from radtree.trees.wall_policy import WallReach, apply_wall_policy, two_walls

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


@lru_cache(maxsize=4096)
def tree_outline(t: InventoryTree) -> tuple[CrownOutline | None, str]:
    """The outline the crown of ``t`` follows (local frame, about its trunk), or None and why
    not: no ``crown_outline``, a round one (the spheroid, :mod:`radtree.trees.outline`), or
    a trunk outside it (the spheroid: its sections could not shrink towards the trunk).
    Cached (≈ 7 ms an outline of 75 vertices; asked for by the wall check, the instancing
    and the build)."""
    if not t.outline:
        return None, "none"
    ring = np.asarray(t.outline, float)
    if not contains(ring, x=np.array([t.x]), y=np.array([t.y]))[0]:
        return None, "trunk outside"
    out = CrownOutline.of(ring, centre=np.array([t.x, t.y]))
    if out.is_round(t.crown_radius_m):
        return None, "round"
    return out, "followed"


def crown_reach(t: InventoryTree, *, towards: np.ndarray) -> float:
    """How far the crown of ``t`` reaches from its trunk along the plan unit ``towards``
    (m): its radius, or its outline's extent when it follows one."""
    out, _ = tree_outline(t)
    return t.crown_radius_m if out is None else out.extent_towards(towards)


def outline_note(trees: list[InventoryTree]) -> str | None:
    """Which crowns follow their outlines, for the notes (None: no tree has one)."""
    why: dict[str, list[str]] = {}
    for t in trees:
        why.setdefault(tree_outline(t)[1], []).append(str(t.id))
    if set(why) <= {"none"}:
        return None
    parts = [f"{len(why.get('followed', []))} crown(s) follow their crown_outline (the "
             "spheroid's vertical profile scaled into the outline, built in place)"]
    if why.get("round"):
        parts.append(f"{len(why['round'])} outline(s) within {ROUND_TOLERANCE:.0%} of the "
                     "crown radius keep the spheroid")
    if why.get("trunk outside"):
        parts.append("the trunk lies outside the outline of " + ", ".join(why["trunk outside"])
                     + ": spheroid")
    return "Crown outlines: " + "; ".join(parts) + "."


#: a clipped inventory crown: the wall it meets and the clip plane's distance from it (m)
WallClip = tuple[WallContact, float]


def wall_clips(project: Project, trees: list[InventoryTree],
               walls: dict[str, list[WallContact]] | None, source: str
               ) -> tuple[dict[str, WallClip], list[str]]:
    """The crown–wall policy (:mod:`radtree.trees.wall_policy`) over an inventory: per tree
    whose crown reaches a wall's clip plane, the wall and the plane's distance from it, and
    the policy's notes; under ``refuse`` (or a crown reaching two walls, or a trunk at the clip
    plane) the ConfigError naming the feature and the fix."""
    n_clip = clip_plane(project.tree, project.sensors)
    rt0 = project.tree.crown.trunk_diameter_m / 2.0
    reaches, clips = [], {}
    for t in trees:
        hit = [c for c in (walls or {}).get(t.id, [])
               if crown_reach(t, towards=-np.asarray(c.normal, float)) > c.distance_m - n_clip]
        if not hit:
            continue
        where = f"feature {t.id!r}"
        if len(hit) > 1:
            raise two_walls(f"the crown of tree {t.id!r}", [c.wall for c in hit],
                            t.plan_reach_m, min(c.distance_m for c in hit) - n_clip, where,
                            source)
        c = hit[0]
        rt = (t.trunk_diameter_m / 2.0) if t.trunk_diameter_m else rt0
        if c.distance_m - n_clip <= rt:
            raise ConfigError(f"the trunk (radius {rt:g} m) stands {c.distance_m:.2f} m from "
                              f"{c.wall}, at its clip plane ({n_clip:g} m out): move the "
                              f"trunk at least {n_clip + rt - c.distance_m + 0.01:.2f} m away",
                              source=source, field=where)
        reaches.append(WallReach(f"the crown of tree {t.id!r}", c.wall,
                                 crown_reach(t, towards=-np.asarray(c.normal, float)),
                                 c.distance_m - n_clip, where,
                                 "the crown radius (crown_diameter_m / 2, or its "
                                 "crown_outline)"))
        clips[t.id] = (c, n_clip)
    return clips, apply_wall_policy(project.tree.wall_policy, reaches, source)


def _wall_frame(contact: WallContact) -> FacadeFrame:
    """The wall's frame: origin at its nearest point to the trunk, n towards the trunk."""
    nx, ny = (float(v) for v in contact.normal)
    return FacadeFrame(azimuth_deg=math.degrees(math.atan2(nx, ny)),
                       origin_x=float(contact.point[0]), origin_y=float(contact.point[1]))


def yaw_of(tree_id: str) -> float:
    """A repeatable yaw (degrees) for an instanced crown, from the tree id."""
    return float(zlib.crc32(tree_id.encode()) % 3600) / 10.0


def leaf_material(slv: Louvers, key: str, source: str) -> tuple[str, LouverOptics, Trans]:
    """A species' slat material ``leaf_<key>`` (fields checked first): (name, optics,
    material)."""
    check_louvers(slv, source)
    mat = f"leaf_{key}"
    o = LouverOptics.of(slv)
    return mat, o, Trans(mat, o.reflectance, o.t_diffuse, o.t_specular)


@dataclass
class _Crowns:
    """What :func:`inventory_crowns` gathers species by species."""

    materials: dict = field(default_factory=lambda: {TRUNK: Plastic(TRUNK, BARK_REFLECTANCE)})
    leaves: list[Mesh] = field(default_factory=list)
    prototypes: dict[str, list[Mesh]] = field(default_factory=dict)
    instances: list[Instance] = field(default_factory=list)
    trunks_v: list[np.ndarray] = field(default_factory=list)
    trunks_f: list[np.ndarray] = field(default_factory=list)
    trunk_owners: list[np.ndarray] = field(default_factory=list)  # each face's tree
    notes: list[str] = field(default_factory=list)
    ab: int = 2
    off: int = 0   # trunk vertices so far

    def add_trunk(self, tree_id: str, tv: np.ndarray, tf: np.ndarray) -> None:
        self.trunks_v.append(tv)
        self.trunks_f.append(tf + self.off)
        self.off += len(tv)
        self.trunk_owners.append(np.full(len(tf), tree_id))


def inventory_crowns(project: Project, trees: list[InventoryTree], tree: Tree, *,
                     instancing: str = "auto", clips: dict[str, WallClip] | None = None
                     ) -> TreeModel:
    """The crowns of every inventory tree (louvers model, free form) as one TreeModel;
    ``tree``: the project's [tree] after the scenario's switches. A crown in ``clips``
    (:func:`wall_clips`) is built in place in its wall's frame, cut at the clip plane."""
    source = str(project.source)
    species = species_of(trees, source)
    keys = list(dict.fromkeys(str(species[t.id].key) for t in trees))
    by_key = {k: [t for t in trees if species[t.id].key == k] for k in keys}
    index = {t.id: i for i, t in enumerate(trees)}
    acc = _Crowns()
    for j, key in enumerate(keys):
        group = by_key[key]
        _species_crowns(acc, tree, key=key, j=j, group=group, sp=species[group[0].id],
                        shared=instancing == "auto", clips=clips or {}, index=index,
                        default_rt=project.tree.crown.trunk_diameter_m / 2.0, source=source)
    meshes = acc.leaves + [Mesh("tree_trunks", TRUNK, np.vstack(acc.trunks_v),
                                np.vstack(acc.trunks_f), np.concatenate(acc.trunk_owners))]
    if (note := outline_note(trees)) is not None:
        acc.notes.insert(0, note)
    acc.notes.insert(0, f"Tree inventory: {len(trees)} trees of {len(keys)} species "
                        f"({', '.join(f'{k} {len(v)}' for k, v in by_key.items())}); "
                        f"{len(acc.instances)} instanced from {len(acc.prototypes)} prototype "
                        "crown(s).")
    info = {"trees": float(len(trees)), "species": float(len(keys)),
            "instances": float(len(acc.instances)), "prototypes": float(len(acc.prototypes))}
    return TreeModel(meshes=meshes, materials=acc.materials, notes=acc.notes,
                     recommended_ab=acc.ab, info=info, form="free", model="louvers",
                     prototypes=acc.prototypes, instances=acc.instances)


def _species_crowns(acc: _Crowns, tree: Tree, *, key: str, j: int, group: list[InventoryTree],
                    sp: Species, shared: bool, clips: dict[str, WallClip],
                    index: dict[str, int], default_rt: float, source: str) -> None:
    """The crowns and trunks of one species (``j``: its index): a shared crown for its
    unclipped trees when ``shared`` and there are several, the others built in place."""
    seed = tree.louvers.seed
    slv = species_louvers(tree, sp)
    mat, o, material = leaf_material(slv, key, source)
    acc.materials[mat] = material
    ab = recommended_volume_ab(slv) if slv.arrangement == "volume" else slv.layers + 2
    acc.ab = max(acc.ab, ab)
    free = [t for t in group if t.id not in clips and tree_outline(t)[0] is None]
    shared = shared and len(free) > 1
    ref = (_shared_crown(acc, free, replace(slv, seed=seed + PROTOTYPE_SEED_STEP * (j + 1)),
                         key=key, name=f"crown_{key}_s{seed}", mat=mat, default_rt=default_rt,
                         source=source) if shared else None)
    polys: list[np.ndarray] = []
    leaf_owners: list[np.ndarray] = []
    for t in group:
        slats, tv, tf = _one_tree(t, slv=replace(slv, seed=seed + TREE_SEED_STEP * index[t.id]),
                                  ref=ref, clip=clips.get(t.id), default_rt=default_rt,
                                  source=source)
        if slats is not None:
            polys.extend(slats)
            leaf_owners.append(np.full(sum(len(q) - 2 for q in slats if len(q) >= 3),
                                       str(t.id)))
        acc.add_trunk(str(t.id), tv, tf)
    if polys:
        v, f = polygons_to_mesh(polys)
        acc.leaves.append(Mesh(f"tree_leaves_{key}", mat, v, f, np.concatenate(leaf_owners)))
        if len(free) < len(group) or not shared:
            built = len(group) - (len(free) if shared else 0)
            acc.notes.append(f"{key}: {built} crown(s) built in place ({len(f)} triangles).")
    acc.notes.append(f"{key} leaves: " + o.describe_slat() + f"; slats {slv.slat_size_m:g} m "
                     f"at {slv.inclination_deg:g}° (species leaf tilt), permeability "
                     f"{sp.permeability_leaf_on:g}.")


def _shared_crown(acc: _Crowns, free: list[InventoryTree], slv: Louvers, *, key: str,
                  name: str, mat: str, default_rt: float, source: str) -> tuple[float, float]:
    """One prototype crown at the trees' median radius and aspect, placed per tree
    (instances scaled to each crown radius); (its semi-axes a, b in m)."""
    a_ref = float(np.median([t.crown_radius_m for t in free]))
    aspect = float(np.median([t.vertical_radius_m / t.crown_radius_m for t in free]))
    b_ref = a_ref * aspect
    pspec = single_spec(np.zeros(3), a_ref, b_ref, default_rt, -b_ref + 0.5 * b_ref)
    v, f = polygons_to_mesh(_slats(pspec, slv, source))
    acc.prototypes[name] = [Mesh(f"{name}_leaves", mat, v, f)]
    dz = []
    for t in free:
        k = t.crown_radius_m / a_ref
        b_eff = b_ref * k
        acc.instances.append(Instance(name, (t.x, t.y, t.crown_base_m + b_eff), yaw_of(t.id),
                                      k, owner=str(t.id)))
        dz.append(t.crown_base_m + 2 * b_eff - t.height_m)
    acc.notes.append(f"{key}: {len(free)} trees share one crown (instanced; median "
                     f"radius {a_ref:.2f} m, aspect b/a {aspect:.2f}, {len(f)} triangles); "
                     f"crown tops differ from the inventory heights by "
                     f"{min(dz):+.2f}…{max(dz):+.2f} m.")
    return a_ref, b_ref


def _one_tree(t: InventoryTree, *, slv: Louvers, ref: tuple[float, float] | None,
              clip: WallClip | None, default_rt: float, source: str
              ) -> tuple[list[np.ndarray] | None, np.ndarray, np.ndarray]:
    """One tree: its slats in world space (None: an instance of the shared crown ``ref``),
    its trunk's vertices and faces. A clipped crown is built in its wall's frame, cut at the
    clip plane."""
    a, b = t.crown_radius_m, t.vertical_radius_m
    outline, _ = tree_outline(t)                   # built in place when it follows one
    placed = ref is not None and clip is None and outline is None   # an instance
    if placed:
        assert ref is not None
        b = (t.crown_radius_m / ref[0]) * ref[1]
    rt = (t.trunk_diameter_m / 2.0) if t.trunk_diameter_m else default_rt
    spec = single_spec(np.array([t.x, t.y, t.crown_base_m + b]), a, b, rt,
                       t.crown_base_m + 0.5 * b)
    wf = None
    if clip is not None:                           # in the wall's frame, cut at the plane
        contact, n_clip = clip
        wf = _wall_frame(contact)
        u, n, _ = wf.to_local(np.array([t.x, t.y, 0.0]))
        spec = replace(single_spec(np.array([u, n, t.crown_base_m + b]), a, b, rt,
                                   t.crown_base_m + 0.5 * b), n_clip=n_clip)
        if outline is not None:                    # the outline in the wall's frame too
            ring = np.column_stack([outline.ring, np.zeros(len(outline.ring))])
            outline = CrownOutline.of(wf.to_local(ring)[:, :2], centre=np.array([u, n]))
    if outline is not None:
        spec = replace(spec, outline=outline)
    slats = None
    if not placed:
        slats = _slats(spec, slv, source)
        if wf is not None:
            slats = [wf.to_world(p) for p in slats]
    tv, tf = spec.trunks()
    return slats, (tv if wf is None else wf.to_world(tv)), tf
