"""Sensor grids on the façade: the study's 8-point circle and a dense grid around it.

Points sit ``offset_m`` off the wall, normals point out of the wall (towards the street).
With several heights (``[sensors] heights_m``, one per storey) each height has its own circle
and map, named ``facade@<h>m`` / ``facade_map@<h>m`` (:func:`level_name`), every sensor
labelled with its ``storey`` (the height's index in the list); one height keeps the plain
names ``facade`` / ``facade_map`` and no label (:func:`street_grids`).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from radtree.config import Sensors
from radtree.scene import SensorGrid
from radtree.site.frame import FacadeFrame


def row_label(dz: float, radius: float) -> str:
    """Row of a sensor by its height above the circle's centre: upper, middle, lower third."""
    if dz > radius / 3.0 + 1e-9:
        return "higher"
    if dz < -radius / 3.0 - 1e-9:
        return "lower"
    return "intermediate"


def facade_circle(sensors: Sensors, frame: FacadeFrame, name: str = "facade") -> SensorGrid:
    """``count`` sensors at equal angle steps on a circle in the façade plane.

    With 8 sensors at 45° steps starting at 0° (to the right), three are higher, two
    intermediate (left and right) and three lower, as in the study.
    """
    angles = np.arange(sensors.count) * 2.0 * math.pi / sensors.count
    u = sensors.x_m + sensors.radius_m * np.cos(angles)
    z = sensors.height_m + sensors.radius_m * np.sin(angles)
    local = np.column_stack([u, np.full_like(u, sensors.offset_m), z])
    rows = [row_label(dz, sensors.radius_m) for dz in z - sensors.height_m]
    normals = np.tile(frame.normal, (len(u), 1))
    return SensorGrid(name, frame.to_world(local), normals, rows)


#: the dense façade map grid (a figure: ``engine.dense_lw`` may trace it with fewer paths)
DENSE_GRID = "facade_map"


def facade_dense_grid(sensors: Sensors, frame: FacadeFrame, name: str = DENSE_GRID) -> SensorGrid:
    """A square grid of side ``dense_size_m`` and spacing ``dense_spacing_m`` centred on the
    sensors, for false-colour façade maps. Row labels are the sensor-row names by height."""
    half = sensors.dense_size_m / 2.0
    n = max(2, int(round(sensors.dense_size_m / sensors.dense_spacing_m)) + 1)
    us = sensors.x_m + np.linspace(-half, half, n)
    zs = sensors.height_m + np.linspace(-half, half, n)
    zs = zs[zs > 0.05]
    U, Z = np.meshgrid(us, zs)
    local = np.column_stack([U.ravel(), np.full(U.size, sensors.offset_m), Z.ravel()])
    rows = [f"z={zz:.2f}" for zz in Z.ravel()]
    normals = np.tile(frame.normal, (U.size, 1))
    return SensorGrid(name, frame.to_world(local), normals, rows)


#: joins a grid's name and its sensor height (``facade@4.5m``)
LEVEL_MARK = "@"


def level_name(grid: str, height_m: float) -> str:
    """``<grid>@<h>m`` with the height as written (``%g``): ``facade@4.5m``."""
    return f"{grid}{LEVEL_MARK}{height_m:g}m"


def is_dense_grid(name: str) -> bool:
    """Whether ``name`` is a dense façade map (``facade_map`` or ``facade_map@<h>m``)."""
    return name == DENSE_GRID or name.startswith(DENSE_GRID + LEVEL_MARK)


def street_grids(sensors: Sensors, frame: FacadeFrame, dense: bool) -> dict[str, SensorGrid]:
    """The street's façade grids: per sensor height its circle (and, when ``dense``, its dense
    map) — see the module text for names and the ``storey`` label."""
    levels = sensors.levels
    if len(levels) == 1:
        at = replace(sensors, height_m=levels[0], heights_m=None)
        grids = {"facade": facade_circle(at, frame)}
        if dense:
            grids[DENSE_GRID] = facade_dense_grid(at, frame)
        return grids
    out: dict[str, SensorGrid] = {}
    for k, h in enumerate(levels):
        at = replace(sensors, height_m=h, heights_m=None)
        made = [facade_circle(at, frame, level_name("facade", h))]
        if dense:
            made.append(facade_dense_grid(at, frame, level_name(DENSE_GRID, h)))
        for g in made:
            g.labels = {"storey": [k] * len(g)}
            out[g.name] = g
    return out


def point_grid(points, orientation: str, frame: FacadeFrame, name: str,
               row: str = "") -> SensorGrid:
    """Sensors at ``points`` (u along the façade, d out of the façade, z up; metres, façade
    frame) looking ``"facade"`` (out of the façade, vertical), ``"horizontal"`` (up) or
    ``"facing_crown"`` (vertical, back towards the façade and its crown) or ``"ground"``
    (looking down at the street, as an albedometer's lower sensor)."""
    local = np.asarray(points, float).reshape(-1, 3)
    if orientation == "horizontal":
        normal = np.array([0.0, 0.0, 1.0])
    elif orientation == "facade":
        normal = frame.normal
    elif orientation == "facing_crown":
        normal = -frame.normal
    elif orientation == "ground":
        normal = np.array([0.0, 0.0, -1.0])
    else:
        raise ValueError(f"orientation must be facade, horizontal, facing_crown or ground, "
                         f"got {orientation!r}")
    return SensorGrid(name, frame.to_world(local), np.tile(normal, (len(local), 1)),
                      [row] * len(local))
