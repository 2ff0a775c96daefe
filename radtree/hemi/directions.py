"""Photo angles -> world direction vectors (x east, y north, z up; angles in degrees).

* Upward photo: (zenith, azimuth) with azimuth clockwise from north is already a world direction:
  ``(sinθ·sinφ, sinθ·cosφ, cosθ)``.
* Horizontal-axis photo taken from a façade: (theta, psi) = (angle from the lens axis, angle
  around the axis clockwise from world-up as seen looking out). The lens axis points along the
  façade azimuth A (compass, clockwise from north; the façade's outward normal), so with
  a = (sin A, cos A, 0), u = (0, 0, 1) and r = a × u = (cos A, −sin A, 0) (the viewer's right)::

      d = cos(theta)·a + sin(theta)·(cos(psi)·u + sin(psi)·r)

  e.g. for a façade looking north (A = 0): theta = 0 is north, (90, 0) is the zenith,
  (90, 90) is east, (90, 180) is the nadir and (90, 270) is west.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray


def up_to_world(zenith: ArrayLike, azimuth: ArrayLike) -> NDArray[np.float64]:
    """Unit vectors (..., 3) of (zenith, azimuth) directions of an upward photo."""
    t = np.radians(np.asarray(zenith, dtype=np.float64))
    p = np.radians(np.asarray(azimuth, dtype=np.float64))
    return np.stack(np.broadcast_arrays(np.sin(t) * np.sin(p), np.sin(t) * np.cos(p), np.cos(t)), -1)


def _facade_frame(facade_azimuth: float) -> tuple[NDArray, NDArray, NDArray]:
    a_rad = np.radians(float(facade_azimuth))
    axis = np.array([np.sin(a_rad), np.cos(a_rad), 0.0])
    up = np.array([0.0, 0.0, 1.0])
    right = np.cross(axis, up)
    return axis, up, right


def horizontal_to_world(
    theta: ArrayLike, psi: ArrayLike, facade_azimuth: float
) -> NDArray[np.float64]:
    """World unit vectors (..., 3) of horizontal-axis photo angles (theta, psi), degrees.

    ``facade_azimuth`` is the compass direction the lens looks along (degrees clockwise from
    north), i.e. the façade's outward normal.
    """
    axis, up, right = _facade_frame(facade_azimuth)
    t = np.radians(np.asarray(theta, dtype=np.float64))[..., None]
    p = np.radians(np.asarray(psi, dtype=np.float64))[..., None]
    return np.cos(t) * axis + np.sin(t) * (np.cos(p) * up + np.sin(p) * right)


def world_to_horizontal(
    vectors: ArrayLike, facade_azimuth: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Inverse of :func:`horizontal_to_world`: (theta, psi) in degrees of world vectors."""
    v = np.asarray(vectors, dtype=np.float64)
    v = v / np.linalg.norm(v, axis=-1, keepdims=True)
    axis, up, right = _facade_frame(facade_azimuth)
    theta = np.degrees(np.arccos(np.clip(v @ axis, -1.0, 1.0)))
    psi = np.mod(np.degrees(np.arctan2(v @ right, v @ up)), 360.0)
    return theta, psi


def world_to_up(vectors: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(zenith, azimuth) in degrees of world vectors (azimuth clockwise from north)."""
    v = np.asarray(vectors, dtype=np.float64)
    v = v / np.linalg.norm(v, axis=-1, keepdims=True)
    zenith = np.degrees(np.arccos(np.clip(v[..., 2], -1.0, 1.0)))
    azimuth = np.mod(np.degrees(np.arctan2(v[..., 0], v[..., 1])), 360.0)
    return zenith, azimuth


def photo_to_world(
    zenith: ArrayLike, azimuth: ArrayLike, *, axis: str = "up", facade_azimuth: float | None = None
) -> NDArray[np.float64]:
    """World vectors of photo angles for either axis convention (see module docstring)."""
    if axis == "up":
        return up_to_world(zenith, azimuth)
    if axis == "horizontal":
        if facade_azimuth is None:
            raise ValueError("a horizontal-axis photo needs the façade azimuth")
        return horizontal_to_world(zenith, azimuth, facade_azimuth)
    raise ValueError(f"axis must be 'up' or 'horizontal', got {axis!r}")
