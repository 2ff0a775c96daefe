"""The leaf-off crown: a sparse opaque branch structure inside the same crown envelope.

A deciduous crown without leaves is its wood: trunk, scaffold branches and finer orders of
branches. This module grows that structure inside the envelope of the free-standing crowns
(:class:`radtree.trees.envelope.CrownRowSpec`, the same spheroids, wall-side clip plane and
shares of the row the leafed crowns use), so that the leaf-on and leaf-off scenes differ only
by the foliage.

Growth rule (deterministic for a seed):

* a **leader** continues the trunk from its top (``trunk_top``) up to ``leader_fraction`` of
  the way to the crown top, diameter ``leader_diameter_ratio`` × trunk diameter;
* ``primaries`` **scaffold branches** leave the trunk top and the leader at heights spread
  evenly over its lower part, at azimuths following the golden angle (± ``jitter``), each
  climbing at the **branch inclination** (reference case §1: peripheral branches ≈ 40° from
  horizontal; ± ``inclination_jitter_deg``);
* every branch segment covers ``reach`` of the distance left to the envelope along its
  direction, then **forks** into ``fork`` children spread ``azimuth_spread_deg`` apart in
  azimuth, each again at ≈ 40°; a branch of the last order (``orders``) runs on to the
  envelope (stopping ``tip_clearance_m`` short of it);
* diameters follow the pipe model (Leonardo's rule): a fork's children have diameter
  d/√fork, from ``base_diameter_m`` for the scaffold branches;
* every segment is an opaque prism of ``sides`` faces (bark, reflectance 0.2).

Twigs thinner than the last order are not modelled, so the bare crown built here is on the
open side of a real leafless street tree (the notes give its vertical cover so the reader
can judge). The structure is plain data (:class:`BranchParams`) so it can be calibrated
against a measured winter permeability.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from radtree.config import Project, Scenario
from radtree.optics import Plastic
from radtree.scene import Mesh
from radtree.site.frame import FacadeFrame
from radtree.trees.build import apply_switches
from radtree.trees.envelope import CrownRowSpec, crown_row_spec
from radtree.trees.model import BARK_REFLECTANCE, TRUNK

GOLDEN_ANGLE_DEG = 137.50776405
BRANCH_MESH = "tree_branches"


@dataclass(frozen=True)
class BranchParams:
    """Parameters of the leaf-off branch structure (see the module text)."""

    inclination_deg: float = 40.0
    inclination_jitter_deg: float = 8.0
    primaries: int = 10
    orders: int = 5
    fork: int = 2
    reach: float = 0.5
    azimuth_spread_deg: float = 50.0
    jitter_deg: float = 15.0
    base_diameter_m: float = 0.16
    leader_fraction: float = 0.8
    leader_diameter_ratio: float = 0.6
    tip_clearance_m: float = 0.1
    min_length_m: float = 0.15
    sides: int = 6
    seed: int = 1

    def __post_init__(self) -> None:
        if not 0.0 <= self.inclination_deg < 90.0:
            raise ValueError(f"branch inclination must be in [0, 90), got {self.inclination_deg}")
        if self.primaries < 1 or self.orders < 1 or self.fork < 1:
            raise ValueError("primaries, orders and fork must be ≥ 1")
        if not 0.0 < self.reach < 1.0:
            raise ValueError(f"reach must be in (0, 1), got {self.reach}")
        if self.sides < 3:
            raise ValueError("a branch prism needs at least 3 sides")
        if self.base_diameter_m <= 0:
            raise ValueError("base_diameter_m must be > 0")


@dataclass
class BranchSegment:
    start: np.ndarray  # local (u, n, z)
    end: np.ndarray
    diameter: float
    order: int  # 0 = leader, 1 = scaffold, 2… = finer orders


def _distance_to_envelope(spec: CrownRowSpec, i: int, p: np.ndarray, d: np.ndarray) -> float:
    """Distance from an interior point ``p`` along unit ``d`` to crown i's clipped envelope."""
    c = spec.centres[i]
    w = p - c
    A = (d[0] ** 2 + d[1] ** 2) / spec.a**2 + d[2] ** 2 / spec.b**2
    B = 2.0 * ((w[0] * d[0] + w[1] * d[1]) / spec.a**2 + w[2] * d[2] / spec.b**2)
    C = (w[0] ** 2 + w[1] ** 2) / spec.a**2 + w[2] ** 2 / spec.b**2 - 1.0
    disc = B * B - 4.0 * A * C
    t = (-B + math.sqrt(max(disc, 0.0))) / (2.0 * A)
    if d[1] < -1e-12:
        t = min(t, (spec.n_clip - p[1]) / d[1])
    lo, hi = spec.strips[i]
    if d[0] < -1e-12 and np.isfinite(lo):
        t = min(t, (lo - p[0]) / d[0])
    if d[0] > 1e-12 and np.isfinite(hi):
        t = min(t, (hi - p[0]) / d[0])
    return max(t, 0.0)


def _direction(azimuth_deg: float, inclination_deg: float) -> np.ndarray:
    a, e = math.radians(azimuth_deg), math.radians(inclination_deg)
    return np.array([math.cos(e) * math.cos(a), math.cos(e) * math.sin(a), math.sin(e)])


def grow_branches(spec: CrownRowSpec, params: BranchParams, trunk_diameter_m: float
                  ) -> list[BranchSegment]:
    """All branch segments of every crown of the row (local façade-frame coordinates)."""
    segments: list[BranchSegment] = []
    ss = np.random.SeedSequence(params.seed)
    for i, child in enumerate(ss.spawn(spec.count)):
        rng = np.random.default_rng(child)
        c = spec.centres[i]
        base = np.array([c[0], c[1], spec.trunk_top])
        top = c[2] + spec.b
        leader_end = np.array([c[0], c[1], spec.trunk_top
                               + params.leader_fraction * (top - spec.trunk_top)])
        if spec.inside(leader_end[None])[0] and leader_end[2] > base[2] + params.min_length_m:
            segments.append(BranchSegment(base, leader_end,
                                          params.leader_diameter_ratio * trunk_diameter_m, 0))
        else:
            leader_end = base
        phase = rng.uniform(0.0, 360.0)
        stack = []
        for k in range(params.primaries):
            f = k / max(params.primaries - 1, 1)
            start = base + (leader_end - base) * 0.5 * f
            az = phase + k * GOLDEN_ANGLE_DEG + rng.uniform(-1, 1) * params.jitter_deg
            stack.append((start, az, 1, params.base_diameter_m))
        while stack:
            start, az, order, diam = stack.pop()
            inc = params.inclination_deg + rng.uniform(-1, 1) * params.inclination_jitter_deg
            d = _direction(az, inc)
            room = _distance_to_envelope(spec, i, start, d) - params.tip_clearance_m
            if room < params.min_length_m:
                continue
            last = order >= params.orders
            length = room if last else params.reach * room
            if length < params.min_length_m:
                length = room
                last = True
            end = start + length * d
            segments.append(BranchSegment(start, end, diam, order))
            if last:
                continue
            n = params.fork
            for j in range(n):
                off = (j - (n - 1) / 2.0) * (params.azimuth_spread_deg / max(n - 1, 1))
                child_az = az + off + rng.uniform(-1, 1) * params.jitter_deg
                stack.append((end, child_az, order + 1, diam / math.sqrt(n)))
    return segments


def prism_mesh(segments: list[BranchSegment], sides: int) -> tuple[np.ndarray, np.ndarray]:
    """Segments as open prisms (``sides`` quads each, as triangles): vertices, faces."""
    verts, faces = [], []
    offset = 0
    phi = 2.0 * np.pi * np.arange(sides) / sides
    for s in segments:
        axis = s.end - s.start
        L = np.linalg.norm(axis)
        if L <= 1e-9:
            continue
        a = axis / L
        ref = np.array([0.0, 0.0, 1.0]) if abs(a[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
        e1 = np.cross(a, ref)
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(a, e1)
        r = 0.5 * s.diameter
        ring = r * (np.cos(phi)[:, None] * e1 + np.sin(phi)[:, None] * e2)
        verts.append(np.vstack([s.start + ring, s.end + ring]))
        i = np.arange(sides)
        j = (i + 1) % sides
        f = np.concatenate([np.column_stack([i, j, j + sides]),
                            np.column_stack([i, j + sides, i + sides])]) + offset
        faces.append(f)
        offset += 2 * sides
    if not verts:
        return np.zeros((0, 3)), np.zeros((0, 3), np.int64)
    return np.vstack(verts), np.vstack(faces).astype(np.int64)


def vertical_cover(spec: CrownRowSpec, segments: list[BranchSegment], spacing: float = 0.08
                   ) -> float:
    """Fraction of the crowns' plan area covered by branches seen from straight above."""
    if not segments:
        return 0.0
    covered = total = 0
    for i, c in enumerate(spec.centres):
        g = np.arange(-spec.a, spec.a + spacing, spacing)
        U, N = np.meshgrid(c[0] + g, c[1] + g, indexing="ij")
        P = np.column_stack([U.ravel(), N.ravel()])
        lo, hi = spec.strips[i]
        keep = (((P[:, 0] - c[0]) ** 2 + (P[:, 1] - c[1]) ** 2 <= spec.a**2)
                & (P[:, 1] >= spec.n_clip) & (P[:, 0] >= lo) & (P[:, 0] <= hi))
        P = P[keep]
        hit = np.zeros(len(P), bool)
        for s in segments:
            a2, b2 = s.start[:2], s.end[:2]
            ab = b2 - a2
            den = float(ab @ ab)
            t = np.zeros(len(P)) if den < 1e-12 else np.clip((P - a2) @ ab / den, 0.0, 1.0)
            dist = np.linalg.norm(P - (a2 + t[:, None] * ab), axis=1)
            hit |= dist <= 0.5 * s.diameter
        covered += int(hit.sum())
        total += len(P)
    return covered / max(total, 1)


@dataclass
class LeafOffCrown:
    """World-space meshes of the bare crowns (trunks + branches), materials and notes."""

    meshes: list[Mesh]
    materials: dict[str, Plastic]
    notes: list[str]
    info: dict[str, float]


def build_leaf_off(project: Project, scenario: Scenario, frame: FacadeFrame,
                   params: BranchParams | None = None) -> LeafOffCrown:
    """The bare crowns of ``scenario``'s tree (its crown switches applied).

    Always built on the free-standing crown envelope ``[tree.crown]``: for the study's sensor
    dome (a lens around the sensors, not a tree) the bare tree is the physical crown row.
    """
    params = params or BranchParams()
    tree, _ = apply_switches(project.tree, scenario.switches, source=str(project.source),
                             root=project.root)
    spec = crown_row_spec(tree, project.sensors, project.street, str(project.source))
    segments = grow_branches(spec, params, tree.crown.trunk_diameter_m)
    bv, bf = prism_mesh(segments, params.sides)
    tv, tf = spec.trunks()
    meshes = [Mesh("tree_trunks", TRUNK, frame.to_world(tv), tf),
              Mesh(BRANCH_MESH, TRUNK, frame.to_world(bv), bf)]
    cover = vertical_cover(spec, segments)
    form = scenario.form or tree.form
    notes = [
        f"Leaf-off crown: {len(segments)} opaque branch segments (bark ρ "
        f"{BARK_REFLECTANCE:g}) in {spec.count} crown envelope(s): a leader, "
        f"{params.primaries} scaffold branches per crown at {params.inclination_deg:g}° "
        f"(± {params.inclination_jitter_deg:g}°) from horizontal, {params.orders} orders "
        f"forking in {params.fork}, diameters {params.base_diameter_m * 100:.0f} cm → "
        f"{params.base_diameter_m / math.sqrt(params.fork) ** (params.orders - 1) * 100:.1f} cm "
        "(pipe model); twigs finer than that are not modelled.",
        f"Vertical cover of the bare crowns (plan view): {100 * cover:.1f} % "
        f"(gap fraction {100 * (1 - cover):.1f} %).",
    ]
    if form == "dome":
        notes.append("The leafed crown is the study's sensor dome; the bare tree is built on "
                     "the free-standing crown envelope [tree.crown] (a dome is no tree).")
    info = {"branch_segments": float(len(segments)), "branch_vertical_cover": cover,
            "branch_triangles": float(len(bf)),
            "branch_inclination_deg": params.inclination_deg}
    return LeafOffCrown(meshes, {TRUNK: Plastic(TRUNK, BARK_REFLECTANCE)}, notes, info)
