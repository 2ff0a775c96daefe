"""Like-for-like estimator comparison: a patch detector's mean illuminance from the backward
engines, and the reduced Mendoza louvers dome both are compared on.

A forward patch detector reports the illuminance averaged over its square; a backward engine
reports it at a point. :func:`backward_patch_mean` samples ``points`` uniformly random points
inside each sensor's square (the forward engine's detector axes) and traces them, so both
estimate the same quantity: the mean over the grid's squares. Its standard error is that of the
mean over the random points (spatial and Monte Carlo noise together).

With ``stratified=True`` the square is cut into m × m equal cells and each cell holds two
independent uniform points (``points`` = 2 m²): stratified random sampling, whose variance
counts only the spread *within* cells (sun flecks and shade are spatially coherent, so most of
the spatial noise of uniform points goes). Its standard error is the textbook estimator for two
units per stratum: with L equal-weight strata (cells of every square) and the pair y₁, y₂ in
each, Var(ȳ) = Σ_h s_h² / (2 L²), s_h² = (y₁ − y₂)² / 2 (Cochran, *Sampling Techniques*,
3rd ed. 1977, ch. 5: variance of the stratified mean Σ W_h² s_h² / n_h; cited from memory) —
unbiased, and it holds the engine's ray noise too, since every point is traced with its own
rays.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from radtree.config import EngineParams, Project, load_project
from radtree.engines.forward.detectors import patch_axes
from radtree.light.sky import SkyState
from radtree.scene import Scene, SensorGrid

MENDOZA = Path(__file__).resolve().parents[2] / "examples" / "mendoza-street"
#: the reduced Mendoza louvers dome: a 6.5 m piece of a 6 m wide street between 8.5 m high
#: façades (a small scene keeps the forward engine's launch disc small), the 5-layer louvers
#: dome of radius 3 m (instead of 4 m) on the sensors, one hour
REDUCED_DOME: dict[str, Any] = {"street.length_m": 6.5, "street.width_m": 6.0,
                "street.building_height_m": 8.5, "street.opposite_building_height_m": 8.5,
                "tree.dome.radius_m": 3.0}
#: the free volume crown: one free-standing louvers crown of slats scattered through its volume
#: (``louvers.arrangement = "volume"``), radius 2.5 m, centre at the sensors' height, trunk
#: 2.5 m from the façade, in the same reduced street
REDUCED_FREE: dict[str, Any] = {**{k: v for k, v in REDUCED_DOME.items() if not k.startswith("tree.dome")},
                "tree.form": "free", "tree.louvers.arrangement": "volume",
                "tree.crown.count": 1, "tree.crown.radius_m": 2.5,
                "tree.crown.vertical_radius_m": 2.5, "tree.crown.base_height_m": 2.5,
                "tree.crown.trunk_distance_m": 2.5}
#: the agreement checks' crown forms by label
REDUCED: dict[str, dict[str, Any]] = {"louvers dome": REDUCED_DOME, "free volume crown": REDUCED_FREE}


@dataclass
class PatchMean:
    """Mean illuminance (lux) over a grid's squares and its standard error."""

    lux: float
    stderr: float


def stratified_cells(points: int) -> int:
    """m for ``points`` = 2 m² (two points in each of m × m cells); ValueError otherwise."""
    m = int(round(np.sqrt(points / 2.0)))
    if m < 1 or 2 * m * m != points:
        raise ValueError(f"stratified patch sampling needs points = 2·m² (2, 8, 18, 32, 50, "
                         f"72, 98, 128, …), got {points}")
    return m


def _offsets(side: float, points: int, rng: np.random.Generator, stratified: bool
             ) -> tuple[np.ndarray, np.ndarray]:
    """In-square offsets (a, b) (m): uniform, or two per cell of an m × m grid (cell-major:
    points 2h and 2h + 1 share cell h)."""
    if not stratified:
        a, b = rng.uniform(-side / 2, side / 2, (2, points))
        return a, b
    m = stratified_cells(points)
    i, j = np.divmod(np.repeat(np.arange(m * m), 2), m)
    a = (i + rng.random(points)) / m * side - side / 2
    b = (j + rng.random(points)) / m * side - side / 2
    return a, b


def patch_points(grid: SensorGrid, side: float, points: int, rng: np.random.Generator,
                 stratified: bool = False) -> SensorGrid:
    """``points`` random points in each sensor's square of ``side`` m (sensor-major order;
    ``stratified``: two in each cell of an m × m grid, module text)."""
    pts, nrm = [], []
    for p, n in zip(grid.points, grid.normals):
        u, v = patch_axes(n)
        a, b = _offsets(side, points, rng, stratified)
        pts.append(p + a[:, None] * u + b[:, None] * v)
        nrm.append(np.tile(n, (points, 1)))
    return SensorGrid(f"{grid.name}_patches", np.vstack(pts), np.vstack(nrm))


def backward_patch_values(engine: str, scene: Scene, state: SkyState, grid: str,
                          side: float, *, ab: int, points: int = 64, rays: int = 64,
                          seed: int = 1, params: EngineParams | None = None,
                          stratified: bool = False) -> np.ndarray:
    """(sensors, points) illuminances (lux) at ``points`` random points inside each of
    ``grid``'s squares of side ``side`` by a backward engine (``numpy`` or ``radiance``):
    ``rays`` paths per point (NumPy) or the Radiance settings of ``params``;
    ``stratified``: two points in each cell of an m × m grid (:func:`patch_points`)."""
    from radtree.engines.registry import get_engine

    g = scene.grids[grid]
    pg = patch_points(g, side, points, np.random.default_rng(seed), stratified)
    sub = Scene(scene.meshes, scene.materials, {pg.name: pg}, scene.notes,
                scene.ground_material, media=scene.media)
    base = params or EngineParams()
    p = base.changed(rays=rays, seed=seed, max_bounces=ab, ab=ab)
    res = get_engine(engine).trace_once(sub, state, p, ab)[pg.name]
    return res.lux.reshape(len(g), points)


def backward_patch_mean(engine: str, scene: Scene, state: SkyState, grid: str, side: float,
                        *, ab: int, points: int = 64, rays: int = 64, seed: int = 1,
                        params: EngineParams | None = None, stratified: bool = False
                        ) -> PatchMean:
    """The mean over ``grid``'s squares by :func:`backward_patch_values`; its standard error
    from the spread of the per-draw means over the squares (spatial and ray noise), or with
    ``stratified`` from the pairs of points sharing a cell (module text)."""
    values = backward_patch_values(engine, scene, state, grid, side, ab=ab, points=points,
                                   rays=rays, seed=seed, params=params, stratified=stratified)
    if stratified:
        pairs = values.reshape(-1, 2)                   # (sensors · cells, 2)
        strata = len(pairs)
        var = float(((pairs[:, 0] - pairs[:, 1]) ** 2).sum()) / (4.0 * strata * strata)
        return PatchMean(float(values.mean()), float(np.sqrt(var)))
    per_point = values.mean(axis=0)
    return PatchMean(float(per_point.mean()), float(per_point.std(ddof=1) / np.sqrt(points)))


def reduced_dome_project(hour: str = "12:30", scenario_overrides: dict | None = None,
                         crown: str = "louvers dome") -> Project:
    """The shipped Mendoza example reduced (:data:`REDUCED_DOME`, or another form of
    :data:`REDUCED` by label) to one hour."""
    ov: dict[str, Any] = dict(REDUCED[crown])
    ov["site.hours"] = [hour]
    ov["sensors.dense_grid"] = False
    ov["sensors.dense_hours"] = [hour]
    ov.update(scenario_overrides or {})
    return load_project(MENDOZA, overrides=ov)
