"""A project's inventory inputs loaded once: trees, buildings, the selected façades and the
local frame (:mod:`radtree.site.inventory`, :mod:`radtree.site.buildings`).

Everything is checked here before anything is built or written, so a bad inventory stops
``radtree build`` / ``simulate`` with one message naming the feature and leaves no half-written
folder.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from radtree.config import Project
from radtree.errors import ConfigError
from radtree.site.buildings import (
    Building,
    Facade,
    check_trees_against_buildings,
    read_buildings,
    select_facades,
)
from radtree.site.frame import FacadeFrame
from radtree.site.inventory import InventoryTree, LocalFrame, read_trees

LOCAL_CRS = "local"   # [site] crs = "local": coordinates already in the local frame (m)


@dataclass(frozen=True)
class DistrictInputs:
    """Trees and buildings in the local frame; ``frame`` converts back to the input CRS."""

    trees: list[InventoryTree]
    buildings: list[Building]
    facades: list[Facade]
    frame: LocalFrame | None


_CACHE: dict[tuple, DistrictInputs] = {}


def _stamp(p: Path | None) -> tuple:
    return (None,) if p is None else (str(p), p.stat().st_mtime_ns, p.stat().st_size)


def load_district(project: Project) -> DistrictInputs:
    """The project's inventory inputs, read and checked (cached by file and modification)."""
    d = project.district
    if d is None:
        raise ConfigError("the project has no [site] trees or buildings", source=str(project.source))
    key = (_stamp(d.trees), _stamp(d.buildings), d, project.site.latitude,
           project.site.longitude, project.street)
    if key in _CACHE:
        return _CACHE[key]
    lat, lon = project.site.latitude, project.site.longitude
    crs = d.crs
    frame: LocalFrame | None = None
    buildings: list[Building] = []
    facades: list[Facade] = []
    if d.buildings is not None:
        buildings, frame = read_buildings(d.buildings, crs, lat, lon, d.storey_height_m)
        facades = select_facades(buildings, d.facades, str(project.source))
        if not facades:
            raise ConfigError("no façade selected", source=str(project.source),
                              field="site.facades")
    trees: list[InventoryTree] = []
    if d.trees is not None:
        trees, tframe = read_trees(d.trees, crs, lat, lon)
        frame = frame or tframe
        if buildings:
            check_trees_against_buildings(trees, buildings, str(d.trees))
        else:
            check_trees_in_canyon(project, trees, str(d.trees))
    out = DistrictInputs(trees, buildings, facades, frame)
    _CACHE[key] = out
    return out


def check_trees_in_canyon(project: Project, trees: list[InventoryTree], source: str) -> None:
    """Without buildings the trees stand in the street canyon: each trunk on the street and
    each crown clear of both façades (ConfigError naming the feature id)."""
    frame = FacadeFrame(azimuth_deg=project.street.facade_azimuth_deg)
    st = project.street
    for t in trees:
        u, n, _ = frame.to_local(np.array([t.x, t.y, 0.0]))
        where = f"feature {t.id!r}"
        if not 0.0 < n < st.width_m or abs(u) > st.length_m / 2.0:
            raise ConfigError(f"tree stands inside a building (n = {n:.2f} m across a "
                              f"{st.width_m:g} m street)", source=source, field=where)
        wall_h = min(st.building_height_m, st.opposite_building_height_m)
        if t.crown_base_m < wall_h and (n - t.crown_radius_m <= project.sensors.offset_m
                                        or n + t.crown_radius_m >= st.width_m):
            raise ConfigError(f"crown (radius {t.crown_radius_m:g} m, trunk {n:.2f} m from the "
                              "façade) reaches through a wall", source=source, field=where)
