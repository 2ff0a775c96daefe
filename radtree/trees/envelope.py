"""Crown envelopes in the façade frame: the sensor dome and the row of free-standing crowns.

**Sensor dome (study form).** A hemisphere of radius ``tree.dome.radius_m`` centred on the
sensor circle's centre on the wall (u = sensors.x_m, n = 0, z = sensors.height_m), flat side
on the façade: the half-ball n ≥ 0. Everything the façade sensors see passes through it. It
must clear the street (radius < sensor height), enclose the sensor circle and stay short of
the opposite façade. No trunk: the study's dome has none.

**Free-standing crowns.** ``crown.count`` spheroids (horizontal semi-axis ``radius_m``,
vertical semi-axis ``vertical_radius_m``, lowest point at ``base_height_m``) centred on
trunks ``trunk_distance_m`` from the façade, every ``spacing_m`` along it, the row centred on
the sensors (u = sensors.x_m). Where neighbouring crowns overlap (spacing < 2·radius) the row
is one envelope: each crown keeps the strip of u closer to its own trunk, so no sheet lies
inside the union. Each crown is clipped by the plane

    n = n_clip = max(crown.clearance_m, sensors.offset_m + 5 mm)

i.e. with clearance 0 the crown reaches the wall but stops 5 mm in front of the sensors (which
sit ``offset_m`` off the wall), so it never cuts the façade nor contains a sensor point. The
envelope surface is the convex hull of points on the clipped spheroid (radial projection of an
icosphere from an interior point), so every straight line crosses one crown's envelope at
most twice. Trunks are vertical cylinders (bark, reflectance 0.2) from the street to half the
vertical semi-axis into the crown.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from radtree.config import Sensors, Street, Tree
from radtree.errors import ConfigError
from radtree.trees.geometry import cylinder_mesh, hemisphere_mesh
from radtree.trees.outline import CrownOutline
from radtree.trees.wall_policy import WallReach, apply_wall_policy

CLIP_MARGIN_M = 0.005  # crown stops this far in front of the sensors when clearance is 0


# ---------------------------------------------------------------- sensor dome
@dataclass(frozen=True)
class DomeSpec:
    """The sensor dome in local coordinates."""

    centre: np.ndarray  # (u, n, z) with n = 0
    radius: float
    segments: int

    def shell(self, rings: int) -> tuple[np.ndarray, np.ndarray]:
        """Local vertices and faces of the hemispherical shell (``rings`` polar rings)."""
        dirs, faces = hemisphere_mesh(rings)
        return self.centre + self.radius * dirs, faces


def dome_spec(tree: Tree, sensors: Sensors, street: Street, source: str | None = None
              ) -> DomeSpec:
    """Validate and lay out the sensor dome."""
    r = tree.dome.radius_m
    h = sensors.height_m
    if not r > 0:
        raise ConfigError(f"got {r}, expected a positive dome radius", source=source,
                          field="tree.dome.radius_m")
    if r >= h:
        raise ConfigError(
            f"the sensor dome must clear the street: radius {r:g} m is not below the sensor "
            f"height {h:g} m (sensors.height_m); choose tree.dome.radius_m < {h:g}",
            source=source, field="tree.dome.radius_m")
    need = sensors.radius_m + sensors.offset_m + 0.05
    if r <= need:
        raise ConfigError(
            f"the sensor dome must enclose the sensor circle: radius {r:g} m ≤ {need:.2f} m "
            "(sensors.radius_m + offset + 5 cm)", source=source, field="tree.dome.radius_m")
    if r >= street.width_m:
        raise ConfigError(
            f"the sensor dome (radius {r:g} m) reaches the opposite façade "
            f"(street width {street.width_m:g} m)", source=source, field="tree.dome.radius_m")
    if tree.dome.segments < 4:
        raise ConfigError(f"got {tree.dome.segments}, expected at least 4 segments",
                          source=source, field="tree.dome.segments")
    centre = np.array([sensors.x_m, 0.0, h])
    return DomeSpec(centre=centre, radius=r, segments=tree.dome.segments)


def dome_notes(spec: DomeSpec) -> list[str]:
    """What the sensor-dome form is and implies, for reports."""
    return [f"Sensor dome (study form): hemisphere of radius {spec.radius:g} m centred on the "
            f"sensor circle (u = {spec.centre[0]:g} m, z = {spec.centre[2]:g} m), flat side on "
            "the façade; no trunk. Everything the sensors see passes through it — including "
            "light reflected by the street, which under a real crown arrives from below almost "
            "unfiltered."]


# ---------------------------------------------------------------- free-standing crowns
@dataclass(frozen=True)
class CrownRowSpec:
    """A row of clipped spheroidal crowns in local coordinates."""

    centres: np.ndarray  # (count, 3) spheroid centres (u_i, trunk distance, base + b)
    a: float  # horizontal semi-axis
    b: float  # vertical semi-axis
    n_clip: float  # crowns keep n ≥ n_clip
    strips: np.ndarray  # (count, 2) u-limits of each crown's share of the row (±inf: none)
    trunk_radius: float
    trunk_top: float
    #: a one-crown row's plan outline (:mod:`radtree.trees.outline`): the crown follows it
    outline: CrownOutline | None = None

    def __post_init__(self) -> None:
        if self.outline is not None and len(self.centres) != 1:
            raise ValueError("a crown outline is for a row of one crown")

    @property
    def count(self) -> int:
        return len(self.centres)

    @property
    def max_radius(self) -> float:
        """The farthest plan reach of a crown from its trunk axis (m): a, or the outline's."""
        return self.a if self.outline is None else self.outline.max_radius_m

    def reach(self, offsets: np.ndarray) -> np.ndarray:
        """The crown's plan radius r(θ) towards plan offsets (…, 2) from its trunk axis (m):
        a for the spheroid, the outline's radial function otherwise."""
        if self.outline is None:
            return np.full(np.shape(offsets)[:-1], self.a)
        return self.outline.reach(offsets)

    def crown_volume(self) -> float:
        """Volume of one unclipped crown (m³): 4/3·π a² b, or 4/3·b·A with A the outline's
        plan area (:mod:`radtree.trees.outline`)."""
        area = math.pi * self.a ** 2 if self.outline is None else self.outline.area_m2
        return 4.0 / 3.0 * area * self.b

    def from_ball(self, x: np.ndarray) -> np.ndarray:
        """Offsets from a crown's centre of points ``x`` (k, 3) uniform in the unit ball,
        mapped to points uniform in the crown: x·(a, a, b), or into the outline."""
        if self.outline is None:
            return np.asarray(x, float) * np.array([self.a, self.a, self.b])
        return self.outline.from_ball(x, b=self.b)

    def crown_ids(self, points: np.ndarray) -> np.ndarray:
        """The crown each local point (k, 3) belongs to by its share of the row (``strips``,
        along u): ``"C1"`` … ``"C<count>"`` in row order, ``""`` outside every share — the
        faces' :attr:`radtree.scene.Mesh.owners`."""
        u = np.asarray(points, float).reshape(-1, 3)[:, 0]
        out = np.full(len(u), "", dtype=object)
        for i, (lo, hi) in enumerate(self.strips):
            out[(out == "") & (u >= lo) & (u <= hi)] = f"C{i + 1}"
        return out.astype(str)

    def trunk_ids(self, n_faces: int) -> np.ndarray:
        """The crown of each of the ``n_faces`` faces of :meth:`trunks` (one trunk per crown,
        in row order, each with the same number of faces)."""
        return np.repeat([f"C{i + 1}" for i in range(self.count)], n_faces // self.count)

    def camera(self, sensors: Sensors) -> np.ndarray:
        """The photo point: the sensor circle's centre on the wall."""
        return np.array([sensors.x_m, 0.0, sensors.height_m])

    def inside(self, points: np.ndarray, margin: float = 0.0) -> np.ndarray:
        """Points (k, 3) inside the union of the clipped crowns (shrunk by ``margin`` m)."""
        p = np.asarray(points, float).reshape(-1, 3)
        res = np.zeros(len(p), bool)
        for c, (lo, hi) in zip(self.centres, self.strips):
            a = self.reach(p[:, :2] - c[:2]) - margin
            b = self.b - margin
            horizontal = (p[:, 0] - c[0]) ** 2 + (p[:, 1] - c[1]) ** 2
            q = horizontal / a**2 + (p[:, 2] - c[2]) ** 2 / b**2
            res |= ((q <= 1.0) & (p[:, 1] >= self.n_clip + margin) & (p[:, 0] >= lo)
                    & (p[:, 0] <= hi))
        return res

    def hull_point(self, i: int) -> np.ndarray:
        """An interior point of crown i from which its clipped envelope is star-shaped."""
        c = self.centres[i]
        n_lo = max(c[1] - self.a, self.n_clip)
        return np.array([c[0], 0.5 * (n_lo + c[1] + self.a), c[2]])

    def envelope(self, i: int, subdivisions: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Crown i's envelope: local vertices, faces, and a mask of faces on the wall-side
        clip plane (the "wall cap"). Faces on the planes shared with neighbours are dropped.
        Spheroids only: a crown following an outline has no hull mesh (ValueError)."""
        if self.outline is not None:
            raise ValueError("a crown following its outline has no envelope mesh")
        import trimesh  # here: importing it takes ~1 s, and most builds never get here

        sphere = trimesh.creation.icosphere(subdivisions=subdivisions)
        d = np.asarray(sphere.vertices, float)
        d = d / np.linalg.norm(d, axis=1)[:, None]
        q = self.hull_point(i)
        c = self.centres[i]
        w = q - c
        A = (d[:, 0] ** 2 + d[:, 1] ** 2) / self.a**2 + d[:, 2] ** 2 / self.b**2
        B = 2.0 * ((w[0] * d[:, 0] + w[1] * d[:, 1]) / self.a**2 + w[2] * d[:, 2] / self.b**2)
        C = (w[0] ** 2 + w[1] ** 2) / self.a**2 + w[2] ** 2 / self.b**2 - 1.0
        t = (-B + np.sqrt(B * B - 4.0 * A * C)) / (2.0 * A)
        kind = np.zeros(len(d), int)  # 0 spheroid, 1 wall plane, 2 low strip, 3 high strip
        with np.errstate(divide="ignore", invalid="ignore"):
            tw = np.where(d[:, 1] < -1e-12, (self.n_clip - q[1]) / d[:, 1], np.inf)
            lo, hi = self.strips[i]
            tl = np.where(d[:, 0] < -1e-12, (lo - q[0]) / d[:, 0], np.inf)
            th = np.where(d[:, 0] > 1e-12, (hi - q[0]) / d[:, 0], np.inf)
        for k, tk in ((1, tw), (2, tl), (3, th)):
            sel = tk < t
            t = np.where(sel, tk, t)
            kind = np.where(sel, k, kind)
        pts = q + t[:, None] * d
        pts[kind == 1, 1] = self.n_clip
        pts[kind == 2, 0] = self.strips[i][0]
        pts[kind == 3, 0] = self.strips[i][1]
        hull = trimesh.convex.convex_hull(pts)
        verts = np.asarray(hull.vertices, float)
        faces = np.asarray(hull.faces, np.int64)
        fv = verts[faces]
        on_wall = np.all(np.abs(fv[:, :, 1] - self.n_clip) < 1e-9, axis=1)
        shared = np.zeros(len(faces), bool)
        for lim in self.strips[i]:
            if np.isfinite(lim):
                shared |= np.all(np.abs(fv[:, :, 0] - lim) < 1e-9, axis=1)
        keep = ~shared
        return verts, faces[keep], on_wall[keep]

    def trunks(self, segments: int = 16) -> tuple[np.ndarray, np.ndarray]:
        verts, faces, off = [], [], 0
        for c in self.centres:
            v, f = cylinder_mesh((c[0], c[1]), self.trunk_radius, 0.0, self.trunk_top, segments)
            verts.append(v)
            faces.append(f + off)
            off += len(v)
        return np.vstack(verts), np.vstack(faces)


def clip_plane(tree: Tree, sensors: Sensors) -> float:
    """n of the wall-side clip plane: max(clearance, sensor offset + 5 mm)."""
    return max(tree.crown.clearance_m, sensors.offset_m + CLIP_MARGIN_M)


def row_wall_reach(tree: Tree, sensors: Sensors) -> WallReach | None:
    """The row's crowns reaching the façade (all alike), or None (:mod:`.wall_policy`)."""
    cr = tree.crown
    d = cr.trunk_distance_m - clip_plane(tree, sensors)
    if cr.radius_m <= d:
        return None
    who = "the row's crown" if cr.count == 1 else f"each of the row's {cr.count} crowns"
    return WallReach(who, "the façade", cr.radius_m, d, "tree.crown.radius_m",
                     "[tree.crown] radius_m", "[tree.crown] trunk_distance_m")


def crown_row_spec(tree: Tree, sensors: Sensors, street: Street, source: str | None = None
                   ) -> CrownRowSpec:
    """Validate and lay out the row of free-standing crowns."""
    cr = tree.crown

    def err(fieldname: str, msg: str) -> ConfigError:
        return ConfigError(msg, source=source, field=f"tree.crown.{fieldname}")

    for name in ("trunk_distance_m", "radius_m", "vertical_radius_m", "base_height_m",
                 "trunk_diameter_m", "spacing_m"):
        if not getattr(cr, name) > 0:
            raise err(name, f"got {getattr(cr, name)}, expected a positive length")
    if cr.count < 1:
        raise err("count", f"got {cr.count}, expected at least one tree")
    if cr.clearance_m < 0:
        raise err("clearance_m", f"got {cr.clearance_m}, expected ≥ 0")
    n_clip = clip_plane(tree, sensors)
    rt = cr.trunk_diameter_m / 2.0
    if cr.trunk_distance_m - rt <= n_clip:
        raise err("trunk_distance_m",
                  f"the trunk (axis {cr.trunk_distance_m:g} m, radius {rt:g} m) must stand in "
                  f"front of the crown's wall-side clip plane at n = {n_clip:g} m")
    if cr.trunk_distance_m + cr.radius_m >= street.width_m:
        fit = math.floor((street.width_m - cr.trunk_distance_m) * 100.0 - 1e-6) / 100.0
        raise err("radius_m",
                  f"the crown reaches n = {cr.trunk_distance_m + cr.radius_m:g} m, beyond the "
                  f"opposite façade at {street.width_m:g} m (street.width_m): reduce radius_m "
                  f"below {street.width_m - cr.trunk_distance_m:g} m (e.g. {fit:.2f}) or widen "
                  "the street")
    reach = row_wall_reach(tree, sensors)
    if reach is not None:
        apply_wall_policy(tree.wall_policy, [reach], source)   # "refuse": its ConfigError
    if cr.count > 1 and cr.spacing_m <= 2.0 * rt:
        raise err("spacing_m", f"got {cr.spacing_m:g} m: trunks of diameter "
                               f"{cr.trunk_diameter_m:g} m would overlap")
    half_len = street.length_m / 2.0
    span = (cr.count - 1) * cr.spacing_m / 2.0 + cr.radius_m
    if span > half_len + abs(sensors.x_m):
        raise err("count", f"the row of {cr.count} crowns spans ±{span:g} m, beyond the "
                           f"modelled street (street.length_m {street.length_m:g} m)")
    if cr.segments < 4:
        raise err("segments", f"got {cr.segments}, expected at least 4")
    us = sensors.x_m + (np.arange(cr.count) - (cr.count - 1) / 2.0) * cr.spacing_m
    zc = cr.base_height_m + cr.vertical_radius_m
    centres = np.column_stack([us, np.full(cr.count, cr.trunk_distance_m), np.full(cr.count, zc)])
    strips = np.full((cr.count, 2), [-np.inf, np.inf])
    if cr.count > 1 and cr.spacing_m < 2.0 * cr.radius_m:
        mids = 0.5 * (us[:-1] + us[1:])
        strips[1:, 0] = mids
        strips[:-1, 1] = mids
    trunk_top = cr.base_height_m + 0.5 * cr.vertical_radius_m
    return CrownRowSpec(centres=centres, a=cr.radius_m, b=cr.vertical_radius_m, n_clip=n_clip,
                        strips=strips, trunk_radius=rt, trunk_top=trunk_top)


def icosphere_level(angular_step_deg: float) -> int:
    """Icosphere subdivision level whose edges subtend about ``angular_step_deg`` (1–5)."""
    level = math.ceil(math.log2(63.43 / max(angular_step_deg, 1e-3)))
    return int(min(5, max(1, level)))


def row_notes(spec: CrownRowSpec, tree: Tree, sensors: Sensors) -> list[str]:
    cr = tree.crown
    shape = (f"spheroid(s) of horizontal radius {spec.a:g} m and vertical semi-axis {spec.b:g} m"
             f", base {cr.base_height_m:g} m above the street")
    measured = tree.points or tree.voxels
    if measured is not None:   # the crown is the measured one; the spheroid only shares it out
        shape = (f"crown(s) from {Path(measured).name} (the row's shares between neighbours "
                 f"and the wall are cut along {shape})")
    notes = [
        f"Free-standing crowns: {spec.count} {shape}, on trunks ({cr.trunk_diameter_m:g} m) "
        f"{cr.trunk_distance_m:g} m from the façade, every {cr.spacing_m:g} m, centred on the "
        f"sensors (u = {sensors.x_m:g} m).",
    ]
    gap = spec.centres[0, 1] - spec.a
    if gap > spec.n_clip:
        notes.append(f"The crowns do not reach the wall: {gap:.2f} m of open air between crown "
                     "and façade (low sun can slip through).")
    elif cr.clearance_m > sensors.offset_m + CLIP_MARGIN_M:
        notes.append(f"Crowns clipped {spec.n_clip:g} m from the façade (crown.clearance_m).")
    else:
        notes.append(f"Crowns reach the wall (clearance {cr.clearance_m:g} m): clipped at "
                     f"n = {spec.n_clip:g} m, 5 mm in front of the sensors "
                     f"({sensors.offset_m:g} m off the wall), so no sensor lies inside a crown.")
    reach = row_wall_reach(tree, sensors)
    if reach is not None:
        notes += apply_wall_policy(tree.wall_policy, [reach], None)
    if np.isfinite(spec.strips).any():
        notes.append("Neighbouring crowns overlap; the row is one envelope (each crown keeps "
                     "the half of the overlap nearer its trunk).")
    return notes
