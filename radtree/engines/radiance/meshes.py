"""Large meshes as compiled Radiance triangle meshes (``obj2mesh`` → ``.rtm``).

A crown of tens of thousands of triangles written as ``polygon`` text is slow to write and to
read (oconv parses every number); Radiance users expect such geometry as a compiled mesh:

```
geometry/<mesh>.obj   Wavefront OBJ: ``v x y z`` (metres, 5 decimals) and ``f a b c`` (1-based)
geometry/<mesh>.rtm   obj2mesh geometry/<mesh>.obj  (made before the first octree, as the
                      octrees are: by `radtree simulate` or by the folder's Makefile)
geometry/<mesh>.rad   MAT mesh <mesh>
                      1 geometry/<mesh>.rtm
                      0
                      0
```

The mesh primitive's modifier (the mesh's material) is substituted on every triangle (the
OBJ carries no ``usemtl``), so the scene is the same triangles with the same material as the
polygon text; like polygons, mesh triangles of plastic/trans materials are two-sided. Meshes
below :data:`MESH_MIN_TRIANGLES` (façades, ground: a few triangles) stay readable polygon text.
"""

from __future__ import annotations

from pathlib import Path

from radtree.cache import cached_file, content_key
from radtree.engines.radiance.numtext import format_rows
from radtree.scene import Mesh

#: meshes with at least this many triangles are written as obj2mesh meshes
MESH_MIN_TRIANGLES = 100
#: obj2mesh -n: most triangles per mesh octree voxel
MESH_OBJLIM = 4


def mesh_to_radiance(mesh: Mesh) -> str:
    """Triangles as Radiance polygons: ``MAT polygon NAME.i 0 0 9 x1 y1 z1 x2 y2 z2 x3 y3 z3``."""
    tri = mesh.triangles
    out = [f"# {mesh.name}: {len(tri)} triangles, material {mesh.material}\n"]
    for i, t in enumerate(tri):
        coords = " ".join(f"{v:.5f}" for v in t.ravel())
        out.append(f"{mesh.material} polygon {mesh.name}.{i}\n0\n0\n9 {coords}\n")
    return "\n".join(out)


def as_compiled_mesh(mesh: Mesh) -> bool:
    """True when ``mesh`` is written as an ``.rtm`` mesh (large), False for polygon text."""
    return mesh.n_triangles >= MESH_MIN_TRIANGLES


def obj_text(mesh: Mesh) -> str:
    """The mesh as Wavefront OBJ: a comment, its vertices (``v``, 5 decimals as the polygon
    text) and its triangles (``f``, 1-based vertex indices); the same bytes as printf's
    ``"v %.5f %.5f %.5f"`` / ``"f %d %d %d"`` (:mod:`radtree.engines.radiance.numtext`)."""
    head = f"# {mesh.name}: {mesh.n_triangles} triangles, material {mesh.material}\n"
    return head + format_rows("v", mesh.vertices, 5) + format_rows("f", mesh.faces + 1, 0)


def write_obj(mesh: Mesh, path: Path) -> bool:
    """Write :func:`obj_text` of ``mesh`` to ``path`` (atomically): copied from the build cache
    (:mod:`radtree.cache`, keyed by the mesh's name, material, vertices and faces) when a
    build wrote it before (True), else formatted and stored there (False)."""
    key = content_key(mesh.vertices, mesh.faces, what="obj", name=mesh.name,
                      material=mesh.material)
    return cached_file(key, ".obj", lambda p: p.write_text(obj_text(mesh), encoding="utf-8"),
                       path)


def mesh_primitive_text(mesh: Mesh, rtm: str) -> str:
    """``geometry/<mesh>.rad`` of a compiled mesh: one ``mesh`` primitive, modifier the mesh's
    material, reading ``rtm`` (relative to the build folder)."""
    return (f"# {mesh.name}: {mesh.n_triangles} triangles, material {mesh.material}, "
            f"compiled by obj2mesh\n{mesh.material} mesh {mesh.name}\n1 {rtm}\n0\n0\n")


def obj2mesh_command(obj: str) -> list[str]:
    """``obj2mesh -n 4 <obj>`` (the compiled mesh goes to stdout). ``-n`` (surfaces per voxel,
    default 9, "below 6 not recommended" as the median vertex valence of a connected mesh):
    crown slats share no vertices (valence ≤ 2), and at ``-n 4`` rtrace runs the reference-case crowns
    as fast as their polygon text, at ``-n 9`` about 20 % slower (CHANGELOG.md, benchmark notes)."""
    return ["obj2mesh", "-n", str(MESH_OBJLIM), obj]
