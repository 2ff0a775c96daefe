"""A free crown's wall cap seen from the sensors: its BSDF with a depth per Klems patch.

The chord envelope (:func:`radtree.trees.slab.chord_samples`) gives each crossing of a
sphere the half chord R cos θ: exact where a line enters the sphere. The wall cap (the
crowns' faces on the wall-side clip plane) is no part of the sphere: a line from a point S on
the cap runs t(u) inside the crown union before it leaves through a far facet P, which carries
R cos θ_P of it (its band's XML), so the cap must carry the rest,

    b(u) = t(u) − R cos θ_P(u),

which depends on where S lies: at the cap's foot point b = h cos ψ (h the centre's
distance — the ring samples before), but the sensors' window lies below the crown centre and
the row of crowns runs along the wall, so seen from the sensors the upper and sideways
directions cross far more foliage (measured on the office example: b from 0.4 to 9 m where
h cos ψ gives 0.4–3 m). The cap's XML is therefore computed for the sensors' point S
(``sensors.x_m``, ``sensors.height_m`` on the cap), patch by patch: ``b`` per incident Klems
patch (``tf``/``rf`` columns by the direction of travel into the crown, ``tb``/``rb`` by the
direction the light comes from, both in the sample frame: z into the crown, y up), a slab
depth τ = b cos θ (a planar slab of depth τ is crossed along τ / cos θ), and the columns
taken from slabs at a geometric grid of depths (one rfluxmtx system per node, shared by all
patches): the shape mixed linearly between the two nodes around τ, the transmitted total
log-linearly (extrapolated beyond the deepest node). Directions where b < one slat (the far
facet's R cos θ_P already exceeds the path, e.g. down through the crown's base) take one slat.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from radtree.config import Project, Scenario
from radtree.config.schema import Tree
from radtree.engines.radiance.bsdf import (
    KEYS,
    BsdfRun,
    FluxSettings,
    check_bsdf,
    flux_passes,
    reciprocal_rings,
    wrap_flux,
    write_system,
)
from radtree.optics import KLEMS_FULL_RINGS
from radtree.trees.envelope import CrownRowSpec, crown_row_spec, icosphere_level
from radtree.trees.slab import CELL_SLATS, RingDimensions, SlabSample, volume_slab

#: depth nodes are spaced by at most this ratio
NODE_RATIO = 1.5
#: the column mixing's version (part of the XML's cache key)
MIX_VERSION = 2
#: the deepest node, in sample cells: a periodic cell tiled much deeper than it is wide makes
#: oconv's octree of the tiles blow up (measured, 2.4 m cell: 3.7 m deep 1 s, 5.5 m deep
#: 3–10 min); deeper patches are extrapolated (exponential through the two deepest nodes)
MAX_NODE_CELLS = 1.5


@dataclass
class PatchDepthSample(RingDimensions):
    """Slabs at the depth nodes ``node_tau`` (m) and each Klems patch's slab depth for front
    (``tau_front``) and back (``tau_back``) incidence; ``thickness``: the normal half chord."""

    name: str
    rings: list[SlabSample]          # the node slabs (named as RingSamples' for the cache key)
    node_tau: np.ndarray
    tau_front: np.ndarray
    tau_back: np.ndarray
    thickness: float
    notes: list[str] = field(default_factory=list)
    info: dict[str, float] = field(default_factory=dict)

    def key_bytes(self) -> bytes:
        taus = np.concatenate([self.node_tau, self.tau_front, self.tau_back]).round(6)
        return f"mix{MIX_VERSION}".encode() + taus.tobytes()


def klems_directions() -> tuple[np.ndarray, np.ndarray]:
    """(θ, φ) in radians of the 145 Klems patch centres (ring centre, k · 360° / n)."""
    theta = np.concatenate([[c] * n for _, _, c, n in KLEMS_FULL_RINGS])
    phi = np.concatenate([np.arange(n) * 360.0 / n for *_, n in KLEMS_FULL_RINGS])
    return np.radians(theta), np.radians(phi)


def far_facets(spec: CrownRowSpec, level: int) -> tuple[np.ndarray, np.ndarray]:
    """Triangles (k, 3, 3, local frame) of the crowns' envelopes without the wall caps, and
    their outward unit normals."""
    tris, normals = [], []
    for i in range(spec.count):
        v, f, on_wall = spec.envelope(i, level)
        t = v[f[~on_wall]]
        n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
        n /= np.linalg.norm(n, axis=1)[:, None]
        flip = np.einsum("ij,ij->i", n, t.mean(axis=1) - spec.hull_point(i)) < 0
        n[flip] *= -1.0
        tris.append(t)
        normals.append(n)
    return np.concatenate(tris), np.concatenate(normals)


def exits(origin: np.ndarray, dirs: np.ndarray, tris: np.ndarray, normals: np.ndarray
          ) -> tuple[np.ndarray, np.ndarray]:
    """Distance (m) from ``origin`` along each unit direction to the first facet it leaves the
    envelope through (outward normal along the ray), and the cosine there; NaN if none."""
    e1, e2 = tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]
    s = origin - tris[:, 0]
    q = np.cross(s, e1)
    dist, cos = np.full(len(dirs), np.nan), np.full(len(dirs), np.nan)
    for k, d in enumerate(dirs):
        p = np.cross(d, e2)
        det = np.einsum("ij,ij->i", e1, p)
        ok = np.abs(det) > 1e-12
        inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
        u = np.einsum("ij,ij->i", s, p) * inv
        v = (q @ d) * inv
        t = np.einsum("ij,ij->i", e2, q) * inv
        c = normals @ d
        hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 1e-6) & (c > 0)
        if hit.any():
            j = int(np.argmin(np.where(hit, t, np.inf)))
            dist[k], cos[k] = t[j], c[j]
    return dist, cos


def cap_frame() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The cap's sample frame in the façade frame (u, n, z): z into the crown (+n), y up
    (+z, the BSDF material's up), x = y × z."""
    z, y = np.array([0.0, 1.0, 0.0]), np.array([0.0, 0.0, 1.0])
    return np.cross(y, z), y, z


def patch_depths(spec: CrownRowSpec, point: np.ndarray, far_half_chord: float, floor: float,
                 level: int) -> tuple[np.ndarray, np.ndarray]:
    """(b_front, b_back) per Klems patch (m, at least ``floor``) for a cap point ``point``
    (façade frame): front by the direction of travel into the crown, back by the direction
    the light arrives from (module text)."""
    tris, normals = far_facets(spec, level)
    theta, phi = klems_directions()
    x, y, z = cap_frame()
    out = []
    for sign in (1.0, -1.0):   # back incidence: the source is the mirrored travel direction
        d = (sign * np.sin(theta) * np.cos(phi))[:, None] * x \
            + (sign * np.sin(theta) * np.sin(phi))[:, None] * y + np.cos(theta)[:, None] * z
        dist, cos = exits(point, d, tris, normals)
        b = np.where(np.isfinite(dist), dist - far_half_chord * np.nan_to_num(cos), floor)
        out.append(np.maximum(b, floor))
    return out[0], out[1]


def depth_nodes(taus: np.ndarray, ratio: float = NODE_RATIO) -> np.ndarray:
    """A geometric grid from the smallest to the largest of ``taus`` (m), steps ≤ ``ratio``."""
    lo, hi = float(np.min(taus)), float(np.max(taus))
    if hi <= lo * 1.0001:
        return np.array([lo, lo * ratio])
    return np.geomspace(lo, hi, int(math.ceil(math.log(hi / lo) / math.log(ratio))) + 1)


def sensor_point(tree: Tree, spec: CrownRowSpec, sensors) -> np.ndarray:
    """The sensors' point on the cap (façade frame)."""
    return np.array([sensors.x_m, spec.n_clip, sensors.height_m])


def wall_cap_sample(project: Project, scenario: Scenario, tree: Tree, far_half_chord: float,
                    min_depth: float) -> PatchDepthSample:
    """The :class:`PatchDepthSample` of the wall cap seen from the sensors' point."""
    source = str(project.source)
    spec = crown_row_spec(tree, project.sensors, project.street, source)
    lv = tree.louvers
    level = icosphere_level(360.0 / tree.crown.segments)
    s = sensor_point(tree, spec, project.sensors)
    b_front, b_back = patch_depths(spec, s, far_half_chord, lv.slat_size_m, level)
    cos = np.cos(klems_directions()[0])
    tau_f, tau_b = b_front * cos, b_back * cos
    deepest = MAX_NODE_CELLS * CELL_SLATS * lv.slat_size_m
    nodes = depth_nodes(np.minimum(np.concatenate([tau_f, tau_b]), deepest))
    slabs = [volume_slab(lv, tree.crown.vertical_radius_m, max(t, min_depth), source,
                         t / max(t, min_depth), 0.0) for t in nodes]
    h = float(spec.centres[0][1] - spec.n_clip)
    notes = [f"Wall cap seen from the sensors' point (u {s[0]:g} m, z {s[2]:g} m): per Klems "
             f"patch the crown depth b = t − R cos θ_P left to the cap by the far facet "
             f"(R = {far_half_chord:.2f} m), {b_back.min():.2f}–{b_back.max():.2f} m "
             f"(h cos ψ at the foot point: up to {h:.2f} m); {len(nodes)} depth nodes "
             f"{nodes[0]:.2f}–{nodes[-1]:.2f} m."]
    info = {"sensor_u_m": float(s[0]), "sensor_z_m": float(s[2]), "nodes": float(len(nodes)),
            "b_max_m": float(max(b_front.max(), b_back.max()))}
    return PatchDepthSample("wall_cap_sensors", slabs, nodes, tau_f, tau_b, h, notes, info)


def mixed(matrices: list[np.ndarray], nodes: np.ndarray, taus: np.ndarray,
          transmission: bool) -> np.ndarray:
    """F[out, in] with column c taken at depth ``taus[c]`` from the node matrices: shape
    linear between the two nodes around it; a transmission's column total exponential in the
    depth through the two nodes' totals (extrapolated past the ends)."""
    out = np.zeros_like(matrices[0])
    for c, tau in enumerate(taus):
        j = int(np.clip(np.searchsorted(nodes, tau) - 1, 0, len(nodes) - 2))
        w = (tau - nodes[j]) / (nodes[j + 1] - nodes[j])
        a, b = matrices[j][:, c], matrices[j + 1][:, c]
        wc = min(max(w, 0.0), 1.0)
        col = (1.0 - wc) * a + wc * b
        ta, tb, tc = a.sum(), b.sum(), col.sum()
        if transmission and ta > 0 and tb > 0 and tc > 0:
            col = col * (ta * (tb / ta) ** w) / tc
        out[:, c] = col
    return out


def write_systems(folder: Path, prefix: str, slabs: list[SlabSample], tiles: int) -> list[Path]:
    """One rfluxmtx system folder per slab sample, ``folder/<prefix><k>/``; their paths."""
    subs = []
    for k, slab in enumerate(slabs):
        sub = folder / f"{prefix}{k}"
        write_system(sub, slab.polygons, slab.materials, slab.width, slab.height,
                     slab.thickness, tiles)
        subs.append(sub)
    return subs


def depth_bsdf(folder: Path, sample: PatchDepthSample, settings: FluxSettings, name: str,
               comment: str = "", progress: Callable[[str], None] | None = None) -> BsdfRun:
    """The XML of ``sample`` in ``folder/<name>.xml``: both rfluxmtx passes per node
    (``folder/node<k>/``, ``settings.nproc`` at a time), columns mixed per patch
    (:func:`mixed`), made reciprocal by ring blocks (:func:`reciprocal_rings`), wrapped."""
    t0 = time.perf_counter()
    subs = write_systems(folder, "node", sample.rings, settings.tiles)
    single = replace(settings, nproc=1)
    with ThreadPoolExecutor(max_workers=max(1, min(settings.nproc, len(subs)))) as pool:
        list(pool.map(lambda sub: flux_passes(sub, single), subs))
    flux = {}
    for key in KEYS:
        mats = [np.loadtxt(sub / f"{key}.dat", ndmin=2) for sub in subs]
        taus = sample.tau_front if key in ("tf", "rf") else sample.tau_back
        flux[key] = mixed(mats, sample.node_tau, taus, key.startswith("t"))
    xml = wrap_flux(folder, reciprocal_rings(flux), name, sample.thickness, sample.width,
                    sample.height, comment)
    return BsdfRun(xml, check_bsdf(xml), time.perf_counter() - t0)

