"""Building footprints extruded into walls and roofs; façade sensor grids on every face.

A footprint polygon (local frame, x east, y north, metres; :mod:`radtree.site.inventory`) is
extruded to ``height_m``: a wall quad per face and a flat roof (:func:`building_meshes`), no
floor (the street is the ground). Faces are the edges of the exterior ring made
counter-clockwise (``shapely.geometry.polygon.orient``): face k runs from vertex k to k + 1,
its outward normal is the edge direction turned 90° clockwise. A face is *towards the street*
when a point 0.5 m outside its midpoint is inside no other footprint (walls shared with a
neighbour are left out).

Sensors: along each selected face every ``facade_spacing_m`` (cell centres, at least one), per
storey at ``window_height_m`` above the storey floor (storey height ``height_m / storeys``, or
``[site] storey_height_m``), ``offset_m`` off the wall, normal out of the wall. Each sensor
carries its ``building``, ``facade`` (``BUILDING:FACE``) and ``storey`` (0 = ground).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from radtree.errors import ConfigError
from radtree.optics import Plastic
from radtree.scene import Mesh, SensorGrid, quad
from radtree.site.inventory import InventoryTree, LocalFrame, check_spread, number, read_features

PROBE_M = 0.5          # how far outside a face its "open ground" probe sits
GROUND_MARGIN_M = 30.0  # the ground extends this far beyond buildings and trees


@dataclass(frozen=True)
class Building:
    """A footprint (shapely Polygon, local frame) extruded to ``height_m``."""

    id: str
    polygon: object
    height_m: float
    facade_reflectance: float
    storeys: int
    window_to_wall: float | None

    @property
    def material(self) -> str:
        return f"facade_{round(self.facade_reflectance * 100):02d}"


@dataclass(frozen=True)
class Facade:
    """One face of a building: from ``start`` to ``end`` (x, y m), outward ``normal``."""

    building: str
    index: int
    start: np.ndarray
    end: np.ndarray
    normal: np.ndarray
    height_m: float
    storeys: int

    @property
    def id(self) -> str:
        return f"{self.building}:{self.index}"

    @property
    def length_m(self) -> float:
        return float(np.linalg.norm(self.end - self.start))

    @property
    def azimuth_deg(self) -> float:
        """Compass direction the face looks towards (clockwise from north)."""
        return (round(math.degrees(math.atan2(self.normal[0], self.normal[1])), 6) + 360.0) % 360.0


def read_buildings(path: Path, frame_crs: str, latitude: float, longitude: float,
                   storey_height_m: float) -> tuple[list[Building], LocalFrame]:
    """Footprints in the local frame, each checked (ConfigError naming the feature id)."""
    from shapely.geometry import Polygon
    from shapely.geometry.polygon import orient
    from shapely.validation import explain_validity

    src = str(path)
    feats, crs = read_features(path, frame_crs, "Polygon", "B")
    frame = LocalFrame(crs, latitude, longitude)
    out = []
    for f in feats:
        where = f"feature {f.id!r}"
        try:
            ring = np.array([[float(v) for v in c[:2]] for c in f.coords[0]])
        except (TypeError, ValueError, IndexError):
            raise ConfigError("footprint coordinates are not a polygon ring", source=src,
                              field=where) from None
        if len(f.coords) > 1:
            raise ConfigError("footprints with courtyards (interior rings) are not supported",
                              source=src, field=where)
        x, y = frame.to_local(ring[:, 0], ring[:, 1])
        poly = Polygon(np.column_stack([x, y]))
        if not poly.is_valid:
            raise ConfigError(f"invalid footprint: {explain_validity(poly)} (a self-"
                              "intersecting ring?)", source=src, field=where)
        if poly.area < 1.0:
            raise ConfigError(f"footprint of {poly.area:.2f} m² (degenerate)", source=src,
                              field=where)
        h = number(f, "height_m", src)
        rho = number(f, "facade_reflectance", src, lo=0.0, lo_open=False, hi=1.0, default=0.5)
        st = int(number(f, "storeys", src, default=max(1.0, math.floor(h / storey_height_m))))
        wwr = number(f, "window_to_wall", src, lo=0.0, lo_open=False, hi=1.0, default=-1.0) \
            if "window_to_wall" in f.props else None
        out.append(Building(f.id, orient(poly, 1.0), h, rho, max(1, st), wwr))
    raw = np.array([[float(v) for v in np.mean(np.asarray(f.coords[0], float)[:, :2], axis=0)]
                    for f in feats]).reshape(-1, 2)
    check_spread([b.id for b in out], raw,
                 np.array([list(b.polygon.centroid.coords)[0]  # type: ignore[attr-defined]
                           for b in out]).reshape(-1, 2),
                 frame, src, "building")
    for i, a in enumerate(out):
        for b in out[i + 1:]:
            if a.polygon.intersection(b.polygon).area > 0.01:   # type: ignore[attr-defined]
                raise ConfigError(f"footprint overlaps building {b.id!r}", source=src,
                                  field=f"feature {a.id!r}")
    return out, frame


def building_faces(buildings: list[Building]) -> list[Facade]:
    """Every face of every footprint (counter-clockwise exterior ring)."""
    out = []
    for b in buildings:
        ring = np.asarray(b.polygon.exterior.coords)[:-1]   # type: ignore[attr-defined]
        n = len(ring)
        for k in range(n):
            p, q = ring[k], ring[(k + 1) % n]
            d = q - p
            length = float(np.hypot(*d))
            if length < 1e-6:
                continue
            normal = np.array([d[1], -d[0]]) / length
            out.append(Facade(b.id, k, p, q, normal, b.height_m, b.storeys))
    return out


def select_facades(buildings: list[Building], selection: tuple[str, ...], source: str
                   ) -> list[Facade]:
    """``("street",)``: the faces towards open ground; else the named ``BUILDING:FACE``."""
    from shapely.geometry import Point

    faces = building_faces(buildings)
    if tuple(selection) == ("street",):
        polys = [(b.id, b.polygon) for b in buildings]
        keep = []
        for f in faces:
            mid = 0.5 * (f.start + f.end) + PROBE_M * f.normal
            pt = Point(mid)
            if not any(bid != f.building and p.contains(pt)  # type: ignore[attr-defined]
                       for bid, p in polys):
                keep.append(f)
        return keep
    by_id = {f.id: f for f in faces}
    chosen = []
    for s in selection:
        if s not in by_id:
            raise ConfigError(f"no façade {s!r} (faces are BUILDING:INDEX, e.g. "
                              f"{', '.join(list(by_id)[:4])} …)", source=source,
                              field="site.facades")
        chosen.append(by_id[s])
    return chosen


def facade_sensors(f: Facade, spacing_m: float, window_height_m: float, offset_m: float
                   ) -> tuple[np.ndarray, np.ndarray, list[int]]:
    """Points, normals and storey of the sensors of one façade."""
    n_along = max(1, int(math.floor(f.length_m / spacing_m)))
    t = (np.arange(n_along) + 0.5) / n_along
    storey_h = f.height_m / f.storeys
    pts, storeys = [], []
    for k in range(f.storeys):
        z = k * storey_h + min(window_height_m, 0.8 * storey_h)
        xy = f.start[None, :] + t[:, None] * (f.end - f.start)[None, :] + offset_m * f.normal
        pts.append(np.column_stack([xy, np.full(n_along, z)]))
        storeys += [k] * n_along
    points = np.vstack(pts)
    normals = np.tile([f.normal[0], f.normal[1], 0.0], (len(points), 1))
    return points, normals, storeys


def facade_grids(facades: list[Facade], spacing_m: float, window_height_m: float,
                 offset_m: float, chunk: int) -> dict[str, SensorGrid]:
    """Sensor grids ``facades_000``, ``facades_001`` … of ``chunk`` façades each (the unit of
    work of a distributed run); every sensor labelled building, façade and storey."""
    grids = {}
    for c0 in range(0, len(facades), chunk):
        pts, nrm, rows = [], [], []
        labels: dict[str, list] = {"building": [], "facade": [], "storey": []}
        for f in facades[c0:c0 + chunk]:
            p, n, st = facade_sensors(f, spacing_m, window_height_m, offset_m)
            pts.append(p)
            nrm.append(n)
            rows += [f"storey {k}" for k in st]
            labels["building"] += [f.building] * len(p)
            labels["facade"] += [f.id] * len(p)
            labels["storey"] += st
        name = f"facades_{c0 // chunk:03d}"
        grids[name] = SensorGrid(name, np.vstack(pts), np.vstack(nrm), rows, labels)
    return grids


def building_meshes(buildings: list[Building]) -> tuple[list[Mesh], dict[str, Plastic]]:
    """Walls (one quad per face) and the flat roof (``shapely.constrained_delaunay_triangles``
    of the footprint) of each building, floors left out (the street is the ground); one
    material per façade reflectance (roofs too: a documented simplification)."""
    import shapely

    meshes, materials = [], {}
    for b in buildings:
        ring = np.asarray(b.polygon.exterior.coords)[:-1]   # type: ignore[attr-defined]
        n = len(ring)
        verts = [np.column_stack([ring, np.zeros(n)]), np.column_stack([ring, np.full(n, b.height_m)])]
        faces = []
        for k in range(n):
            j = (k + 1) % n
            faces += [[k, j, n + j], [k, n + j, n + k]]
        tris = shapely.get_parts(shapely.constrained_delaunay_triangles(b.polygon))
        roof = [np.asarray(t.exterior.coords)[:3] for t in tris]
        base = 2 * n
        for i, t in enumerate(roof):
            verts.append(np.column_stack([t, np.full(3, b.height_m)]))
            faces.append([base + 3 * i, base + 3 * i + 1, base + 3 * i + 2])
        meshes.append(Mesh(f"building_{b.id}", b.material, np.vstack(verts), np.array(faces)))
        materials[b.material] = Plastic(b.material, b.facade_reflectance)
    return meshes, materials


def ground_mesh(buildings: list[Building], trees: list[InventoryTree]) -> Mesh:
    """The street and open ground: one rectangle around everything, ``GROUND_MARGIN_M`` wider."""
    xy = [np.asarray(b.polygon.exterior.coords) for b in buildings]  # type: ignore[attr-defined]
    xy += [np.array([[t.x, t.y]]) for t in trees]
    allxy = np.vstack(xy)
    lo = allxy.min(axis=0) - GROUND_MARGIN_M
    hi = allxy.max(axis=0) + GROUND_MARGIN_M
    return quad("ground", "ground", np.array([[lo[0], lo[1], 0], [hi[0], lo[1], 0],
                                               [hi[0], hi[1], 0], [lo[0], hi[1], 0]]))


@dataclass(frozen=True)
class WallContact:
    """A wall near a crown: its name, the wall's nearest point to the trunk (x, y m), the
    unit normal from the wall towards the trunk, and the trunk axis' distance to the wall (m)."""

    wall: str
    point: np.ndarray
    normal: np.ndarray
    distance_m: float


def check_trees_against_buildings(trees: list[InventoryTree], buildings: list[Building],
                                  source: str, margin: float = 0.0
                                  ) -> dict[str, list[WallContact]]:
    """A trunk inside a footprint is an error naming the tree's feature id. Returns, per tree,
    the buildings whose walls below the roof its crown comes within ``margin`` m of (the
    crown–wall policy, :mod:`radtree.trees.wall_policy`, decides what is done)."""
    from shapely.geometry import Point
    from shapely.ops import nearest_points

    out: dict[str, list[WallContact]] = {}
    for t in trees:
        p = Point(t.x, t.y)
        for b in buildings:
            poly = b.polygon
            if poly.contains(p):   # type: ignore[attr-defined]
                raise ConfigError(f"tree stands inside building {b.id!r}", source=source,
                                  field=f"feature {t.id!r}")
            if t.crown_base_m < b.height_m:
                gap = poly.exterior.distance(p)   # type: ignore[attr-defined]
                if gap < t.plan_reach_m + margin:   # the outline's farthest, if any
                    q = nearest_points(poly.exterior, p)[0]   # type: ignore[attr-defined]
                    foot = np.array([q.x, q.y])
                    normal = (np.array([t.x, t.y]) - foot) / max(gap, 1e-12)
                    out.setdefault(t.id, []).append(WallContact(
                        f"a wall of building {b.id!r}", foot, normal, float(gap)))
    return out
