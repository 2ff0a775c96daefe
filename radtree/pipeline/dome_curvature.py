"""The sensor dome's curvature in its crown BSDF (``tree.bsdf.curvature = "traced"``).

The dome's BSDF is computed on a planar stack of its slat shells (:mod:`radtree.trees.slab`):
same slats and spacing, but flat. In the dome the shells are concentric spheres (radii
1.6–3.82 m for the reference-case example): light scattered in a shell and travelling outwards meets
the next shell more nearly along its normal than the flat stack's next layer, and light
travelling inwards meets the inner, smaller shells ever more obliquely or misses them, so
the curved stack passes more scattered light than the flat one.

A sensor at the dome's centre sees each point of the BSDF shell along its normal: the light it
receives is the XML's row of the normal outgoing patch, f[0, j] (transmission front → back,
Klems patch 0 of the back side). This module traces that row through the explicit slats of
the curved dome from its centre (:func:`radtree.engines.numpy.transfer.trace_escapes`: paths
start on a black sphere just inside the innermost shell, along directions d of the band,
cosine-weighted about the façade normal as a façade sensor sees them; a path returning into
that sphere is light the stack reflects back, not part of the row) and bins each escape by the
Klems patch it arrives from, in the frame the shell's ``BSDF`` material applies the XML in at
d (:func:`shell_frames`; azimuth convention :func:`incident_patches`). The traced
P_j = f[0, j] Λ_j (the weight of patch j of the sky in the radiance the centre receives)
replaces the planar sample's row (``tree.bsdf.curvature = "traced"``), and the reciprocal
column of T_b is set to match (Helmholtz: T_f[o, i] = T_b[i, o]); ``"rings"`` keeps the planar
row's azimuthal shape and only rescales each Klems θ ring to the traced sum
P_r = Σ_{j ∈ r} P_j (the correction before: it misses that the curved stack passes light
arriving from above the band — from higher elevations, along the shell — up to 3–10 × the
flat stack's at grazing incidence, but light from below 0.3–3 ×). The other rows (light seen
obliquely from off-centre points, the wall's view of the shell) stay planar.

The façade: the dome stands against it, and the explicit stack's shells end in the wall plane.
The trace carries the part of the façade inside the BSDF shell (the annulus from the sink to
the dome's radius, the paint's reflectance): light the stack sends towards it comes back into
the stack, as in the explicit scene. An escape heading behind the façade plane is not sky
light (beyond the shell the façade is the BSDF scene's own surface), so it is dropped, and a
Klems patch partly behind the plane (grazing patches of the shell near the wall's rim) gets
the mean over its part in front (:func:`visible_fraction`). Before (version 1), such escapes
— light leaving the stack through its open face in the wall plane — counted as sky light.

Sectors (``tree.bsdf.sectors``): the row depends on where the shell point lies relative to
the wall's rim, not only on its elevation (in the band at the horizon, grazing light passes
1.5 × more near the rim than facing the street), so a band can be traced in sectors of the
horizontal angle from the façade normal (:func:`radtree.trees.bsdf_shell.facade_angle`), each
with its own XML.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh

from radtree.config import Project, Scenario, effective_project
from radtree.config.schema import Tree
from radtree.engines.numpy.transfer import trace_escapes
from radtree.engines.radiance.bsdf import KEYS, klems_patch_rings, wrap_flux
from radtree.errors import EngineError
from radtree.optics import KLEMS_FULL_RINGS, Plastic
from radtree.scene import Mesh, Scene
from radtree.site.frame import FacadeFrame
from radtree.trees.bsdf_shell import facade_angle
from radtree.trees.build import build_tree
from radtree.trees.envelope import dome_spec
from radtree.trees.louvers_dome import dome_layer_radii
from radtree.trees.model import TRUNK

log = logging.getLogger(__name__)

#: the sphere inside the innermost shell that ends paths coming back (reflected by the stack)
SINK = "curvature_sink"
#: the façade inside the dome's BSDF shell, traced with the slats
WALL = "curvature_wall"
#: paths traced per band: the row's sum to ≈ 0.3 % (1 σ), ≈ 2 s a band on 2 cores
CURVATURE_PATHS = 400_000
#: version of the traced row (part of the cache key): 4 — the façade inside the shell is traced
#: (its reflectance), no sky light comes from behind the façade plane (a patch partly behind
#: it keeps its front part's mean)
CURVATURE_VERSION = 4
RING_EDGES = np.array([lo for lo, _, _, _ in KLEMS_FULL_RINGS] + [90.0])
#: patches per Klems ring and the index of each ring's first patch
RING_PATCHES = np.array([n for _, _, _, n in KLEMS_FULL_RINGS])
RING_START = np.concatenate([[0], np.cumsum(RING_PATCHES)[:-1]])


@dataclass(frozen=True)
class RingRow:
    """The normal-outgoing row of a dome band, per Klems θ ring of incidence: ``weight``
    P_r = Σ_{j ∈ r} f[0, j] Λ_j (dimensionless: the share of a uniform sky's radiance in
    ring r that reaches the centre), its Monte Carlo standard error, the share of the launched
    throughput the stack sent back inwards, and the paths traced; ``patch`` / ``patch_stderr``:
    the same per Klems patch j, P_j = f[0, j] Λ_j (None: rings only)."""

    weight: np.ndarray
    stderr: np.ndarray
    reflected: float
    paths: int
    patch: np.ndarray | None = None
    patch_stderr: np.ndarray | None = None


def klems_patch(theta_deg: np.ndarray, phi_deg: np.ndarray) -> np.ndarray:
    """Klems-full patch index (0–144) of directions at polar angle θ and azimuth φ (degrees):
    the ring of θ, and in it the patch whose azimuth span (centred on k · 360°/n, k = 0 … n−1)
    holds φ."""
    ring = np.clip(np.searchsorted(RING_EDGES, theta_deg, side="right") - 1, 0,
                   len(KLEMS_FULL_RINGS) - 1)
    width = 360.0 / RING_PATCHES[ring]
    k = np.floor(((np.asarray(phi_deg) + 0.5 * width) % 360.0) / width).astype(np.int64)
    return RING_START[ring] + k % RING_PATCHES[ring]


def shell_frames(d: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The frame (x, y, z) the shell's ``BSDF`` material applies the XML in where the centre
    sees it along the unit vectors ``d`` (world axes): z the inward normal −d, y the up
    tangent (towards higher elevation above the horizon, lower below it: the lower half
    carries the XML with up −z), x = y × z (as in the planar sample, x × y = z)."""
    s = np.where(d[:, 2] >= 0.0, 1.0, -1.0)
    up = s[:, None] * np.array([0.0, 0.0, 1.0]) - (s * d[:, 2])[:, None] * d
    y = up / np.linalg.norm(up, axis=1, keepdims=True)
    z = -d
    return np.cross(y, z), y, z


def incident_patches(source_local: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(T_f column, T_b row) patch indices of light arriving at the shell from the unit
    directions ``source_local`` (towards the source, in the :func:`shell_frames` frame, on the
    outer side: z < 0): θ from −z; the T_f incident patch by the azimuth of the light's
    direction of travel (−source), the reciprocal T_b outgoing patch by that of the source
    direction itself. Established on the planar sample: its row traced with the NumPy engine
    in this convention correlates per ring with the rfluxmtx row (r 0.5–0.85 in rings 1–8);
    with y reversed the correlation turns negative (test_dome_curvature)."""
    x, y, z = source_local[:, 0], source_local[:, 1], source_local[:, 2]
    theta = np.degrees(np.arccos(np.clip(-z, -1.0, 1.0)))
    phi = np.degrees(np.arctan2(y, x))
    return klems_patch(theta, phi + 180.0), klems_patch(theta, phi)


def band_directions(n_world: np.ndarray, lo_deg: float, hi_deg: float, count: int,
                    rng: np.random.Generator,
                    sector_deg: tuple[float, float] = (-90.0, 90.0)) -> np.ndarray:
    """``count`` directions cosine-distributed about the façade normal ``n_world`` (horizontal)
    whose |elevation| lies in [lo, hi] degrees and whose horizontal angle from the normal
    (:func:`radtree.trees.bsdf_shell.facade_angle`, −90° … 90°) lies in ``sector_deg``
    (rejection sampling)."""
    n = np.asarray(n_world, float) / np.linalg.norm(n_world)
    u = np.cross([0.0, 0.0, 1.0], n)
    out: list[np.ndarray] = []
    have = 0
    while have < count:
        k = max(1024, 2 * (count - have))
        a, b = rng.random(k), rng.random(k)
        r, phi = np.sqrt(a), 2 * math.pi * b
        local = np.column_stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(1.0 - a)])
        d = local[:, :1] * u + local[:, 1:2] * np.array([0.0, 0.0, 1.0]) + local[:, 2:] * n
        el = np.degrees(np.arcsin(np.clip(np.abs(d[:, 2]), 0.0, 1.0)))
        psi = facade_angle(d, n)
        keep = d[(el >= lo_deg) & (el <= hi_deg) & (psi >= sector_deg[0])
                 & (psi <= sector_deg[1])]
        out.append(keep)
        have += len(keep)
    return np.vstack(out)[:count]


@dataclass(frozen=True)
class CurvedDome:
    """The explicit slats of a scenario's sensor dome with the sink inside them, ready to
    trace: the scene (world axes, metres), the dome's centre, the sink's radius and the façade
    normal (the sensors' axis)."""

    scene: Scene
    centre: np.ndarray
    sink_radius: float
    normal: np.ndarray


def wall_annulus(centre: np.ndarray, along: np.ndarray, r_in: float, r_out: float,
                 segments: int = 180) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and faces of the annulus r_in … r_out (m) about ``centre`` in the façade plane
    (spanned by ``along`` and world z)."""
    a = np.linspace(0.0, 2 * math.pi, segments, endpoint=False)
    ring = np.cos(a)[:, None] * np.asarray(along, float) + np.sin(a)[:, None] * [0.0, 0.0, 1.0]
    verts = np.vstack([centre + r_in * ring, centre + r_out * ring])
    k = np.arange(segments)
    k1 = (k + 1) % segments
    faces = np.vstack([np.column_stack([k, k1, segments + k]),
                       np.column_stack([k1, segments + k1, segments + k])])
    return verts, faces


def curved_dome(project: Project, scenario: Scenario, tree: Tree) -> CurvedDome:
    """Build :class:`CurvedDome` of ``scenario`` (``tree``: its tree, switches applied)."""
    project = effective_project(project, scenario)
    frame = FacadeFrame(azimuth_deg=project.street.facade_azimuth_deg)
    model = build_tree(project, scenario, frame)
    spec = dome_spec(tree, project.sensors, project.street)
    radii = dome_layer_radii(spec, tree.louvers, project.sensors)
    centre = frame.to_world(spec.centre)
    sink_r = float(radii[0] - 0.75 * tree.louvers.slat_size_m)
    if not sink_r > 0.05:
        raise EngineError(f"the dome's innermost shell (radius {radii[0]:.2f} m) leaves no room "
                          "for the curvature trace's sink inside it")
    ball = trimesh.creation.icosphere(subdivisions=4, radius=sink_r)
    meshes = [m for m in model.meshes if m.material != TRUNK]
    meshes.append(Mesh(SINK, SINK, np.asarray(ball.vertices) + centre, np.asarray(ball.faces)))
    # the façade inside the BSDF shell (the annulus from the sink to the dome's radius, its
    # paint's reflectance): light the stack sends towards it comes back into the stack; the
    # façade beyond the shell is the scene's own (escapes behind the façade plane are not sky)
    meshes.append(Mesh(WALL, WALL, *wall_annulus(centre, frame.along, sink_r, spec.radius)))
    materials = {**model.materials, SINK: Plastic(SINK, 0.0),
                 WALL: Plastic(WALL, project.street.facade_reflectance)}
    return CurvedDome(Scene(meshes, materials, {}, []), centre, sink_r, frame.normal)


def curved_ring_row(dome: CurvedDome, lo_deg: float, hi_deg: float, paths: int = 200_000,
                    seed: int = 1, workers: int = 2,
                    sector_deg: tuple[float, float] = (-90.0, 90.0)) -> RingRow:
    """Trace the normal-outgoing row of the band |elevation| ∈ [lo, hi]° (and horizontal
    angle from the façade normal in ``sector_deg``, :func:`band_directions`) through the
    dome's explicit slats, per Klems patch and per ring (see the module docstring)."""
    rng = np.random.default_rng(seed)
    d = band_directions(dome.normal, lo_deg, hi_deg, paths, rng, sector_deg)
    # start just outside the sink (its facets lie inside the sphere by < 0.3 %)
    origins = dome.centre + (dome.sink_radius + 1e-3) * d
    esc = trace_escapes(dome.scene, origins, d, seed=seed + 1, workers=workers)
    x, y, z = shell_frames(d)
    p = esc.path
    local = np.column_stack([np.einsum("ij,ij->i", esc.direction, f[p]) for f in (x, y, z)])
    front = local[:, 2] < 0
    # no sky light comes from behind the façade plane (the façade beyond the shell is the
    # BSDF scene's own; the annulus inside it returned what reached it)
    sky = front & (esc.direction @ dome.normal > 0.0)
    patch = incident_patches(local[sky])[0]
    ring, lam = klems_patch_rings()
    w, pf = esc.weight[sky], p[sky]
    per_patch, patch_stderr = binned_mean(patch, pf, w, paths, ring.size)
    # a patch partly behind the wall: its value is the mean over its part in front of it
    vis = visible_fraction(d, dome.normal, rng)
    scale = np.where(vis > 0.02, 1.0 / np.maximum(vis, 0.02), 0.0)
    per_patch, patch_stderr = per_patch * scale, patch_stderr * scale
    weight = np.bincount(ring, per_patch, minlength=len(KLEMS_FULL_RINGS))
    stderr = np.sqrt(np.bincount(ring, patch_stderr ** 2, minlength=len(KLEMS_FULL_RINGS)))
    reflected = float(esc.weight[~front].sum() / paths)
    return RingRow(weight, stderr, reflected, paths, per_patch, patch_stderr)


def patch_directions(per_patch: int, rng: np.random.Generator) -> np.ndarray:
    """``per_patch`` source directions in each Klems patch (145 × per_patch × 3, the
    :func:`shell_frames` frame, on the outer side), uniform in projected solid angle, with the
    T_f column convention of :func:`incident_patches`."""
    rows = []
    for lo, hi, _, n in KLEMS_FULL_RINGS:
        width = 360.0 / n
        for k in range(n):
            s2 = rng.uniform(math.sin(math.radians(lo)) ** 2, math.sin(math.radians(hi)) ** 2,
                             per_patch)
            theta = np.arcsin(np.sqrt(s2))
            travel = np.radians(k * width + (rng.random(per_patch) - 0.5) * width)
            src = travel - math.pi
            rows.append(np.column_stack([np.sin(theta) * np.cos(src),
                                         np.sin(theta) * np.sin(src), -np.cos(theta)]))
    return np.array(rows)


def visible_fraction(d: np.ndarray, normal: np.ndarray, rng: np.random.Generator,
                     views: int = 400, per_patch: int = 64) -> np.ndarray:
    """Per Klems patch (T_f column), the share of its projected solid angle that lies in
    front of the wall (world direction · façade ``normal`` > 0), averaged over ``views`` of
    the traced view directions ``d`` (each with its :func:`shell_frames` frame)."""
    pick = d[rng.choice(len(d), size=min(views, len(d)), replace=False)]
    x, y, z = shell_frames(pick)
    loc = patch_directions(per_patch, rng)            # (145, m, 3)
    n = np.asarray(normal, float)
    # world · n = loc_x (x·n) + loc_y (y·n) + loc_z (z·n), per view
    coef = np.column_stack([x @ n, y @ n, z @ n])      # (views, 3)
    dots = np.einsum("pmk,vk->pmv", loc, coef)
    return (dots > 0.0).mean(axis=(1, 2))


def binned_mean(bins: np.ndarray, path: np.ndarray, weight: np.ndarray, paths: int,
                size: int) -> tuple[np.ndarray, np.ndarray]:
    """Per bin, the mean over ``paths`` launched paths of each path's summed escape
    ``weight`` in that bin, and its standard error (a path may escape into a bin more than
    once: the per-path sums are the independent samples)."""
    key = bins.astype(np.int64) * paths + path
    cell, inv = np.unique(key, return_inverse=True)
    per_cell = np.bincount(inv, weight)
    mean = np.bincount(cell // paths, per_cell, minlength=size) / paths
    second = np.bincount(cell // paths, per_cell ** 2, minlength=size) / paths
    return mean, np.sqrt(np.maximum(second - mean ** 2, 0.0) / (paths - 1))


def planar_ring_row(flux_tf: np.ndarray) -> np.ndarray:
    """P_r of a planar sample's T_f flux matrix F[o, i] = f[o, i] Λ_o: Σ_{j ∈ r} f[0, j] Λ_j."""
    ring, lam = klems_patch_rings()
    f_row = flux_tf[0] / lam[0]
    return np.bincount(ring, f_row * lam, minlength=len(KLEMS_FULL_RINGS))


def reciprocal_patch() -> np.ndarray:
    """For each T_f incident patch j, the T_b outgoing patch of the reversed path (the azimuth
    turned by 180°, :func:`incident_patches`)."""
    ring, _ = klems_patch_rings()
    k = np.arange(ring.size) - RING_START[ring]
    n = RING_PATCHES[ring]
    return RING_START[ring] + (k + n // 2) % n


def curved_flux(flux: dict[str, np.ndarray], row: RingRow, per: str = "patch"
                ) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """The planar flux matrices with the normal-outgoing row of T_f replaced by the traced
    ``row`` (``per = "patch"``: patch by patch, F_tf[0, j] = P_j Λ_0 / Λ_j, and the reciprocal
    column of T_b set to match, F_tb[j', 0] = P_j, j' = :func:`reciprocal_patch`; ``"ring"``:
    the planar row and column scaled ring by ring to the traced ring sums, their azimuthal
    shape kept). Returns them and the factors per ring, traced / planar ring sum (1 where the
    planar ring is empty)."""
    ring, lam = klems_patch_rings()
    planar = planar_ring_row(flux["tf"])
    factor = np.where(planar > 0, row.weight / np.where(planar > 0, planar, 1.0), 1.0)
    out = {k: np.array(v, float) for k, v in flux.items()}
    if per == "ring":
        out["tf"][0, :] *= factor[ring]
        out["tb"][:, 0] *= factor[ring]
        return out, factor
    if per != "patch" or row.patch is None:
        raise ValueError(f"curved_flux: per = {per!r} needs 'ring', or 'patch' with a row "
                         "traced per patch")
    out["tf"][0, :] = row.patch * lam[0] / lam
    out["tb"][reciprocal_patch(), 0] = row.patch
    return out, factor


def write_curved_xml(planar_folder: Path, folder: Path, name: str, row: RingRow, *,
                     size: tuple[float, float, float], comment: str = "",
                     per: str = "patch") -> tuple[Path, np.ndarray]:
    """The planar sample's four flux matrices (``planar_folder/*.dat``) with the traced row
    (:func:`curved_flux`, ``per`` patch or ring), wrapped into ``folder/<name>.xml`` of the
    sample's ``size`` (thickness, width, height; m); returns it and the factors per ring
    (logged)."""
    flux = {k: np.loadtxt(planar_folder / f"{k}.dat", ndmin=2) for k in KEYS}
    curved, factor = curved_flux(flux, row, per)
    log.info("curvature: ring factors %s", np.array2string(factor, precision=3))
    return wrap_flux(folder, curved, name, *size, comment), factor
