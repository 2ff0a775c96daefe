"""The glTF export read back by a reader radtree did not write (``radtree verify``, path *glTF
export*).

``radtree export --format gltf`` writes the scene with trimesh; :func:`read_glb` reads the
binary glTF with nothing but the Khronos glTF 2.0 specification (§4.4 binary header and
chunks, §5.1 accessors, §3.7.2 component types, §5.25 node ``matrix`` / TRS, glTF's +Y up):
no trimesh, no glTF library, so a fault in the writer or in trimesh's reading of its own file
cannot hide. Compared with the in-memory scene (:func:`radtree.pipeline.assemble.make_scene`):
the triangle count of every mesh (exact), the leaf area (m²) and the scene's bounding box (m).

Claims: positions are stored as 32-bit floats (componentType 5126), whose relative rounding is
at most 2⁻²⁴ ≈ 6e-8 (IEEE 754 binary32, 24-bit significand): a coordinate within 100 m of the
origin moves by ≤ 6e-6 m, so the bounding box is claimed within 1e-5 m; a leaf's area
(side ≥ 5 cm) by ≤ 2 × 6e-6 / 0.05 ≈ 2.4e-4 of itself in the worst case, and the sum over many
leaves (rounding errors of either sign) is claimed within 1e-4 of the total.
"""

from __future__ import annotations

import json
import struct
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from radtree.verify.checks import Check

#: glTF 2.0 §3.7.2.1 componentType → NumPy type (little-endian)
COMPONENT = {5120: "<i1", 5121: "<u1", 5122: "<i2", 5123: "<u2", 5125: "<u4", 5126: "<f4"}
WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}
TRIANGLES = 4
AREA_CLAIM, BOX_CLAIM = 1e-4, 1e-5
REFERENCE = "the .glb parsed from the Khronos glTF 2.0 specification (no trimesh)"


@dataclass(frozen=True)
class GlbMesh:
    """One node's triangles in the file's world frame (glTF: metres, +Y up)."""

    name: str
    triangles: np.ndarray       # (n, 3, 3)


def _accessor(doc: dict, binary: bytes, index: int) -> np.ndarray:
    acc = doc["accessors"][index]
    view = doc["bufferViews"][acc["bufferView"]]
    dtype = np.dtype(COMPONENT[acc["componentType"]])
    width = WIDTH[acc["type"]]
    start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
    stride = view.get("byteStride", 0) or dtype.itemsize * width
    rows = [np.frombuffer(binary, dtype, width, start + k * stride) for k in range(acc["count"])] \
        if stride != dtype.itemsize * width else \
        [np.frombuffer(binary, dtype, width * acc["count"], start)]
    return np.concatenate(rows).reshape(acc["count"], width)


def _local(node: dict) -> np.ndarray:
    """The node's 4 × 4 transform (§5.25: ``matrix`` column-major, else T · R · S)."""
    if "matrix" in node:
        return np.asarray(node["matrix"], float).reshape(4, 4).T
    x, y, z, w = node.get("rotation", [0.0, 0.0, 0.0, 1.0])
    r = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                  [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                  [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    m = np.eye(4)
    m[:3, :3] = r * np.asarray(node.get("scale", [1.0, 1.0, 1.0]))
    m[:3, 3] = node.get("translation", [0.0, 0.0, 0.0])
    return m


def _primitive(doc: dict, binary: bytes, prim: dict) -> np.ndarray:
    if prim.get("mode", TRIANGLES) != TRIANGLES:
        raise ValueError(f"primitive mode {prim['mode']}: only triangles (4) are read")
    pos = _accessor(doc, binary, prim["attributes"]["POSITION"]).astype(float)
    idx = (_accessor(doc, binary, prim["indices"]).ravel() if "indices" in prim
           else np.arange(len(pos)))
    return pos[idx.reshape(-1, 3)]


def read_glb(path: Path) -> list[GlbMesh]:
    """Every mesh node of the default scene of a binary glTF, its triangles transformed to the
    world frame (§4.4: 12-byte header ``glTF``, version 2; a JSON chunk, then a BIN chunk)."""
    data = Path(path).read_bytes()
    magic, version, length = struct.unpack_from("<4sII", data, 0)
    if magic != b"glTF" or version != 2 or length != len(data):
        raise ValueError(f"{path}: not a glTF 2.0 binary file")
    json_len, json_type = struct.unpack_from("<I4s", data, 12)
    doc = json.loads(data[20:20 + json_len])
    bin_start = 20 + json_len
    bin_len, bin_type = struct.unpack_from("<I4s", data, bin_start)
    if json_type != b"JSON" or bin_type != b"BIN\0":
        raise ValueError(f"{path}: chunks {json_type!r}, {bin_type!r}")
    binary = data[bin_start + 8:bin_start + 8 + bin_len]
    out: list[GlbMesh] = []

    def visit(index: int, parent: np.ndarray) -> None:
        node = doc["nodes"][index]
        world = parent @ _local(node)
        if "mesh" in node:
            tris = np.concatenate([_primitive(doc, binary, p)
                                   for p in doc["meshes"][node["mesh"]]["primitives"]])
            flat = np.c_[tris.reshape(-1, 3), np.ones(tris.size // 3)] @ world.T
            out.append(GlbMesh(node.get("name", str(index)), flat[:, :3].reshape(-1, 3, 3)))
        for child in node.get("children", []):
            visit(child, world)

    for root in doc["scenes"][doc.get("scene", 0)]["nodes"]:
        visit(root, np.eye(4))
    return out


def z_up(points: np.ndarray) -> np.ndarray:
    """glTF's +Y-up frame → radtree's (x east, y north, z up): (x, y, z) → (x, −z, y)."""
    return np.stack([points[..., 0], -points[..., 2], points[..., 1]], axis=-1)


def _area(tris: np.ndarray) -> float:
    return float(0.5 * np.linalg.norm(np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0]),
                                      axis=1).sum())


def gltf_checks(project=None, scenario: str | None = None,
                folder: Path | None = None) -> list[Check]:
    """``radtree export --format gltf`` of ``scenario`` of ``project`` (default: the Mendoza
    example's scenario A, the louvers dome) read back by :func:`read_glb` against the scene
    it was written from."""
    from radtree.config import load_project
    from radtree.export.run import ExportOptions, export_project
    from radtree.pipeline.assemble import make_scene
    from radtree.verify.compare import MENDOZA

    project = project or load_project(MENDOZA)
    sc = project.scenario(scenario) if scenario else project.scenarios[0]
    with tempfile.TemporaryDirectory(prefix="radtree-verify-gltf-") as tmp:
        (path,) = export_project(project, options=ExportOptions(
            "gltf", Path(folder or tmp), scenario=sc.name))
        read = {m.name: z_up(m.triangles) for m in read_glb(path)}
    scene = make_scene(project, sc).scene
    meshes = {m.name: m for m in scene.solid_meshes() if m.n_triangles}
    what = f"glTF export of {project.name} {sc.name}, read back"
    # a mesh counts only when its node holds exactly its triangles; a stray node counts against
    count = sum(m.n_triangles for n, m in meshes.items()
                if n in read and len(read[n]) == m.n_triangles) - sum(
        len(t) for n, t in read.items() if n not in meshes)
    leaves = [n for n in meshes if "leaves" in n]
    area = sum(meshes[n].area() for n in leaves)
    got_area = sum(_area(read[n]) for n in leaves if n in read)
    ours = np.concatenate([m.vertices[m.faces].reshape(-1, 3) for m in meshes.values()])
    theirs = np.concatenate([t.reshape(-1, 3) for t in read.values()])
    box = float(np.abs(np.r_[ours.min(0) - theirs.min(0), ours.max(0) - theirs.max(0)]).max())
    total = sum(m.n_triangles for m in meshes.values())
    return [
        Check(f"{what}: triangles of every mesh, by name ({len(meshes)} meshes)", "-",
              float(total), float(count), 0.0, 0.0, REFERENCE),
        Check(f"{what}: leaf area (m²)", "-", area, got_area, AREA_CLAIM * area,
              AREA_CLAIM * area, REFERENCE + "; float32 positions (IEEE 754)"),
        Check(f"{what}: bounding box, largest corner deviation (m)", "-", 0.0, box, BOX_CLAIM,
              BOX_CLAIM, REFERENCE + "; float32 positions (IEEE 754)"),
    ]
