"""Scene geometry, per-material optics and the escaping rays' environment of the in-process
engines (the NumPy backward engine and the forward light tracer share them).

:func:`scene_geometry` flattens a scene's light-interacting meshes into one triangle soup with
a material index per triangle and a cached ray caster; :func:`scene_optics` turns the materials
into coefficient arrays indexed by that material index; :class:`Environment` is the luminance
(cd/m²) an escaping ray sees (sky above, distant ground below).
"""

from __future__ import annotations

import hashlib
import threading
import weakref
from dataclasses import dataclass

import numpy as np

from radtree.engines.common.media import MediaTracer, media_bounds, media_digest, media_tracer
from radtree.engines.common.raycast import RayCaster, make_caster
from radtree.errors import EngineError
from radtree.light.sky import SkyState, sky_luminance
from radtree.optics import Glass, Hole, Plastic, Trans
from radtree.scene import Scene

GLASS_INDEX = 1.52  # Radiance's refractive index of glass


class Geometry:
    """All light-interacting triangles of a scene, with their material index and ray caster."""

    def __init__(self, scene: Scene, backend: str, workers: int):
        meshes = scene.solid_meshes()
        self.material_names = sorted({m.material for m in meshes}
                                     | set(() if scene.media is None else scene.media.materials))
        mat_index = {n: i for i, n in enumerate(self.material_names)}
        verts, faces, tri_mat, offset = [], [], [], 0
        for m in meshes:
            if m.n_triangles == 0:
                continue
            verts.append(m.vertices)
            faces.append(m.faces + offset)
            tri_mat.append(np.full(m.n_triangles, mat_index[m.material], np.int64))
            offset += len(m.vertices)
        self.vertices = np.vstack(verts) if verts else np.zeros((0, 3))
        self.faces = np.vstack(faces) if faces else np.zeros((0, 3), np.int64)
        self.tri_material = np.concatenate(tri_mat) if tri_mat else np.zeros(0, np.int64)
        # unit normal, first vertex and centroid per triangle
        self.normals, self.v0, self.centroids = triangle_frames(self.vertices, self.faces)
        # the same as (3, n) tables, one row per axis: gathered by the shadow-ray loop, whose
        # arithmetic runs on rows of all rays (contiguous) instead of 3-wide rows
        self.normals_t = np.ascontiguousarray(self.normals.T)
        self.v0_t = np.ascontiguousarray(self.v0.T)
        pts = [self.vertices] + [g.points for g in scene.grids.values()]
        allp = np.vstack(pts)
        self.size = float(np.ptp(allp, axis=0).max()) if len(allp) else 1.0
        self.caster: RayCaster = make_caster(self.vertices, self.faces, backend, workers)
        # turbid crowns (spheroids, voxel grids; radtree.engines.common.media), None without
        self.media: MediaTracer | None = media_tracer(
            scene.media, materials=scene.materials, backend=backend, workers=workers)
        if self.media is not None:
            box = media_bounds(scene.media)
            self.size = max(self.size, float(np.ptp(np.vstack([allp, box]), axis=0).max()))


def triangle_frames(vertices: np.ndarray, faces: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per triangle: unit normal (right-handed corner order; (0, 0, 1) when degenerate), first
    vertex and centroid, each (n, 3)."""
    tris = vertices[faces]
    n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]) if len(tris) else \
        np.zeros((0, 3))
    length = np.linalg.norm(n, axis=1)
    bad = length < 1e-300
    n[bad] = (0.0, 0.0, 1.0)
    length[bad] = 1.0
    centroids = tris.mean(axis=1) if len(tris) else np.zeros((0, 3))
    return n / length[:, None], np.ascontiguousarray(tris[:, 0]), centroids


_GEOMETRY_CACHE: dict[int, tuple[weakref.ref, str, Geometry]] = {}
_GEOMETRY_LOCK = threading.Lock()


def _fingerprint(scene: Scene, backend: str, workers: int) -> str:
    h = hashlib.blake2b(digest_size=16)
    h.update(f"{backend}|{workers}".encode())
    for m in scene.solid_meshes():
        h.update(f"{m.name}|{m.material}|{m.vertices.shape}|{m.faces.shape}".encode())
        h.update(np.ascontiguousarray(m.vertices).tobytes())
        h.update(np.ascontiguousarray(m.faces).tobytes())
    for g in scene.grids.values():
        h.update(np.ascontiguousarray(g.points).tobytes())
    if scene.media is not None:   # turbid crowns: their envelopes and densities
        h.update(media_digest(scene.media))
    return h.hexdigest()


def scene_geometry(scene: Scene, backend: str, workers: int) -> Geometry:
    """The scene's triangles and ray caster, cached across hours of the same scene.

    Thread-safe: the scenario runner traces several hours of one scene in parallel threads
    (they then share one ray caster; Embree queries are thread-safe).
    """
    key = id(scene)
    fp = _fingerprint(scene, backend, workers)
    with _GEOMETRY_LOCK:
        hit = _GEOMETRY_CACHE.get(key)
        if hit is not None and hit[0]() is scene and hit[1] == fp:
            return hit[2]
        geo = Geometry(scene, backend, workers)
        for k in [k for k, v in _GEOMETRY_CACHE.items() if v[0]() is None]:
            del _GEOMETRY_CACHE[k]
        _GEOMETRY_CACHE[key] = (weakref.ref(scene), fp, geo)
        return geo


@dataclass
class Optics:
    """Per-material coefficients (arrays indexed by material index)."""

    rd: np.ndarray  # diffuse reflectance
    td: np.ndarray  # diffuse transmittance
    ts: np.ndarray  # specular (undeviated) transmittance
    rm: np.ndarray  # mirror reflectance (plastic specularity)
    glass_tn: np.ndarray  # glass transmissivity (NaN = not glass)

    def per_triangle(self, material: np.ndarray) -> np.ndarray:
        """(diffuse R, diffuse T, specular T, mirror) per triangle (n, 4), from each
        triangle's material index."""
        return np.stack([self.rd, self.td, self.ts, self.rm], axis=1)[material]

    @property
    def any_specular_pass(self) -> bool:
        return bool(np.any(self.ts > 0) or np.any(np.isfinite(self.glass_tn)))


def scene_optics(scene: Scene, state: SkyState, names: list[str]) -> Optics:
    k = len(names)
    rd, td, ts, rm = np.zeros(k), np.zeros(k), np.zeros(k), np.zeros(k)
    tn = np.full(k, np.nan)
    for i, name in enumerate(names):
        m = scene.materials[name]
        if isinstance(m, Plastic):
            rho = state.ground_reflectance if name == scene.ground_material else m.reflectance
            rd[i] = rho * (1.0 - m.specularity)
            rm[i] = m.specularity
        elif isinstance(m, Trans):
            rd[i], td[i], ts[i] = m.reflectance, m.diffuse_transmittance, m.specular_transmittance
        elif isinstance(m, Glass):
            tn[i] = m.transmissivity
        elif isinstance(m, Hole):  # pragma: no cover - holes are removed with solid_meshes()
            ts[i] = 1.0
        else:  # pragma: no cover
            raise EngineError(f"material '{name}' of type {type(m).__name__} is not supported "
                              "by the in-process engines (a BSDF crown, [tree] representation"
                              " = \"bsdf\", is Radiance only: use --engine radiance)")
    return Optics(rd, td, ts, rm, tn)


def glass_coefficients(cos_i: np.ndarray, transmissivity: np.ndarray
                       ) -> tuple[np.ndarray, np.ndarray]:
    """Transmittance and reflectance of Radiance ``glass`` at incidence cosines ``cos_i``.

    Fresnel reflection (both polarisations, n = 1.52), the transmissivity applied along the
    refracted path (tn^(1/cos θ_t)) and the infinite series of internal reflections — the
    formulas of Radiance's ``m_glass``.
    """
    c = np.clip(np.abs(cos_i), 1e-6, 1.0)
    n = GLASS_INDEX
    cos2 = np.sqrt((1.0 - 1.0 / (n * n)) + c * c / (n * n))
    d = np.power(transmissivity, 1.0 / cos2)
    r1e = ((c - n * cos2) / (c + n * cos2)) ** 2
    r1m = ((1.0 / c - n / cos2) / (1.0 / c + n / cos2)) ** 2
    t = (0.5 * (1 - r1e) ** 2 * d / (1 - r1e * r1e * d * d)
         + 0.5 * (1 - r1m) ** 2 * d / (1 - r1m * r1m * d * d))
    d2 = d * d
    r = (0.5 * r1e * (1 + (1 - 2 * r1e) * d2) / (1 - r1e * r1e * d2)
         + 0.5 * r1m * (1 + (1 - 2 * r1m) * d2) / (1 - r1m * r1m * d2))
    return t, r


class Environment:
    """Luminance (cd/m²) of whatever an escaping ray sees: sky above, distant ground below."""

    def __init__(self, state: SkyState):
        self.state = state
        self.perez = None
        if state.sky_model == "perez":
            from radtree.light.perez import perez_sky

            self.perez = perez_sky(state)
        self.ground = state.ground_luminance

    def __call__(self, d: np.ndarray) -> np.ndarray:
        dz = d[:, 2]
        up = dz > 0.0
        if self.perez is not None:
            L = self.perez.luminance(d)
            return np.where(up | self.state.ground_glow, L, 0.0)
        return np.where(up, sky_luminance(self.state, dz), self.ground)
