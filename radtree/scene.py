"""The in-memory scene: triangle meshes tagged with material names, materials, sensor grids.

A scene is plain data, shared by both engines. Coordinates in metres, x east, y north, z up.
Illuminance sensors are points with a unit normal (the sensor's facing) and a row label.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from radtree.media_voxels import Media
from radtree.optics import Hole, Material


@dataclass
class Mesh:
    """A triangle mesh made of one material.

    ``vertices`` (N, 3) float metres; ``faces`` (M, 3) int indices into ``vertices``. Triangles are
    two-sided for both engines (Radiance polygons are two-sided for plastic/trans/glass).
    ``owners`` (M,) str, optional: the tree each face belongs to (an inventory tree's id, a
    row crown's number; ``""`` = none) — what :meth:`Scene.without_owners` removes and what an
    engine attributing light to trees names (:mod:`radtree.engines.numpy.attribution`).
    """

    name: str
    material: str
    vertices: np.ndarray
    faces: np.ndarray
    owners: np.ndarray | None = None

    def __post_init__(self) -> None:
        self.vertices = np.asarray(self.vertices, dtype=float).reshape(-1, 3)
        self.faces = np.asarray(self.faces, dtype=np.int64).reshape(-1, 3)
        if len(self.faces) and (self.faces.min() < 0 or self.faces.max() >= len(self.vertices)):
            raise ValueError(f"mesh '{self.name}': face index outside its {len(self.vertices)} vertices")
        if not np.all(np.isfinite(self.vertices)):
            raise ValueError(f"mesh '{self.name}': vertices must be finite")
        if self.owners is not None:
            self.owners = np.asarray(self.owners, dtype=str).reshape(-1)
            if len(self.owners) != len(self.faces):
                raise ValueError(f"mesh '{self.name}': one owner per face is needed")

    @property
    def n_triangles(self) -> int:
        return int(len(self.faces))

    @property
    def triangles(self) -> np.ndarray:
        """(M, 3, 3) triangle corner coordinates."""
        return self.vertices[self.faces]

    def area(self) -> float:
        t = self.triangles
        return float(0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1).sum())

    @staticmethod
    def merge(name: str, material: str, meshes: list[Mesh]) -> Mesh:
        verts, faces, offset = [], [], 0
        for m in meshes:
            verts.append(m.vertices)
            faces.append(m.faces + offset)
            offset += len(m.vertices)
        if not verts:
            return Mesh(name, material, np.zeros((0, 3)), np.zeros((0, 3), int))
        owners = None
        if any(m.owners is not None for m in meshes):
            owners = np.concatenate([m.owners if m.owners is not None
                                     else np.full(m.n_triangles, "") for m in meshes])
        return Mesh(name, material, np.vstack(verts), np.vstack(faces), owners)


def quad(name: str, material: str, corners: np.ndarray) -> Mesh:
    """A planar quadrilateral (4 corners in order) as two triangles."""
    return Mesh(name, material, np.asarray(corners, float), np.array([[0, 1, 2], [0, 2, 3]]))


@dataclass
class SensorGrid:
    """Named illuminance sensors: ``points`` (N, 3) m, unit ``normals`` (N, 3), ``rows`` labels;
    ``labels``: further per-sensor columns of the results table (e.g. building, facade, storey)."""

    name: str
    points: np.ndarray
    normals: np.ndarray
    rows: list[str] = field(default_factory=list)
    labels: dict[str, list] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.points = np.asarray(self.points, dtype=float).reshape(-1, 3)
        self.normals = np.asarray(self.normals, dtype=float).reshape(-1, 3)
        if len(self.points) == 0:
            raise ValueError(f"sensor grid '{self.name}' has no points")
        if self.normals.shape != self.points.shape:
            raise ValueError(f"sensor grid '{self.name}': one normal per point is needed")
        norms = np.linalg.norm(self.normals, axis=1)
        if np.any(norms < 1e-9):
            raise ValueError(f"sensor grid '{self.name}': zero-length normal")
        self.normals = self.normals / norms[:, None]
        if not self.rows:
            self.rows = [""] * len(self.points)
        if len(self.rows) != len(self.points):
            raise ValueError(f"sensor grid '{self.name}': one row label per point is needed")
        for key, values in self.labels.items():
            if len(values) != len(self.points):
                raise ValueError(f"sensor grid '{self.name}': one {key} per point is needed")

    def __len__(self) -> int:
        return len(self.points)

    def to_pts(self) -> str:
        """Radiance ``rtrace`` input: one ``x y z dx dy dz`` line per sensor."""
        lines = [
            " ".join(f"{v:.6f}" for v in (*p, *n)) for p, n in zip(self.points, self.normals)
        ]
        return "\n".join(lines) + "\n"


@dataclass(frozen=True)
class Instance:
    """A placed copy of a prototype (a list of meshes in its own frame): rotated
    ``rotate_z_deg`` counter-clockwise about +z, scaled uniformly by ``scale``, then moved by
    ``translate`` (m) — Radiance's ``-rz A -s S -t X Y Z`` order. ``owner``: the tree the
    copy is (as :attr:`Mesh.owners`), ``""`` = none."""

    prototype: str
    translate: tuple[float, float, float]
    rotate_z_deg: float = 0.0
    scale: float = 1.0
    owner: str = ""

    def apply(self, v: np.ndarray) -> np.ndarray:
        a = np.radians(self.rotate_z_deg)
        c, s = np.cos(a), np.sin(a)
        rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        return (np.asarray(v, float) @ rot.T) * self.scale + np.asarray(self.translate, float)


@dataclass
class Scene:
    """Geometry + materials + sensor grids. ``notes`` say what the scene contains, for reports.

    ``prototypes`` (name → meshes) placed by ``instances``: an engine that instances
    (Radiance) writes each prototype once; the others see them expanded by
    :meth:`solid_meshes` (cost: :meth:`instanced_triangles`)."""

    meshes: list[Mesh]
    materials: dict[str, Material]
    grids: dict[str, SensorGrid]
    notes: list[str] = field(default_factory=list)
    ground_material: str = "ground"
    prototypes: dict[str, list[Mesh]] = field(default_factory=dict)
    instances: list[Instance] = field(default_factory=list)
    #: turbid-medium crowns (``[tree] representation = "turbid"``): spheroids, voxel grids or
    #: both (:mod:`radtree.media`, :mod:`radtree.media_voxels`)
    media: Media | None = None

    def __post_init__(self) -> None:
        for m in [*self.meshes, *(p for ms in self.prototypes.values() for p in ms)]:
            if m.material not in self.materials:
                raise ValueError(f"mesh '{m.name}' uses undefined material '{m.material}'")
        for name in ([] if self.media is None else self.media.materials):
            if name not in self.materials:
                raise ValueError(f"turbid crowns use undefined material '{name}'")
        for inst in self.instances:
            if inst.prototype not in self.prototypes:
                raise ValueError(f"instance of unknown prototype '{inst.prototype}'")

    @property
    def n_triangles(self) -> int:
        """Triangles as stored (each prototype once)."""
        return (sum(m.n_triangles for m in self.meshes)
                + sum(m.n_triangles for ms in self.prototypes.values() for m in ms))

    def instanced_triangles(self) -> int:
        """Triangles the instances stand for when expanded."""
        per = {k: sum(m.n_triangles for m in ms) for k, ms in self.prototypes.items()}
        return sum(per[i.prototype] for i in self.instances)

    def own_solid_meshes(self) -> list[Mesh]:
        """Meshes that interact with light (holes left out), prototypes not expanded."""
        return [m for m in self.meshes if not isinstance(self.materials[m.material], Hole)]

    def solid_meshes(self) -> list[Mesh]:
        """Meshes that interact with light (holes left out), instances expanded."""
        out = self.own_solid_meshes()
        for k, inst in enumerate(self.instances):
            for m in self.prototypes[inst.prototype]:
                if not isinstance(self.materials[m.material], Hole):
                    owners = (np.full(m.n_triangles, inst.owner) if inst.owner
                              else m.owners)
                    out.append(Mesh(f"{m.name}@{k}", m.material, inst.apply(m.vertices),
                                    m.faces, owners))
        return out

    def owners(self) -> list[str]:
        """The trees whose faces the scene holds (:attr:`Mesh.owners`, :attr:`Instance.owner`),
        in order of first appearance."""
        seen: dict[str, None] = {}
        for inst in self.instances:
            if inst.owner:
                seen.setdefault(inst.owner)
        for m in [*self.meshes, *(p for ms in self.prototypes.values() for p in ms)]:
            if m.owners is not None:
                seen.update(dict.fromkeys(str(o) for o in dict.fromkeys(m.owners.tolist()) if o))
        return list(seen)

    def without_owners(self, owners: set[str] | None = None) -> Scene:
        """The same scene without the faces of ``owners`` (default: every owned face) — the
        scene with those trees removed; grids, materials and notes shared."""
        def gone(o: np.ndarray) -> np.ndarray:
            return (o != "") if owners is None else np.isin(o, list(owners))

        def keep(m: Mesh) -> Mesh | None:
            if m.owners is None:
                return m
            k = ~gone(m.owners)
            if k.all():
                return m
            if not k.any():
                return None
            return Mesh(m.name, m.material, m.vertices, m.faces[k], m.owners[k])

        meshes = [k for k in (keep(m) for m in self.meshes) if k is not None]
        protos = {n: [k for k in (keep(m) for m in ms) if k is not None]
                  for n, ms in self.prototypes.items()}
        insts = [i for i in self.instances
                 if not (i.owner and (owners is None or i.owner in owners))]
        used = {i.prototype for i in insts}
        return Scene(meshes, self.materials, self.grids, list(self.notes), self.ground_material,
                     {n: ms for n, ms in protos.items() if n in used}, insts)

    def mesh(self, name: str) -> Mesh:
        for m in self.meshes:
            if m.name == name:
                return m
        raise KeyError(name)
