"""The office block of the building application (reference case §5): rooms behind the studied façade.

``bays`` × ``storeys`` identical offices (default 3 × 3 in elevation; any counts, even ones
too) sit behind the façade plane n = 0 of the street canyon, in the façade frame (u along the
façade, n towards the street, z up). Each office is ``width_m`` wide (along u), ``depth_m``
deep (n from −depth to 0) and ``height_m`` high, with a glazed opening over its full width
between ``window_sill_m`` and ``window_head_m`` above its floor. Storey k (0 = the ground
floor, the lowest) has its floor at ``ground_floor_m + k·storey_height_m``. The block is
centred on u = ``sensors.x_m`` (where the crown row is centred): with an odd number of bays
the tree stands in front of the central bay, with an even number in front of the partition
between the two middle bays.

Rooms are named ``"STOREY-BAY"``: ``"0-1"`` is the ground-floor office of bay 1, bays counted
from 0 at the left end of the block seen from the street (smallest u). ``[office] rooms``
selects the sensed rooms: ``"all"`` (the default) or a list such as ``["0-1", "1-1"]``.

Geometry, all in one closed set of surfaces (rooms are closed except through the glazing):

* ``facade`` — the façade wall (``facade_paint``, the street's material) over the whole canyon
  length and building height, minus the office openings. It replaces the street's plain
  façade quad of the same name.
* ``office_glazing`` — the panes (Radiance ``glass`` built with
  :meth:`radtree.optics.Glass.from_transmittance` from ``glazing_transmittance``), flush with
  the façade plane (no wall thickness, no reveal: the opening is a hole in a thin façade).
* ``office_frames`` — opaque frame and mullions (``window_frame``, ρ = 0.5): a border of width f
  around each opening and a vertical mullion every ≈ 1.5 m, with f chosen so that the frame
  covers exactly ``frame_fraction`` of the opening.
* ``office_floors`` / ``office_ceilings`` / ``office_walls`` — Lambertian ``plastic`` of the
  configured reflectances (defaults 0.2 / 0.7 / 0.5). Walls are the back walls, the end walls
  and the partitions between offices (one surface shared by both neighbours — same material
  on both sides), plus the inner face of the façade below the sill / above the head (5 mm
  inside the façade so a room never sees the white exterior paint).
* Slabs between storeys: the ceiling of storey k and the floor of storey k + 1 are separate
  surfaces. When ``storey_height_m − height_m`` leaves less than 5 mm (the default 2.5 m
  storey for a 2.5 m office leaves none), every office is lowered to ``storey_height_m − 5 mm``
  so floor and ceiling never coincide (coincident surfaces of different materials are
  ambiguous for a ray tracer); the notes say so.

Sensor grids, in every sensed room (equal-area grids: every point is the centre of an equal
cell, so "% of points" is "% of area"); each grid holds the sensed rooms one after the other
(in the order of ``rooms``; ``"all"``: storey by storey from the ground, bay by bay from the
left) and every sensor carries its ``storey`` (int) and ``room`` (``"STOREY-BAY"``), columns
of the results table:

* ``facade`` — vertical, on the outside of each sensed office's façade (opening and frame),
  ``sensors.offset_m`` (1 cm) out, normals +n (out of the façade), cells of
  ``facade_grid_spacing_m`` over the office's width × height; rows are labelled by height above
  the street, ``z=4.00``.
* ``workplane`` — horizontal at ``workplane_height_m`` above each sensed office's floor,
  normals up, cells of ``grid_spacing_m`` over the floor area inset ``wall_offset_m`` from every
  wall (the band next to the walls is excluded, as in LM-83 / EN 17037 practice); rows are
  labelled by depth behind the façade, ``d=0.75``.

Heights: with 2.5 m storeys, ``ground_floor_m`` = 1.25 m puts storey 1's floor at 3.75 m and
the centre of its façade grid at 5.0 m — the height of the study's measured sensors;
``examples/office-block`` sets it so and senses the central office ``"1-1"`` only.
(``Office()``'s own default, 2.5 m, puts storey 1's façade centre at 6.25 m.)
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from radtree.config import Office, Project
from radtree.errors import ConfigError
from radtree.optics import Glass, Material, Plastic
from radtree.scene import Mesh, SensorGrid, quad
from radtree.site.frame import FacadeFrame

MIN_SLAB_M = 0.005
"""Smallest gap kept between a ceiling and the floor above (m)."""
INNER_FACADE_INSET_M = 0.005
"""The room side of the façade wall (below the sill / above the head) sits this far inside."""
FRAME_REFLECTANCE = 0.5
"""Window frames and mullions: a mid-grey powder coat (not given in the study)."""
PANE_WIDTH_M = 1.5
"""Target pane width: a vertical mullion every ≈ 1.5 m of opening width."""
FACADE_MATERIAL = "facade_paint"
RECOMMENDED_AB = 6
"""Ambient bounces an office room needs for its inter-reflections (floor 0.2, walls 0.5,
ceiling 0.7, 6 m deep). Without a tree at 13:30 (pure Monte Carlo, -ad 2048) the work-plane
mean is 34 % low at -ab 2, 6 % at -ab 4, 2 % at -ab 5 and 0.6 % at -ab 6 (against -ab 8)."""

MATERIAL_NAMES = ("glazing", "window_frame", "office_floor", "office_wall", "office_ceiling")


@dataclass(frozen=True)
class Box:
    """An axis-aligned room in façade-frame coordinates (u, n, z), metres."""

    u0: float
    u1: float
    n0: float
    n1: float
    z0: float
    z1: float

    def contains(self, local: np.ndarray, tol: float = 0.0) -> np.ndarray:
        p = np.atleast_2d(np.asarray(local, float))
        return ((p[:, 0] > self.u0 + tol) & (p[:, 0] < self.u1 - tol)
                & (p[:, 1] > self.n0 + tol) & (p[:, 1] < self.n1 - tol)
                & (p[:, 2] > self.z0 + tol) & (p[:, 2] < self.z1 - tol))


@dataclass(frozen=True)
class OfficeLayout:
    """Where every office, opening and frame bar of the block lies (façade frame, metres)."""

    office: Office
    centre_u: float
    room_height: float
    sill: float
    head: float
    frame_width: float
    panes: int
    facade_offset: float

    def bay_u(self, j: int) -> tuple[float, float]:
        """(u0, u1) of bay j (0 = the leftmost seen from the street); the block is centred on
        ``centre_u`` (for odd counts (bays − 1)/2 is a whole number: the central bay's
        formula as before)."""
        w = self.office.width_m
        u0 = self.centre_u + (j - (self.office.bays - 1) / 2) * w - w / 2.0
        return u0, u0 + w

    def floor_z(self, k: int) -> float:
        return self.office.ground_floor_m + k * self.office.storey_height_m

    def room(self, j: int, k: int) -> Box:
        u0, u1 = self.bay_u(j)
        z0 = self.floor_z(k)
        return Box(u0, u1, -self.office.depth_m, 0.0, z0, z0 + self.room_height)

    @property
    def sensed(self) -> list[tuple[str, int, int]]:
        """The sensed rooms: (name ``"STOREY-BAY"``, storey k, bay j), in ``rooms`` order."""
        out = []
        for name in self.office.room_names:
            k, j = name.split("-")
            out.append((name, int(k), int(j)))
        return out

    def opening(self, j: int, k: int) -> tuple[float, float, float, float]:
        """(u0, u1, z0, z1) of the office's façade opening."""
        u0, u1 = self.bay_u(j)
        z = self.floor_z(k)
        return u0, u1, z + self.sill, z + self.head

    @property
    def block_top(self) -> float:
        return self.floor_z(self.office.storeys - 1) + self.room_height

    @property
    def u_range(self) -> tuple[float, float]:
        return self.bay_u(0)[0], self.bay_u(self.office.bays - 1)[1]

    def frame_area_fraction(self) -> float:
        """Frame area / opening area actually built (equals ``frame_fraction``)."""
        w, h, f, n = self.office.width_m, self.head - self.sill, self.frame_width, self.panes
        glass = max(0.0, w - (n + 1) * f) * max(0.0, h - 2 * f)
        return 1.0 - glass / (w * h)


def frame_width_for(width: float, height: float, fraction: float, panes: int) -> float:
    """Width f of a frame border plus ``panes − 1`` mullions covering ``fraction`` of a
    width × height opening: (w − (p+1)f)(h − 2f) = (1 − fraction)·w·h, smallest root."""
    if fraction <= 0.0:
        return 0.0
    k = panes + 1
    b = 2.0 * width + k * height
    disc = max(0.0, b * b - 8.0 * k * fraction * width * height)
    return (b - math.sqrt(disc)) / (4.0 * k)


def office_layout(project: Project) -> OfficeLayout:
    """Validate the ``[office]`` table against the street and return the block's layout."""
    o = project.office
    if o is None:
        raise ConfigError("the project has no [office] table", source=str(project.source),
                          field="office")
    src = str(project.source)

    def err(field: str, msg: str) -> ConfigError:
        return ConfigError(msg, source=src, field=f"office.{field}")

    if o.ground_floor_m < 0:
        raise err("ground_floor_m", f"got {o.ground_floor_m}, expected ≥ 0")
    if not 0.0 <= o.window_sill_m < o.window_head_m:
        raise err("window_sill_m", f"got sill {o.window_sill_m} m and head {o.window_head_m} m; "
                  "expected 0 ≤ sill < head")
    if o.window_head_m > o.height_m + 1e-9:
        raise err("window_head_m", f"got {o.window_head_m} m, above the office height "
                  f"{o.height_m} m")
    room_h = o.height_m
    if o.storeys > 1 and o.storey_height_m - o.height_m < MIN_SLAB_M:
        room_h = o.storey_height_m - MIN_SLAB_M
    if room_h <= o.window_sill_m:
        raise err("window_sill_m", f"the sill ({o.window_sill_m} m) is at or above the room "
                  f"height ({room_h:g} m)")
    head = min(o.window_head_m, room_h)
    if not 0.0 < o.workplane_height_m < room_h:
        raise err("workplane_height_m", f"got {o.workplane_height_m} m, expected between 0 and "
                  f"the room height {room_h:g} m")
    if o.wall_offset_m < 0:
        raise err("wall_offset_m", f"got {o.wall_offset_m}, expected ≥ 0")
    for dim, name in ((o.width_m, "width_m"), (o.depth_m, "depth_m")):
        if 2.0 * o.wall_offset_m >= dim:
            raise err("wall_offset_m", f"{o.wall_offset_m} m from each wall leaves no work plane "
                      f"in an office {dim} m across ({name})")
    street = project.street
    top = o.ground_floor_m + (o.storeys - 1) * o.storey_height_m + room_h
    if top > street.building_height_m + 1e-9:
        raise err("storeys", f"the block reaches {top:.2f} m, above the building "
                  f"({street.building_height_m} m, street.building_height_m)")
    centre_u = project.sensors.x_m
    half = o.bays * o.width_m / 2.0
    if centre_u - half < -street.length_m / 2.0 - 1e-9 or \
            centre_u + half > street.length_m / 2.0 + 1e-9:
        raise err("bays", f"{o.bays} offices of {o.width_m} m centred at u = {centre_u} m "
                  f"(sensors.x_m) do not fit in the façade ({street.length_m} m long, "
                  "street.length_m)")
    panes = max(1, int(round(o.width_m / PANE_WIDTH_M)))
    f = frame_width_for(o.width_m, head - o.window_sill_m, o.frame_fraction, panes)
    return OfficeLayout(o, centre_u, room_h, o.window_sill_m, head, f, panes,
                        project.sensors.offset_m)


# ---------------------------------------------------------------- geometry
def _rect_u_z(u0: float, u1: float, z0: float, z1: float, n: float) -> np.ndarray:
    return np.array([[u0, n, z0], [u1, n, z0], [u1, n, z1], [u0, n, z1]], float)


def _rect_u_n(u0: float, u1: float, n0: float, n1: float, z: float) -> np.ndarray:
    return np.array([[u0, n0, z], [u1, n0, z], [u1, n1, z], [u0, n1, z]], float)


def _rect_n_z(n0: float, n1: float, z0: float, z1: float, u: float) -> np.ndarray:
    return np.array([[u, n0, z0], [u, n1, z0], [u, n1, z1], [u, n0, z1]], float)


def _merge(name: str, material: str, rects: list[np.ndarray], frame: FacadeFrame) -> Mesh | None:
    if not rects:
        return None
    return Mesh.merge(name, material, [quad(name, material, frame.to_world(r)) for r in rects])


def facade_minus_openings(u_range: tuple[float, float], z_range: tuple[float, float],
                          openings: list[tuple[float, float, float, float]]
                          ) -> list[tuple[float, float, float, float]]:
    """Rectangles (u0, u1, z0, z1) tiling the façade outside the openings.

    The façade is cut at every opening edge; in each horizontal band the cells outside the
    openings are merged into runs.
    """
    us = sorted({u_range[0], u_range[1], *(v for o in openings for v in o[:2])})
    zs = sorted({z_range[0], z_range[1], *(v for o in openings for v in o[2:])})
    us = [u for u in us if u_range[0] <= u <= u_range[1]]
    zs = [z for z in zs if z_range[0] <= z <= z_range[1]]
    out = []
    for z0, z1 in zip(zs[:-1], zs[1:]):
        if z1 - z0 < 1e-9:
            continue
        zc = 0.5 * (z0 + z1)
        run_start = None
        for u0, u1 in zip(us[:-1], us[1:]):
            uc = 0.5 * (u0 + u1)
            inside = any(a <= uc <= b and c <= zc <= d for a, b, c, d in openings)
            if not inside and run_start is None:
                run_start = u0
            if inside and run_start is not None:
                out.append((run_start, u0, z0, z1))
                run_start = None
        if run_start is not None:
            out.append((run_start, us[-1], z0, z1))
    return [r for r in out if r[1] - r[0] > 1e-9]


def office_materials(office: Office) -> dict[str, Material]:
    """Glazing, frame, floor, wall and ceiling materials (the façade paint is the street's)."""
    return {
        "glazing": Glass.from_transmittance("glazing", office.glazing_transmittance),
        "window_frame": Plastic("window_frame", FRAME_REFLECTANCE),
        "office_floor": Plastic("office_floor", office.floor_reflectance),
        "office_wall": Plastic("office_wall", office.wall_reflectance),
        "office_ceiling": Plastic("office_ceiling", office.ceiling_reflectance),
    }


def office_meshes(layout: OfficeLayout, frame: FacadeFrame, street_length_m: float,
                  building_height_m: float) -> list[Mesh]:
    """Façade wall with openings, glazing, frames, floors, ceilings and walls (world space)."""
    o = layout.office
    B, S = o.bays, o.storeys
    D = o.depth_m
    floors, ceilings, walls, glass, frames = [], [], [], [], []
    openings = []
    f = layout.frame_width
    for k in range(S):
        z0 = layout.floor_z(k)
        z1 = z0 + layout.room_height
        for j in range(B):
            u0, u1 = layout.bay_u(j)
            floors.append(_rect_u_n(u0, u1, -D, 0.0, z0))
            ceilings.append(_rect_u_n(u0, u1, -D, 0.0, z1))
            walls.append(_rect_u_z(u0, u1, z0, z1, -D))
            ou0, ou1, oz0, oz1 = layout.opening(j, k)
            openings.append((ou0, ou1, oz0, oz1))
            inner = -INNER_FACADE_INSET_M
            if oz0 > z0 + 1e-9:
                walls.append(_rect_u_z(u0, u1, z0, oz0, inner))
            if oz1 < z1 - 1e-9:
                walls.append(_rect_u_z(u0, u1, oz1, z1, inner))
            # frame: bottom and top bars over the full width, (panes + 1) vertical bars
            h = oz1 - oz0
            w = ou1 - ou0
            if f > 0:
                frames.append(_rect_u_z(ou0, ou1, oz0, oz0 + f, 0.0))
                frames.append(_rect_u_z(ou0, ou1, oz1 - f, oz1, 0.0))
            pane_w = (w - (layout.panes + 1) * f) / layout.panes
            for p in range(layout.panes + 1):
                bu = ou0 + p * (pane_w + f)
                if f > 0:
                    frames.append(_rect_u_z(bu, bu + f, oz0 + f, oz1 - f, 0.0))
                if p < layout.panes and pane_w > 1e-9 and h - 2 * f > 1e-9:
                    glass.append(_rect_u_z(bu + f, bu + f + pane_w, oz0 + f, oz1 - f, 0.0))
        # end walls and partitions: one surface per bay boundary (same material both sides)
        for j in range(B + 1):
            u = layout.bay_u(j)[0] if j < B else layout.bay_u(B - 1)[1]
            walls.append(_rect_n_z(-D, 0.0, z0, z1, u))
    L2 = street_length_m / 2.0
    paint = [_rect_u_z(a, b, c, d, 0.0)
             for a, b, c, d in facade_minus_openings((-L2, L2), (0.0, building_height_m),
                                                     openings)]
    out = [
        _merge("facade", FACADE_MATERIAL, paint, frame),
        _merge("office_glazing", "glazing", glass, frame),
        _merge("office_frames", "window_frame", frames, frame),
        _merge("office_floors", "office_floor", floors, frame),
        _merge("office_ceilings", "office_ceiling", ceilings, frame),
        _merge("office_walls", "office_wall", walls, frame),
    ]
    return [m for m in out if m is not None]


# ---------------------------------------------------------------- grids
def _cell_centres(a: float, b: float, spacing: float) -> np.ndarray:
    """Centres of n = round((b − a)/spacing) (≥ 1) equal cells covering [a, b]."""
    n = max(1, int(round((b - a) / spacing)))
    step = (b - a) / n
    return a + step * (np.arange(n) + 0.5)


def _room_labels(rooms: list[tuple[str, int, int]], sizes: list[int]) -> dict[str, list]:
    return {"storey": [k for (_, k, _), m in zip(rooms, sizes) for _ in range(m)],
            "room": [n for (n, _, _), m in zip(rooms, sizes) for _ in range(m)]}


def facade_grid(layout: OfficeLayout, frame: FacadeFrame, name: str = "facade") -> SensorGrid:
    """Vertical grid on the outside of every sensed office's façade, normals out (+n)."""
    local, rows, sizes = [], [], []
    for _, k, j in layout.sensed:
        room = layout.room(j, k)
        us = _cell_centres(room.u0, room.u1, layout.office.facade_grid_spacing_m)
        zs = _cell_centres(room.z0, room.z1, layout.office.facade_grid_spacing_m)
        Z, U = np.meshgrid(zs[::-1], us, indexing="ij")          # top row first
        local.append(np.column_stack([U.ravel(), np.full(U.size, layout.facade_offset),
                                      Z.ravel()]))
        rows += [f"z={z:.2f}" for z in Z.ravel()]
        sizes.append(U.size)
    pts = np.vstack(local)
    normals = np.tile(frame.normal, (len(pts), 1))
    return SensorGrid(name, frame.to_world(pts), normals, rows,
                      _room_labels(layout.sensed, sizes))


def workplane_grid(layout: OfficeLayout, frame: FacadeFrame,
                   name: str = "workplane") -> SensorGrid:
    """Horizontal grid at the work-plane height in every sensed office, normals up."""
    o = layout.office
    off = o.wall_offset_m
    local, rows, sizes = [], [], []
    for _, k, j in layout.sensed:
        room = layout.room(j, k)
        us = _cell_centres(room.u0 + off, room.u1 - off, o.grid_spacing_m)
        ns = _cell_centres(room.n0 + off, room.n1 - off, o.grid_spacing_m)[::-1]  # façade first
        N, U = np.meshgrid(ns, us, indexing="ij")
        z = room.z0 + o.workplane_height_m
        local.append(np.column_stack([U.ravel(), N.ravel(), np.full(U.size, z)]))
        rows += [f"d={-n:.2f}" for n in N.ravel()]
        sizes.append(U.size)
    pts = np.vstack(local)
    normals = np.tile([0.0, 0.0, 1.0], (len(pts), 1))
    return SensorGrid(name, frame.to_world(pts), normals, rows,
                      _room_labels(layout.sensed, sizes))


# ---------------------------------------------------------------- entry point
def office_parts(project: Project, frame: FacadeFrame
                 ) -> tuple[list[Mesh], dict[str, Material], dict[str, SensorGrid], list[str]]:
    """Meshes, materials, grids (``facade``, ``workplane``) and notes of the office block."""
    layout = office_layout(project)
    o = layout.office
    meshes = office_meshes(layout, frame, project.street.length_m,
                           project.street.building_height_m)
    materials = office_materials(o)
    grids = {"facade": facade_grid(layout, frame), "workplane": workplane_grid(layout, frame)}
    glass = materials["glazing"]
    assert isinstance(glass, Glass)
    n_tri = sum(m.n_triangles for m in meshes)
    fg, wg = grids["facade"], grids["workplane"]
    floors = ", ".join(f"{layout.floor_z(k):g}" for k in range(o.storeys))
    sensed = ", ".join(n for n, _, _ in layout.sensed)
    notes = [
        f"office block: {o.bays} bays × {o.storeys} storeys of offices {o.width_m:g} m wide × "
        f"{layout.room_height:g} m high × {o.depth_m:g} m deep behind the façade; floors at "
        f"{floors} m (storey {o.storey_height_m:g} m); results read in "
        f"{len(layout.sensed)} office(s) 'STOREY-BAY' (storey 0 = ground floor, bay 0 = "
        f"leftmost seen from the street): {sensed}; {n_tri} triangles",
        f"openings over the full office width from {layout.sill:g} to {layout.head:g} m above "
        f"the floor, glazing flush with the façade (no reveal): Radiance glass, measured Tn "
        f"{o.glazing_transmittance:g} → transmissivity {glass.transmissivity:.4f}; frame and "
        f"{layout.panes - 1} mullion(s) {100 * layout.frame_width:.1f} cm wide = "
        f"{100 * layout.frame_area_fraction():.1f} % of the opening, ρ {FRAME_REFLECTANCE:g}",
        f"inside: floor ρ {o.floor_reflectance:g}, walls ρ {o.wall_reflectance:g}, ceiling ρ "
        f"{o.ceiling_reflectance:g} (Lambertian); façade wall around the openings: "
        f"{FACADE_MATERIAL}",
        f"grids: façade {len(fg)} points ({o.facade_grid_spacing_m:g} m cells over each sensed "
        f"office's façade, {layout.facade_offset:g} m out, centres at "
        + ", ".join(f"{layout.floor_z(k) + 0.5 * layout.room_height:.2f}"
                    for k in sorted({k for _, k, _ in layout.sensed}))
        + f" m); work plane {len(wg)} points "
        f"({o.grid_spacing_m:g} m cells at {o.workplane_height_m:g} m, {o.wall_offset_m:g} m "
        "from the walls)",
    ]
    if layout.room_height < o.height_m - 1e-9:
        notes.append(f"storey height {o.storey_height_m:g} m leaves no slab for {o.height_m:g} m "
                     f"offices: rooms built {layout.room_height:g} m high so that floor and "
                     f"ceiling are separate surfaces ({1000 * MIN_SLAB_M:g} mm apart)")
    return meshes, materials, grids, notes
