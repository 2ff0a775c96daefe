"""The street's reflectance and the *calculated* ground-reflected term (scenarios A and D).

:func:`ground_reflectance_at`: the street's reflectance at a sun altitude — the project's
constant, or its table ``angle_deg,reflectance`` interpolated linearly and clamped at the ends.

The façade sensors are traced with a black ground and no ground glow; then, per vertical
sensor, E_refl = ρ(α) · E_ground · F is added, where

* ρ(α): the concrete reflectance at the hour's sun altitude (per-hour table);
* E_ground: the illuminance on the street — ``open``: the unobstructed global horizontal
  illuminance (direct + sky); ``shaded`` (default): the street under the crown's shade, i.e.
  ``permeability`` × the open value (the measured canopy permeability, 5–6 % in Mendoza: the
  street under a continuous row of mulberries is shaded for most of the day);
* F: the view factor from a vertical sensor at height h to the street — ``street`` (default):
  a street of width W, infinitely long, F = (1 − h/√(h² + W²))/2 (≈ 0.38 at h = 5 m,
  W = 20 m); ``unbounded``: F = 0.5.

Only sensors whose normal is horizontal (|n_z| < 0.1) receive the term.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from radtree.config import Project, Scenario, effective_project
from radtree.errors import ConfigError
from radtree.light.sky import SkyState
from radtree.light.tables import ground_reflectance_table
from radtree.scene import SensorGrid
from radtree.site.street import sky_view_factor_to_street


def ground_reflectance_at(project: Project, altitude_deg: float) -> float:
    """The street's reflectance for a sun altitude (table: interpolate, clamp; else constant)."""
    table = project.street.ground_reflectance_table
    if table is None:
        return project.street.ground_reflectance
    path = Path(table)
    try:
        version = path.stat().st_mtime_ns
    except OSError:
        version = -1      # the reader says what is wrong
    angles, values = _reflectance_curve(str(path), version)
    return float(np.interp(altitude_deg, angles, values))


@lru_cache(maxsize=64)
def _reflectance_curve(path: str, mtime_ns: int) -> tuple[np.ndarray, np.ndarray]:
    """The table's (angle, reflectance) sorted by angle, read once per file version."""
    df = ground_reflectance_table(Path(path)).sort_values("angle_deg")
    if (df["reflectance"] > 1).any():
        raise ConfigError(f"ground reflectance table {path}: reflectance above 1")
    angles, values = df["angle_deg"].to_numpy(float), df["reflectance"].to_numpy(float)
    angles.setflags(write=False)
    values.setflags(write=False)
    return angles, values


@dataclass(frozen=True)
class ReflectionChoice:
    ground: str = "shaded"
    view_factor: str = "street"
    permeability: float = 0.055

    def describe(self) -> str:
        g = ("street under the crown: permeability "
             f"{self.permeability:g} × open global horizontal" if self.ground == "shaded"
             else "open street: unobstructed global horizontal")
        f = ("(1 − h/√(h²+W²))/2 for the street width" if self.view_factor == "street"
             else "0.5 (unbounded ground)")
        return f"E_refl = ρ(α)·E_ground·F with E_ground = {g}, F = {f}"


def reflection_choice(project: Project, scenario: Scenario) -> ReflectionChoice:
    """The scenario's ``reflection.*`` switches (typed by :mod:`radtree.config.switches` when
    the scenario was made)."""
    sw = scenario.switches
    ground = str(sw.get("reflection.ground", "shaded"))
    vf = str(sw.get("reflection.view_factor", "street"))
    perm = float(sw.get("reflection.permeability", project.tree.homogeneous.permeability))
    return ReflectionChoice(ground, vf, perm)


def calculated_reflection(project: Project, scenario: Scenario, state: SkyState,
                          grid: SensorGrid) -> np.ndarray:
    """Lux added to each sensor of ``grid`` for this hour (0 for non-vertical sensors)."""
    project = effective_project(project, scenario)
    choice = reflection_choice(project, scenario)
    rho = ground_reflectance_at(project, state.sun.altitude_deg)
    e_open = state.direct_horizontal_lux + state.sky_horizontal_lux
    e_ground = e_open * (choice.permeability if choice.ground == "shaded" else 1.0)
    heights = grid.points[:, 2]
    if choice.view_factor == "street":
        F = np.array([sky_view_factor_to_street(h, project.street.width_m) for h in heights])
    else:
        F = np.full(len(heights), 0.5)
    vertical = np.abs(grid.normals[:, 2]) < 0.1
    return np.where(vertical, rho * e_ground * F, 0.0)


def unfiltered_ground_light(project: Project, scenario: Scenario, state: SkyState,
                            grid: SensorGrid) -> np.ndarray:
    """Street-reflected light reaching the façade *below* the crown, unfiltered.

    Under a real crown the street's reflected light arrives at the façade from below the crown
    almost unfiltered, whereas the sensor-dome form makes it cross the dome. The switch
    ``"reflection.unfiltered" = s`` (0–1) adds s · ρ(α) · E_ground · F to vertical sensors, with
    E_ground the *open* street (sunlit patches beyond the crown's shadow are what light the
    façade from below) and F the street view factor. 0 (default) adds nothing.
    """
    s = float(scenario.switches.get("reflection.unfiltered", 0.0))
    if s <= 0.0:
        return np.zeros(len(grid))
    project = effective_project(project, scenario)
    rho = ground_reflectance_at(project, state.sun.altitude_deg)
    e_open = state.direct_horizontal_lux + state.sky_horizontal_lux
    F = np.array([sky_view_factor_to_street(h, project.street.width_m)
                  for h in grid.points[:, 2]])
    vertical = np.abs(grid.normals[:, 2]) < 0.1
    return np.where(vertical, s * rho * e_open * F, 0.0)


def ground_terms(project: Project, scenario: Scenario, state: SkyState,
                 grid: SensorGrid) -> np.ndarray:
    """Every calculated (not traced) ground term added to the sensors of ``grid`` this hour (lux):
    the analytic ground reflection of ``reflection = "calculated"`` plus the unfiltered street
    light of the ``reflection.unfiltered`` switch."""
    extra = np.zeros(len(grid))
    if scenario.reflection == "calculated":
        extra = calculated_reflection(project, scenario, state, grid)
    return extra + unfiltered_ground_light(project, scenario, state, grid)


def reflection_notes(project: Project) -> dict[str, str]:
    """Per scenario, how ground-reflected light is handled (for reports)."""
    out = {}
    for sc in project.scenarios:
        if sc.reflection == "calculated":
            out[sc.name] = "calculated: " + reflection_choice(project, sc).describe()
        else:
            out[sc.name] = "traced: sun → street → façade through the crown model"
    return out
