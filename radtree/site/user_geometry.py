"""User geometry from ``[[geometry]]`` tables: triangle meshes (OBJ/STL/PLY) or Radiance polygons.

Each table names a file and the material its surfaces are made of::

    [[geometry]]
    file = "data/kiosk.obj"        # OBJ, STL or PLY (read with trimesh) — or a .rad file
    material = "facade_paint"      # a material of the scene (street, office or crown model)

Coordinates are read as they are: metres, world axes (x east, y north, z up) — the same axes
as the generated street, whose studied façade lies in the plane through the origin facing
``street.facade_azimuth_deg``. No unit conversion or re-centring is done.

A ``.rad`` file may hold only ``polygon`` primitives (``MOD polygon ID 0 0 3n x1 y1 z1 …``),
comments (``#``) and blank space. Its modifiers are replaced by the table's material; any other
primitive (material definitions included) or an inline command (``!…``) stops with an error
naming the file, the primitive and what is supported. Polygons are triangulated by ear
clipping (simple polygons, convex or not).
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from pathlib import Path

import numpy as np

from radtree.errors import ConfigError
from radtree.scene import Mesh

MESH_SUFFIXES = (".obj", ".stl", ".ply")
RAD_SUFFIXES = (".rad",)


def _mesh_name(path: Path, used: set[str]) -> str:
    base = "user_" + re.sub(r"[^A-Za-z0-9_.-]+", "_", path.stem)
    name, i = base, 2
    while name in used:
        name = f"{base}_{i}"
        i += 1
    used.add(name)
    return name


def load_user_meshes(extra: Iterable[tuple[Path, str]],
                     materials: Mapping[str, object] | None = None) -> list[Mesh]:
    """One :class:`Mesh` per ``(path, material)``; ``materials`` (the scene's, optional) is used
    to reject an unknown material name early with the list of known ones."""
    out: list[Mesh] = []
    used: set[str] = set()
    for i, (path, material) in enumerate(extra):
        path = Path(path)
        field = f"geometry[{i}]"
        if materials is not None and material not in materials:
            raise ConfigError(
                f"material {material!r} for {path.name} is not a material of the scene; "
                f"known: {', '.join(sorted(materials))}", field=f"{field}.material")
        if not path.exists():
            raise ConfigError(f"file not found: {path}", field=f"{field}.file")
        suffix = path.suffix.lower()
        if suffix in MESH_SUFFIXES:
            vertices, faces = read_mesh_file(path)
        elif suffix in RAD_SUFFIXES:
            vertices, faces = read_rad_polygons(path)
        else:
            raise ConfigError(f"{path}: unsupported file type {path.suffix!r} (expected "
                              f"{', '.join(MESH_SUFFIXES + RAD_SUFFIXES)})", field=f"{field}.file")
        if len(faces) == 0:
            raise ConfigError(f"{path}: no surfaces found", field=f"{field}.file")
        if not np.all(np.isfinite(vertices)):
            raise ConfigError(f"{path}: coordinates must be finite numbers", field=f"{field}.file")
        out.append(Mesh(_mesh_name(path, used), material, vertices, faces))
    return out


def read_mesh_file(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and triangles of an OBJ/STL/PLY file (all its objects merged), via trimesh."""
    import trimesh

    try:
        loaded = trimesh.load(str(path), force="mesh", process=False)
    except Exception as exc:  # trimesh raises many kinds of errors for bad files
        raise ConfigError(f"{path}: cannot read as a triangle mesh: {exc}") from exc
    if not isinstance(loaded, trimesh.Trimesh):
        raise ConfigError(f"{path}: no triangle mesh found (got {type(loaded).__name__})")
    return np.asarray(loaded.vertices, float), np.asarray(loaded.faces, np.int64)


# ---------------------------------------------------------------- Radiance polygons
_TOKEN = re.compile(r"\S+")


def _tokens(text: str, path: Path) -> list[tuple[str, int]]:
    """Whitespace tokens with their line numbers; comments dropped, commands refused."""
    out: list[tuple[str, int]] = []
    for lineno, line in enumerate(text.splitlines(), 1):
        stripped = line.strip()
        if stripped.startswith("!"):
            raise ConfigError(f"{path}, line {lineno}: inline commands ({stripped[:40]!r}) are "
                              "not supported; run the command and save its polygons")
        line = line.split("#", 1)[0]
        out.extend((m.group(0), lineno) for m in _TOKEN.finditer(line))
    return out


def read_rad_polygons(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and triangles of the ``polygon`` primitives of a Radiance scene file."""
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f"{path}: cannot read: {exc}") from exc
    toks = _tokens(text, path)
    pos = 0
    verts: list[np.ndarray] = []
    faces: list[np.ndarray] = []
    offset = 0

    def take(what: str) -> tuple[str, int]:
        nonlocal pos
        if pos >= len(toks):
            line = toks[-1][1] if toks else 1
            raise ConfigError(f"{path}, line {line}: file ends inside a primitive (expected "
                              f"{what})")
        tok = toks[pos]
        pos += 1
        return tok

    def count(what: str) -> tuple[int, int]:
        tok, line = take(what)
        try:
            n = int(tok)
        except ValueError:
            raise ConfigError(f"{path}, line {line}: expected the number of {what}, got "
                              f"{tok!r}") from None
        if n < 0:
            raise ConfigError(f"{path}, line {line}: negative argument count {n}")
        return n, line

    while pos < len(toks):
        _mod, line = take("modifier")
        ptype, _ = take("primitive type")
        pid, _ = take("identifier")
        if ptype != "polygon":
            raise ConfigError(f"{path}, line {line}: primitive {ptype!r} {pid!r} is not "
                              "supported: only 'polygon' primitives are read (the material "
                              "comes from the [[geometry]] table's 'material')")
        for what in ("string arguments", "integer arguments"):
            n_args, aline = count(what)
            if n_args:
                raise ConfigError(f"{path}, line {aline}: polygon {pid!r} has {n_args} "
                                  f"{what}, expected 0")
        nreal, rline = count("real arguments")
        if nreal < 9 or nreal % 3:
            raise ConfigError(f"{path}, line {rline}: polygon {pid!r} has {nreal} real "
                              "arguments, expected 3 per vertex and at least 3 vertices")
        vals = []
        for _ in range(nreal):
            tok, vline = take("polygon coordinates")
            try:
                vals.append(float(tok))
            except ValueError:
                raise ConfigError(f"{path}, line {vline}: polygon {pid!r}: {tok!r} is not "
                                  "a number") from None
        pts = np.array(vals, float).reshape(-1, 3)
        tris = triangulate_polygon(pts)
        if len(tris) == 0:
            raise ConfigError(f"{path}, line {line}: polygon {pid!r} is degenerate (no area)")
        verts.append(pts)
        faces.append(tris + offset)
        offset += len(pts)
    if not verts:
        return np.zeros((0, 3)), np.zeros((0, 3), np.int64)
    return np.vstack(verts), np.vstack(faces)


def triangulate_polygon(points: np.ndarray) -> np.ndarray:
    """Ear-clipping triangulation of a planar simple polygon (n, 3) → (n − 2, 3) indices."""
    pts = np.asarray(points, float)
    n = len(pts)
    # Newell normal: robust for non-convex polygons
    nrm = np.zeros(3)
    for i in range(n):
        a, b = pts[i], pts[(i + 1) % n]
        nrm += np.array([(a[1] - b[1]) * (a[2] + b[2]), (a[2] - b[2]) * (a[0] + b[0]),
                         (a[0] - b[0]) * (a[1] + b[1])])
    if np.linalg.norm(nrm) < 1e-12:
        return np.zeros((0, 3), np.int64)
    axis = int(np.argmax(np.abs(nrm)))
    p2 = pts[:, [(axis + 1) % 3, (axis + 2) % 3]]     # right-handed about ``axis``
    if nrm[axis] < 0:                       # make the projected polygon counter-clockwise
        p2 = p2[:, ::-1]
    if n == 3:
        return np.array([[0, 1, 2]], np.int64)

    def cross(o: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
        return float((a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]))

    idx = list(range(n))
    tris = []
    guard = 0
    while len(idx) > 3 and guard < n * n:
        guard += 1
        found = False
        for k in range(len(idx)):
            i0, i1, i2 = idx[k - 1], idx[k], idx[(k + 1) % len(idx)]
            a, b, c = p2[i0], p2[i1], p2[i2]
            if cross(a, b, c) <= 1e-14:
                continue                    # reflex or degenerate corner
            inside = False
            for j in idx:
                if j in (i0, i1, i2):
                    continue
                q = p2[j]
                if cross(a, b, q) >= 0 and cross(b, c, q) >= 0 and cross(c, a, q) >= 0:
                    inside = True
                    break
            if not inside:
                tris.append((i0, i1, i2))
                idx.pop(k)
                found = True
                break
        if not found:                       # collinear leftovers or self-touching: fan them
            break
    if len(idx) >= 3:
        tris.extend((idx[0], idx[m], idx[m + 1]) for m in range(1, len(idx) - 1))
    return np.array(tris, np.int64).reshape(-1, 3)
