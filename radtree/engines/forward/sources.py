"""Where the forward engine's photons start: the sun as a collimated source (over the whole
scene or as a beam aimed at a target), and the sky and distant ground glow.

* **Sun, whole scene**: a launch disc perpendicular to the sun, of the radius of the scene's
  bounding sphere, outside that sphere: flux E_dn · π R² (lm, E_dn the direct normal
  illuminance in lux), photon origins uniform on the disc, all travelling along −sun.
* **Sun beam**: the same disc with the stated diameter, its axis through the target point.
* **Environment** (sky above the horizon, the distant ground glow below — the luminance the
  NumPy engine's escaping rays see, :class:`radtree.engines.common.geometry.Environment`): a
  direction ω is drawn from a table of the luminance over the whole sphere (equal solid-angle
  cells, ∝ L·Ω) and a photon starts on the disc of radius R perpendicular to ω outside the
  bounding sphere, travelling along −ω; flux through the disc from dω is L(ω) dω · π R², so
  the total is π R² ∫ L dω and a photon's flux is corrected by L(ω) / L(cell).
* **Rings** (the stratified launch of :mod:`radtree.engines.forward.strata`): start points
  uniform in an annulus a ≤ ρ < b of the launch plane around the *focus*, where the line
  through a target point along the photon's direction crosses that plane; flux per photon
  = (flux per m² of launch plane) × π (b² − a²) / photons. Rings out to R + |target − centre|
  cover the whole launch disc.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from radtree.engines.common.sampling import orthonormal_basis

_ENV_ZONES = (48, 96)  # cells in z (uniform in cos θ) and in azimuth: equal solid angles


@dataclass(frozen=True)
class Sphere:
    """Bounding sphere (m) of everything photons can meet, detectors included."""

    centre: np.ndarray
    radius: float


def bounding_sphere(points: np.ndarray) -> Sphere:
    """Box-centred bounding sphere of ``points`` (k, 3), with a 1 % (≥ 1 cm) margin."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    c = (lo + hi) / 2.0
    r = float(np.linalg.norm(points - c, axis=1).max())
    return Sphere(c, max(r * 1.01, r + 0.01))


@dataclass
class Launch:
    """Photons ready to start: origins, unit directions of travel, flux each (lm)."""

    origins: np.ndarray
    dirs: np.ndarray
    flux: np.ndarray


def _disc_points(centres: np.ndarray, normals: np.ndarray, radius: float,
                 rng: np.random.Generator) -> np.ndarray:
    k = len(centres)
    r = radius * np.sqrt(rng.random(k))
    phi = 2.0 * math.pi * rng.random(k)
    t, b = orthonormal_basis(normals)
    return centres + t * (r * np.cos(phi))[:, None] + b * (r * np.sin(phi))[:, None]


def _ring_points(foci: np.ndarray, normals: np.ndarray, a: float, b: float,
                 rng: np.random.Generator) -> np.ndarray:
    """Points uniform in the annuli a ≤ ρ < b (m) around ``foci`` in the planes of unit
    ``normals``."""
    k = len(foci)
    r = np.sqrt(a * a + rng.random(k) * (b * b - a * a))
    phi = 2.0 * math.pi * rng.random(k)
    t, bb = orthonormal_basis(normals)
    return foci + t * (r * np.cos(phi))[:, None] + bb * (r * np.sin(phi))[:, None]


def _foci(target: np.ndarray, centres: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """Where the lines through ``target`` along ``normals`` cross the planes through
    ``centres`` perpendicular to them."""
    return target + normals * np.einsum("ij,ij->i", centres - target, normals)[:, None]


class SunSource:
    """The collimated sun: direction ``sun`` (unit, towards the sun), direct normal
    illuminance ``dni`` (lux), a disc of ``radius`` (m) whose axis passes through ``axis_point``,
    placed ``distance`` (m) from it towards the sun."""

    def __init__(self, sun: np.ndarray, dni: float, axis_point: np.ndarray, radius: float,
                 distance: float):
        self.sun = np.asarray(sun, float) / np.linalg.norm(sun)
        self.axis_point = np.asarray(axis_point, float)
        self.radius = float(radius)
        self.centre = self.axis_point + self.sun * float(distance)
        self.density = float(dni)  # lm per m² of launch plane
        self.flux = self.density * math.pi * self.radius ** 2

    def launch(self, k: int, photon_flux: float, rng: np.random.Generator) -> Launch:
        normals = np.broadcast_to(self.sun, (k, 3))
        o = _disc_points(np.broadcast_to(self.centre, (k, 3)), normals, self.radius, rng)
        return Launch(o, np.broadcast_to(-self.sun, (k, 3)).copy(), np.full(k, photon_flux))

    def ring_launch(self, k: int, a: float, b: float, target: np.ndarray,
                    rng: np.random.Generator) -> Launch:
        """``k`` photons starting uniformly in the ring a ≤ ρ < b (m) around ``target``'s
        focus, each carrying an equal share of the ring's flux (lm)."""
        normals = np.broadcast_to(self.sun, (k, 3))
        foci = _foci(target, np.broadcast_to(self.centre, (k, 3)), normals)
        o = _ring_points(foci, normals, a, b, rng)
        share = self.density * math.pi * (b * b - a * a) / k
        return Launch(o, np.broadcast_to(-self.sun, (k, 3)).copy(), np.full(k, share))

    def distance_to_axis(self, points: np.ndarray) -> np.ndarray:
        """Perpendicular distance (m) of ``points`` from the beam axis."""
        rel = points - self.axis_point
        return np.linalg.norm(rel - np.outer(rel @ self.sun, self.sun), axis=1)


class EnvironmentSource:
    """Sky and ground glow of luminance ``luminance(d)`` (cd/m², d unit directions towards
    the source) around a bounding ``sphere``."""

    def __init__(self, luminance, sphere: Sphere):
        nz, nphi = _ENV_ZONES
        self.nz, self.nphi = nz, nphi
        self.sphere = sphere
        zc = -1.0 + (np.arange(nz) + 0.5) * 2.0 / nz
        pc = (np.arange(nphi) + 0.5) * 2.0 * math.pi / nphi
        Z, P = np.meshgrid(zc, pc, indexing="ij")
        s = np.sqrt(1.0 - Z * Z)
        d = np.column_stack([(s * np.cos(P)).ravel(), (s * np.sin(P)).ravel(), Z.ravel()])
        self.luminance = luminance
        self.cell_dirs = d   # (cells, 3) unit directions of the cell centres
        self.cell_l = np.maximum(np.asarray(luminance(d), float), 0.0)
        self.omega = 4.0 * math.pi / (nz * nphi)
        total = float(self.cell_l.sum())
        self.area = math.pi * sphere.radius ** 2
        self.density = total * self.omega  # lm per m² of launch plane, all directions
        self.flux = self.area * self.density
        self.cdf = np.cumsum(self.cell_l) / total if total > 0 else None

    def draw_cells(self, cdf: np.ndarray, k: int, rng: np.random.Generator
                   ) -> tuple[np.ndarray, np.ndarray]:
        """``k`` (unit directions, cells): cells of the table drawn by the cumulative
        distribution ``cdf`` over them, each direction uniform within its cell."""
        cell = np.minimum(np.searchsorted(cdf, rng.random(k), side="right"), len(cdf) - 1)
        iz, ip = cell // self.nphi, cell % self.nphi
        z = -1.0 + (iz + rng.random(k)) * 2.0 / self.nz
        phi = (ip + rng.random(k)) * 2.0 * math.pi / self.nphi
        s = np.sqrt(np.maximum(0.0, 1.0 - z * z))
        return np.column_stack([s * np.cos(phi), s * np.sin(phi), z]), cell

    def cell_of(self, w: np.ndarray) -> np.ndarray:
        """The table's cell holding each unit direction ``w`` (k, 3)."""
        iz = np.clip(((w[:, 2] + 1.0) * 0.5 * self.nz).astype(np.int64), 0, self.nz - 1)
        phi = np.mod(np.arctan2(w[:, 1], w[:, 0]), 2.0 * math.pi)
        ip = np.clip((phi / (2.0 * math.pi) * self.nphi).astype(np.int64), 0, self.nphi - 1)
        return iz * self.nphi + ip

    def _directions(self, k: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        """``k`` unit directions towards the source drawn ∝ L·Ω, and each one's flux
        correction L(ω) / L(cell)."""
        assert self.cdf is not None
        w, cell = self.draw_cells(self.cdf, k, rng)
        return w, np.asarray(self.luminance(w), float) / self.cell_l[cell]

    def launch(self, k: int, photon_flux: float, rng: np.random.Generator) -> Launch:
        w, ratio = self._directions(k, rng)
        centres = self.sphere.centre + w * (self.sphere.radius + 1.0)
        o = _disc_points(centres, w, self.sphere.radius, rng)
        return Launch(o, -w, photon_flux * ratio)

    def ring_launch(self, k: int, a: float, b: float, target: np.ndarray,
                    rng: np.random.Generator) -> Launch:
        """As :meth:`SunSource.ring_launch`, each photon's direction drawn from the sky."""
        w, ratio = self._directions(k, rng)
        centres = self.sphere.centre + w * (self.sphere.radius + 1.0)
        o = _ring_points(_foci(target, centres, w), w, a, b, rng)
        share = self.density * math.pi * (b * b - a * a) / k
        return Launch(o, -w, share * ratio)
