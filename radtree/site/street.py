"""The street canyon: studied façade, street (ground), opposite façade, and their materials.

Built in the façade frame (u along the façade, n towards the street, z up) and turned into
world coordinates. The street spans n ∈ [0, width], u ∈ [−length/2, length/2]; the studied
building's façade is the plane n = 0 up to ``building_height_m``; the opposite façade is the
plane n = width up to ``opposite_building_height_m``. Roofs are not modelled (they face the
sky only).
"""

from __future__ import annotations

import numpy as np

from radtree.config import Street
from radtree.optics import Plastic
from radtree.scene import Mesh, quad
from radtree.site.frame import FacadeFrame


def street_materials(street: Street) -> dict[str, Plastic]:
    """White façade paint, opposite façade, and the ground (its reflectance is set per hour)."""
    return {
        "facade_paint": Plastic("facade_paint", street.facade_reflectance),
        "opposite_facade": Plastic("opposite_facade", street.opposite_reflectance),
        "ground": Plastic("ground", street.ground_reflectance),
    }


def street_meshes(street: Street, frame: FacadeFrame) -> list[Mesh]:
    """Façade, ground and opposite façade of the canyon as world-space meshes."""
    L2 = street.length_m / 2.0
    W = street.width_m
    H = street.building_height_m
    Ho = street.opposite_building_height_m

    def world(name: str, material: str, corners: list[list[float]]) -> Mesh:
        return quad(name, material, frame.to_world(np.array(corners, float)))

    return [
        world("facade", "facade_paint", [[-L2, 0, 0], [L2, 0, 0], [L2, 0, H], [-L2, 0, H]]),
        world("ground", "ground", [[-L2, 0, 0], [-L2, W, 0], [L2, W, 0], [L2, 0, 0]]),
        world("opposite_facade", "opposite_facade",
              [[-L2, W, 0], [-L2, W, Ho], [L2, W, Ho], [L2, W, 0]]),
    ]


def sky_view_factor_to_street(sensor_height_m: float, street_width_m: float) -> float:
    """View factor from a vertical sensor at height h to a street of width W in front of it,
    infinitely long: F = (1 − h/√(h² + W²)) / 2 (0.5 for an unbounded ground)."""
    h, w = sensor_height_m, street_width_m
    return float((1.0 - h / np.hypot(h, w)) / 2.0)
