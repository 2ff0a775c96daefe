"""The façade frame: a local coordinate system attached to the studied façade.

Local axes: u along the façade (to the right when looking at it from the street), n the
façade's outward normal (towards the street), z up. The façade plane is n = 0, the street
surface z = 0. ``azimuth_deg`` is the compass direction of n (0 = the façade looks north).
With azimuth 0, u = +x (east), n = +y (north). World axes: x east, y north, z up.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class FacadeFrame:
    azimuth_deg: float = 0.0
    origin_x: float = 0.0
    origin_y: float = 0.0

    @property
    def normal(self) -> np.ndarray:
        a = math.radians(self.azimuth_deg)
        return np.array([math.sin(a), math.cos(a), 0.0])

    @property
    def along(self) -> np.ndarray:
        a = math.radians(self.azimuth_deg)
        return np.array([math.cos(a), -math.sin(a), 0.0])

    @property
    def matrix(self) -> np.ndarray:
        """3×3 matrix whose columns are u, n, z in world coordinates."""
        return np.column_stack([self.along, self.normal, [0.0, 0.0, 1.0]])

    def to_world(self, local: np.ndarray) -> np.ndarray:
        """Points (…, 3) in (u, n, z) → world (x, y, z)."""
        local = np.asarray(local, float)
        return local @ self.matrix.T + np.array([self.origin_x, self.origin_y, 0.0])

    def directions_to_world(self, local: np.ndarray) -> np.ndarray:
        return np.asarray(local, float) @ self.matrix.T

    def to_local(self, world: np.ndarray) -> np.ndarray:
        world = np.asarray(world, float) - np.array([self.origin_x, self.origin_y, 0.0])
        return world @ self.matrix
