"""The "floating spheres" scene of the physics suite, after RAMI's HET01 (discrete floating
spheres) scaled by 1/10, and the numerical integral of its uncollided transmission.

RAMI HET01 (https://rami-benchmark.jrc.ec.europa.eu, RAMI-2/3 "Floating Spheres — Discrete"):
a 100 m × 100 m scene, 15 non-overlapping spheres of radius 10 m with centres 11–19 m above the
soil, LAI of an individual sphere 5.0 (leaf area / π R²), uniformly oriented (spherical) disc
leaves of radius 0.1 m. Scaled by 1/10 here: a 10 m × 10 m scene, spheres of radius 1 m with
centres 1.1–1.9 m high, LAI 5 per sphere, square leaves (the suite's leaf shape) of side 0.05 m
— placed at random (seeded) since the benchmark's own positions are not reproduced here.

A sphere of radius R holding one-sided leaf area LAI·π R² has the leaf area density
u = LAI·π R² / (4/3 π R³) = 3·LAI / (4 R) (m²/m³); along a direction of zenith θ a line of
chord lengths ℓ_i through the spheres is left uncollided with probability
exp(−G·u·Σ ℓ_i) (G = 0.5 for spherical leaves, Poisson-placed leaf centres). The expected
transmission over a detector square is that probability averaged over the square
(:func:`sphere_transmission`, a fine midpoint grid), and the check compares it with what the
engines tally there.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from radtree.engines.numpy.scenes import squares
from radtree.scene import Mesh
from radtree.verify.leaves import sample_inclinations

SCENE_M = 10.0       # scene side (m): RAMI's 100 m / 10
SPHERES = 15
RADIUS_M = 1.0       # RAMI's 10 m / 10
HEIGHTS_M = (1.1, 1.9)
SPHERE_LAI = 5.0
LEAF_M = 0.05


@dataclass(frozen=True)
class Spheres:
    """Sphere centres (k, 3) (m), their common radius (m) and leaf area density (m²/m³)."""

    centres: np.ndarray
    radius: float
    density: float


def place_spheres(rng: np.random.Generator, count: int = SPHERES, radius: float = RADIUS_M,
                  extent: float = SCENE_M, heights: tuple[float, float] = HEIGHTS_M,
                  lai: float = SPHERE_LAI) -> Spheres:
    """``count`` non-overlapping spheres (rejection sampling) with centres inside the scene
    square (side ``extent``, centred on the origin) at heights in ``heights``."""
    out: list[np.ndarray] = []
    half = extent / 2.0 - radius
    for _ in range(100_000):
        c = np.array([*rng.uniform(-half, half, 2), rng.uniform(*heights)])
        if all(np.linalg.norm(c - o) >= 2.0 * radius for o in out):
            out.append(c)
            if len(out) == count:
                return Spheres(np.array(out), radius, 3.0 * lai / (4.0 * radius))
    raise ValueError(f"cannot place {count} spheres of radius {radius} m in {extent} m")


def sphere_leaves(name: str, material: str, spheres: Spheres, rng: np.random.Generator,
                  size: float = LEAF_M) -> Mesh:
    """Square leaves of side ``size`` (m), centres Poisson-placed uniformly in every sphere,
    spherical leaf-angle distribution, random azimuths and spins."""
    r = spheres.radius
    per = spheres.density * 4.0 / 3.0 * math.pi * r ** 3 / (size * size)
    cs = []
    for c in spheres.centres:
        k = int(rng.poisson(per))
        d = rng.normal(size=(k, 3))
        d /= np.linalg.norm(d, axis=1)[:, None]
        cs.append(c + d * (r * rng.random(k) ** (1.0 / 3.0))[:, None])
    centres = np.vstack(cs)
    k = len(centres)
    inc = sample_inclinations("spherical", k, rng)
    az = rng.uniform(0.0, 2.0 * math.pi, k)
    normals = np.column_stack([np.sin(inc) * np.cos(az), np.sin(inc) * np.sin(az), np.cos(inc)])
    v, f = squares(centres, normals, size, rng.uniform(0, 2 * math.pi, k))
    return Mesh(name, material, v, f)


def optical_depth(points: np.ndarray, sun: np.ndarray, spheres: Spheres,
                  g: float = 0.5) -> np.ndarray:
    """G·u·Σ chord lengths (m) through the spheres of the rays from ``points`` (k, 3) towards
    the unit vector ``sun``."""
    rel = spheres.centres[None, :, :] - points[:, None, :]          # (k, s, 3)
    along = rel @ sun                                                # (k, s)
    d2 = np.einsum("ksi,ksi->ks", rel, rel) - along ** 2
    chord = 2.0 * np.sqrt(np.maximum(spheres.radius ** 2 - d2, 0.0))
    chord = np.where(along > 0.0, chord, 0.0)   # spheres behind the point cast no shadow
    return g * spheres.density * chord.sum(axis=1)


def sphere_transmission(centres: np.ndarray, side: float, sun: np.ndarray, spheres: Spheres,
                        n: int = 40) -> np.ndarray:
    """Expected uncollided transmission averaged over each horizontal square of side ``side``
    (m) centred at ``centres`` (k, 3): an n × n midpoint grid of exp(−optical depth)."""
    off = (np.arange(n) + 0.5) / n * side - side / 2.0
    X, Y = np.meshgrid(off, off)
    grid = np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)])
    return np.array([np.exp(-optical_depth(c + grid, sun, spheres)).mean() for c in centres])
