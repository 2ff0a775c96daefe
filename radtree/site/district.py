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
    WallContact,
    check_trees_against_buildings,
    read_buildings,
    select_facades,
)
from radtree.site.frame import FacadeFrame
from radtree.site.inventory import InventoryTree, LocalFrame, read_trees
from radtree.site.placement import behind_trees, line_frame, placement_note

LOCAL_CRS = "local"   # [site] crs = "local": coordinates already in the local frame (m)


@dataclass(frozen=True)
class DistrictInputs:
    """Trees and buildings in the local frame; ``frame`` converts back to the input CRS.
    Without buildings, ``street_frame`` is the street canyon's façade frame
    (:mod:`radtree.site.placement`; ``placement`` its note when placed automatically).
    ``walls``: per tree id, the walls its crown reaches (:class:`WallContact`; the crown–wall
    policy, :mod:`radtree.trees.wall_policy`, decides what is done)."""

    trees: list[InventoryTree]
    buildings: list[Building]
    facades: list[Facade]
    frame: LocalFrame | None
    street_frame: FacadeFrame | None = None
    placement: str = ""
    walls: dict[str, list[WallContact]] | None = None


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
    street_frame, note, walls = None, "", None
    if d.trees is not None:
        trees, tframe = read_trees(d.trees, crs, lat, lon)
        frame = frame or tframe
        if buildings:
            walls = check_trees_against_buildings(trees, buildings, str(d.trees),
                                                  reach_margin(project))
        else:
            street_frame, note = canyon_frame(project, trees, tframe)
            walls = check_trees_in_canyon(project, trees, str(d.trees), street_frame)
    out = DistrictInputs(trees, buildings, facades, frame, street_frame, note, walls)
    _CACHE[key] = out
    return out


def reach_margin(project: Project) -> float:
    """How far beyond its radius a crown may be from a wall and still meet the wall's clip
    plane (m): an upper bound of the plane's distance from the wall (clearance, or the
    sensors' offset + 5 mm; :func:`radtree.trees.envelope.clip_plane`)."""
    return project.tree.crown.clearance_m + project.sensors.offset_m + 0.01


def canyon_frame(project: Project, trees: list[InventoryTree], frame: LocalFrame
                 ) -> tuple[FacadeFrame, str]:
    """The canyon's façade frame for inventory trees without buildings, and the note of an
    automatic placement (:mod:`radtree.site.placement`): the ``facade_line`` when given;
    else through the site origin when the inventory is in ``crs = "local"`` (the user's own
    coordinates, the façade's frame), else behind the trees (a real-world CRS: the site
    origin is only where the projection is centred, typically the trees' centroid)."""
    st = project.street
    if st.facade_line is not None:
        return line_frame(st.facade_line), ""
    if frame.crs == LOCAL_CRS:
        return FacadeFrame(azimuth_deg=st.facade_azimuth_deg), ""
    placed = behind_trees(st.facade_azimuth_deg, [(t.x, t.y) for t in trees],
                          project.tree.crown.trunk_distance_m)
    return placed, placement_note(project, placed)


def check_trees_in_canyon(project: Project, trees: list[InventoryTree], source: str,
                          frame: FacadeFrame) -> dict[str, list[WallContact]]:
    """Without buildings the trees stand in the street canyon: each trunk on the street
    (ConfigError naming the feature id and the fix otherwise). Returns the façades each crown
    reaches below their tops (the crown–wall policy decides what is done)."""
    st = project.street
    out: dict[str, list[WallContact]] = {}
    for t in trees:
        u, n, _ = frame.to_local(np.array([t.x, t.y, 0.0]))
        where = f"feature {t.id!r}"
        if not 0.0 < n < st.width_m:
            side = "behind the studied façade" if n <= 0 else "beyond the opposite façade"
            raise ConfigError(f"tree stands {side} (n = {n:.2f} m across a {st.width_m:g} m "
                              "street): set [street] facade_line (the façade's foot in the site "
                              "frame) or street.width_m so the trunk stands in the street",
                              source=source, field=where)
        if abs(u) > st.length_m / 2.0:
            raise ConfigError(f"tree stands {abs(u):.2f} m along the façade from its middle, "
                              f"beyond the modelled street (street.length_m {st.length_m:g} m): "
                              f"set street.length_m ≥ {2 * abs(u) + t.crown_diameter_m:.1f}",
                              source=source, field=where)
        contacts = []
        origin = frame.to_world(np.array([u, 0.0, 0.0]))[:2]
        reach = t.crown_radius_m + reach_margin(project)
        if t.crown_base_m < st.building_height_m and n < reach:
            contacts.append(WallContact("the façade", origin, frame.normal[:2], float(n)))
        if t.crown_base_m < st.opposite_building_height_m and st.width_m - n < reach:
            far = frame.to_world(np.array([u, st.width_m, 0.0]))[:2]
            contacts.append(WallContact("the opposite façade", far, -frame.normal[:2],
                                        float(st.width_m - n)))
        if contacts:
            out[t.id] = contacts
    return out
