"""A picture of a built crown model: three orthographic views in the façade frame.

``render_model_png(model, scene, path)`` (as ``radtree build`` calls it) or
``render_model_png(model, None, path, frame, extra_meshes=..., sensor_points=...)`` draws the
elevation (seen from the street: u across, z up), the section (n across — the façade is the
line n = 0 — z up) and the plan (u across, n up) of every triangle, coloured by material, with
the façade line, the street and the sensors. Uses matplotlib's Agg canvas directly (no global
backend change); the PNG is written atomically.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from radtree.fileio import atomic_path
from radtree.optics import Hole, Plastic, Trans
from radtree.scene import Mesh, Scene
from radtree.site.frame import FacadeFrame
from radtree.trees.model import LEAF, TRUNK, TreeModel

#: meshes below this many triangles are drawn whole when the crown is subsampled
SMALL_MESH = 2000

VIEWS = (("Elevation from the street", 0, 2, "u along the façade (m)", "z (m)"),
         ("Section (façade at n = 0)", 1, 2, "n from the façade (m)", "z (m)"),
         ("Plan", 0, 1, "u along the façade (m)", "n from the façade (m)"))


def _colour(name: str, material: object) -> tuple[float, float, float]:
    if name == LEAF:
        return (0.18, 0.55, 0.20)
    if name == TRUNK:
        return (0.45, 0.30, 0.15)
    if isinstance(material, Trans):
        return (0.35, 0.65, 0.35)
    if isinstance(material, Plastic):
        return (0.15, 0.40, 0.15)
    return (0.5, 0.5, 0.5)


def render_model_png(model: TreeModel, scene: Scene | None, path: str | Path,
                     frame: FacadeFrame | None = None, *, extra_meshes: Sequence[Mesh] = (),
                     sensor_points: np.ndarray | None = None, title: str | None = None,
                     max_triangles: int = 15_000, dpi: int = 110, seed: int = 0) -> Path:
    """Write a PNG with three orthographic views of ``model``.

    ``scene`` (optional): its other meshes (street, façades) are drawn faintly and its
    ``facade`` grid (else its first grid) marked in red. ``extra_meshes`` and
    ``sensor_points`` (k, 3 world coordinates) add to / replace those. ``frame`` defaults to
    the frame the model was built in (``model.frame``), else one inferred from the sensors'
    normals. At most about ``max_triangles`` crown triangles are drawn: beyond that a random
    subset of the large meshes (leaves, slats; small ones such as trunks are drawn whole).
    """
    extra = list(extra_meshes)
    if scene is not None:
        own = {id(m) for m in model.meshes}
        extra += [m for m in scene.solid_meshes() if id(m) not in own
                  and m.name not in {c.name for c in model.meshes}]
        if sensor_points is None and scene.grids:
            grid = scene.grids.get("facade") or next(iter(scene.grids.values()))
            sensor_points = grid.points
            if frame is None and model.frame is None:
                nx, ny = float(grid.normals[0, 0]), float(grid.normals[0, 1])
                frame = FacadeFrame(float(np.degrees(np.arctan2(nx, ny))))
    frame = frame or model.frame or FacadeFrame()
    return _render(model, path=Path(path), frame=frame, extra_meshes=extra,
                   sensor_points=sensor_points, title=title, max_triangles=max_triangles,
                   dpi=dpi, seed=seed)


def _crown_triangles(model: TreeModel, frame: FacadeFrame, *, max_triangles: int, seed: int
                     ) -> tuple[list[tuple[Any, tuple[float, float, float]]], float]:
    """The crown's triangles in the façade frame with their colours, large meshes thinned
    at random (``seed``) to about ``max_triangles``; and the share kept."""
    rng = np.random.default_rng(seed)
    crown = [m for m in model.meshes if m.n_triangles
             and not isinstance(model.materials.get(m.material), Hole)]
    total = sum(m.n_triangles for m in crown)
    small = sum(m.n_triangles for m in crown if m.n_triangles < SMALL_MESH)
    keep_share = min(1.0, max(max_triangles - small, 1) / max(total - small, 1)) if total else 1.0
    local_tris = []
    for m in crown:
        tri = frame.to_local(m.vertices)[m.faces]
        if keep_share < 1.0 and m.n_triangles >= SMALL_MESH:
            tri = tri[rng.random(len(tri)) < keep_share]
        local_tris.append((tri, _colour(m.material, model.materials.get(m.material))))
    return local_tris, keep_share


def _render(model: TreeModel, *, path: Path, frame: FacadeFrame, extra_meshes: Sequence[Mesh],
            sensor_points: np.ndarray | None, title: str | None, max_triangles: int, dpi: int,
            seed: int) -> Path:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.collections import PolyCollection
    from matplotlib.figure import Figure

    fig = Figure(figsize=(16, 5.4), dpi=dpi)
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, 3)
    local_tris, keep_share = _crown_triangles(model, frame, max_triangles=max_triangles,
                                              seed=seed)
    extras = [frame.to_local(m.vertices)[m.faces] for m in extra_meshes if m.n_triangles]
    sensors = None if sensor_points is None else frame.to_local(np.asarray(sensor_points, float))
    pts = [t.reshape(-1, 3) for t, _ in local_tris]
    if sensors is not None:
        pts.append(sensors)
    allpts = np.vstack(pts) if pts else np.zeros((1, 3))
    lo, hi = allpts.min(axis=0), allpts.max(axis=0)
    lo = np.minimum(lo, [lo[0], -0.5, 0.0]) - 1.0
    hi = np.maximum(hi, [hi[0], 1.0, 1.0]) + 1.0
    drawn = sum(len(t) for t, _ in local_tris)
    alpha = float(np.clip(60.0 / max(1.0, np.sqrt(drawn)), 0.08, 0.9))
    for ax, (name, i, j, xl, yl) in zip(axes, VIEWS):
        for tri in extras:
            ax.add_collection(PolyCollection(tri[:, :, [i, j]], facecolors=(0.85, 0.85, 0.85),
                                             edgecolors=(0.6, 0.6, 0.6), linewidths=0.3,
                                             alpha=0.5, zorder=0))
        for tri, col in local_tris:
            ax.add_collection(PolyCollection(tri[:, :, [i, j]], facecolors=col,
                                             edgecolors="none", alpha=alpha, zorder=2))
        if i == 1:
            ax.axvline(0.0, color="k", lw=1.5, zorder=3)
            ax.text(0.0, hi[2], " façade", va="top", fontsize=8)
        if j == 1:
            ax.axhline(0.0, color="k", lw=1.5, zorder=3)
        if j == 2:
            ax.axhline(0.0, color=(0.4, 0.4, 0.4), lw=1.0, zorder=3)
        if sensors is not None:
            ax.plot(sensors[:, i], sensors[:, j], "o", color="red", ms=3, zorder=4)
        ax.set_xlim(lo[i], hi[i])
        ax.set_ylim(lo[j], hi[j])
        ax.set_aspect("equal")
        ax.set_title(name, fontsize=10)
        ax.set_xlabel(xl, fontsize=8)
        ax.set_ylabel(yl, fontsize=8)
        ax.tick_params(labelsize=7)
    head = title or f"{model.model} crown, {model.form} form"
    fig.suptitle(f"{head}\n{_subtitle(model, drawn if keep_share < 1.0 else None)}",
                 fontsize=11)
    fig.tight_layout()
    target = Path(path)
    with atomic_path(target) as tmp:
        fig.savefig(tmp, format="png", dpi=dpi)
    return target


def _subtitle(model: TreeModel, drawn: int | None) -> str:
    """Triangles, build time, triangles drawn when thinned, and the crown's transmission."""
    sub = f"{model.triangles} triangles, built in {model.build_seconds:.2f} s"
    if drawn is not None:
        sub += f" ({drawn} of them drawn)"
    for key in ("tau_crown_direct", "hole_fraction", "crown_transmission"):
        if key in model.info:
            sub += f"; {key.replace('_', ' ')} {model.info[key]:.4f}"
    return sub
