"""Vectorised direction sampling for the Monte Carlo engine (all arrays (n, 3), unit vectors)."""

from __future__ import annotations

import math
from typing import Protocol

import numpy as np


class Uniform(Protocol):
    """Anything with ``random(k)`` → k uniform doubles in [0, 1) (a NumPy ``Generator``)."""

    def random(self, size: int) -> np.ndarray: ...


def orthonormal_basis(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit tangents (t, b) with (t, b, n) right-handed, for unit normals n (k, 3).

    Branch-free construction of Duff et al. (2017), stable for every direction.
    """
    nx, ny, nz = n[:, 0], n[:, 1], n[:, 2]
    sign = np.where(nz >= 0.0, 1.0, -1.0)
    a = -1.0 / (sign + nz)
    b = nx * ny * a
    t = np.stack([1.0 + sign * nx * nx * a, sign * b, -sign * nx], axis=1)
    bb = np.stack([b, sign + ny * ny * a, -ny], axis=1)
    return t, bb


def cosine_hemisphere(normals: np.ndarray, rng: Uniform) -> np.ndarray:
    """Directions distributed ∝ cos θ about each normal (pdf cos θ / π)."""
    k = len(normals)
    u1 = rng.random(k)
    u2 = rng.random(k)
    return cosine_directions(u1, u2, normals)


def cosine_directions(u1: np.ndarray, u2: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """Directions ∝ cos θ about unit ``normals`` (k, 3) from uniforms ``u1``, ``u2`` (k,)
    (sin²θ = u1, azimuth 2π u2)."""
    r = np.sqrt(u1)
    phi = 2.0 * math.pi * u2
    z = np.sqrt(np.maximum(0.0, 1.0 - u1))
    t, b = orthonormal_basis(normals)
    return t * (r * np.cos(phi))[:, None] + b * (r * np.sin(phi))[:, None] + normals * z[:, None]


def cosine_rows(normals_t: np.ndarray, rng: Uniform) -> np.ndarray:
    """:func:`cosine_hemisphere` with normals and directions as (3, k) arrays, one row per
    axis (the same draws and the same numbers, computed on long rows)."""
    k = normals_t.shape[1]
    u1 = rng.random(k)
    u2 = rng.random(k)
    r = np.sqrt(u1)
    phi = 2.0 * math.pi * u2
    z = np.sqrt(np.maximum(0.0, 1.0 - u1))
    x, y = r * np.cos(phi), r * np.sin(phi)
    nx, ny, nz = normals_t
    sign = np.where(nz >= 0.0, 1.0, -1.0)
    a = -1.0 / (sign + nz)
    b = nx * ny * a
    out = np.empty_like(normals_t)
    # t · x + b · y + n · z per axis, with Duff et al.'s tangents t and b (orthonormal_basis)
    for row, t_c, b_c in ((0, 1.0 + sign * nx * nx * a, b), (1, sign * b, sign + ny * ny * a),
                          (2, -sign * nx, -ny)):
        np.multiply(t_c, x, out=out[row])
        out[row] += b_c * y
        out[row] += normals_t[row] * z
    return out


def uniform_cone(axis: np.ndarray, half_angle_rad: float, k: int,
                 rng: Uniform) -> np.ndarray:
    """``k`` directions uniform in solid angle within a cone about one unit ``axis`` (3,)."""
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    cos_max = math.cos(half_angle_rad)
    u1 = rng.random(k)
    u2 = rng.random(k)
    cz = 1.0 - u1 * (1.0 - cos_max)
    s = np.sqrt(np.maximum(0.0, 1.0 - cz * cz))
    phi = 2.0 * math.pi * u2
    t, b = orthonormal_basis(axis[None, :])
    return (t * (s * np.cos(phi))[:, None] + b * (s * np.sin(phi))[:, None]
            + axis[None, :] * cz[:, None])


def mirror(d: np.ndarray, n: np.ndarray) -> np.ndarray:
    """Mirror reflection of directions d about normals n."""
    return d - 2.0 * np.einsum("ij,ij->i", d, n)[:, None] * n
