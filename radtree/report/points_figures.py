"""The report's figures of a crown built from points (``[tree] points``, issue 41 item 2):
its leaf-area vertical profile and the crown beside its points (matplotlib, Agg, 150 dpi PNG
like :mod:`radtree.report.figures`).

Coordinates: the crown's own frame — u along the façade, n away from it, both from the trunk
axis, z up from the street (m). The point cloud is placed as the crown builder places it
(:mod:`radtree.trees.points_crown`: the centre of its outline on the trunk axis, its x along u,
its y along n, its ground at z = 0), so both views compare like with like.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from radtree.figures import new_figure, save_png

DPI = 150
SCAN_COLOUR = "0.35"
SLAT_COLOUR = "tab:green"


@dataclass(frozen=True)
class CrownViews:
    """What the side views show: the points (k, 3) and the slat polygons (list of (m, 3)) of
    one crown in its own frame (module text), and the layer thickness (m) of the profile."""

    points: np.ndarray
    slats: list[np.ndarray]
    layer_m: float


def slat_profile(slats: list[np.ndarray], *, layer_m: float, layers: int
                 ) -> np.ndarray:
    """One-sided slat area (m²) per layer of ``layer_m`` from the street, by each triangle's
    centroid height (``layers`` layers; area above them added to the top one)."""
    out = np.zeros(layers)
    for p in slats:
        if len(p) < 3:
            continue
        a, b, c = p[0][None, :], p[1:-1], p[2:]
        area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
        k = np.clip(((a[:, 2] + b[:, 2] + c[:, 2]) / 3.0 / layer_m).astype(int), 0, layers - 1)
        np.add.at(out, k, area)
    return out


def profile_plot(record: dict[str, Any], views: CrownViews | None, path: Path) -> str:
    """Leaf area per metre of height (m²/m) against height: the scan's inversion per voxel
    layer (the manifest's profile) and, when given, the built slats of one crown."""
    prof = record["profile"]
    lo = np.asarray(prof["z_bottom_m"], float)
    per_m = np.asarray(prof["leaf_area_m2_per_m"], float)
    v = float(record["voxel_m"])
    fig = new_figure(5.6, 4.8, DPI)
    ax = fig.add_subplot()
    ax.stairs(per_m, np.append(lo, lo[-1] + v) if len(lo) else [0.0], orientation="horizontal",
              color=SCAN_COLOUR, linewidth=1.8, label="scan (Beer–Lambert inversion in its hull)")
    built = ""
    if views is not None and len(lo):
        area = slat_profile(views.slats, layer_m=v, layers=len(lo))
        ax.stairs(area / v, np.append(lo, lo[-1] + v), orientation="horizontal",
                  color=SLAT_COLOUR, linewidth=1.4, linestyle="--",
                  label="built slats (one crown)")
        built = (f" Dashed green: the built slats' one-sided area per layer, "
                 f"{area.sum():.1f} m² in all.")
    ax.set_xlabel("leaf area per metre of height (m²/m)")
    ax.set_ylabel("height above the street (m)")
    ax.set_xlim(left=0)
    ax.set_ylim(bottom=0)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, frameon=False, loc="upper right")
    ax.set_title(f"{record['file']}: {record['leaf_area_m2']:.1f} m² of leaf area",
                 fontsize=10)
    save_png(fig, path, DPI)
    return (f"Vertical profile of the crown's leaf (plant) area from {record['file']}: m² per "
            f"metre of height in layers of one voxel ({v:g} m), from the Beer–Lambert "
            f"inversion along vertical beams (G = {record['g_vertical']:.3f}) kept inside the "
            f"convex hull of the returns (solid grey), total {record['leaf_area_m2']:.1f} m² "
            "per crown." + built)


def _hull(xy: np.ndarray) -> np.ndarray | None:
    """The closed convex hull (k, 2) of plan or side points, None for fewer than 3."""
    from scipy.spatial import ConvexHull, QhullError

    try:
        h = ConvexHull(xy)
    except (QhullError, ValueError):
        return None
    ring = xy[h.vertices]
    return np.vstack([ring, ring[:1]])


def _side(ax: Any, views: CrownViews, *, axis: int, scan: bool) -> None:
    from matplotlib.collections import PolyCollection

    p = views.points[:, [axis, 2]]
    if scan:
        ax.scatter(p[:, 0], p[:, 1], s=3.0, c=SCAN_COLOUR, linewidths=0, alpha=0.7,
                   rasterized=True)
    else:
        polys = [q[:, [axis, 2]] for q in views.slats if len(q) >= 3]
        ax.add_collection(PolyCollection(polys, facecolors=SLAT_COLOUR, edgecolors="none",
                                         alpha=0.35))
    hull = _hull(p)
    if hull is not None:
        ax.plot(hull[:, 0], hull[:, 1], color=SCAN_COLOUR, linewidth=0.9, linestyle="--")
    ax.set_aspect("equal")
    ax.grid(True, alpha=0.3)


def crown_views_plot(views: CrownViews, path: Path, *, file: str) -> str:
    """Side views of the crown beside its points: along the façade (u–z) and across it
    (n–z), the point cloud (left) and the built slats (right), on the same axes."""
    fig = new_figure(6.4, 8.4, DPI)
    axes = fig.subplots(2, 2, sharey=True)
    allp = np.vstack([views.points] + [q for q in views.slats if len(q)])
    half = float(np.max(np.abs(allp[:, :2]))) * 1.05 + 0.1
    top = float(allp[:, 2].max()) * 1.05 + 0.1
    for row, (axis, name) in enumerate(((0, "u along the façade (m)"),
                                        (1, "n away from the façade (m)"))):
        for col, scan in enumerate((True, False)):
            ax = axes[row, col]
            _side(ax, views, axis=axis, scan=scan)
            ax.set_xlim(-half, half)
            ax.set_ylim(0, top)
            ax.set_xlabel(name)
            if col == 0:
                ax.set_ylabel("height (m)")
            ax.set_title(("points" if scan else "built slats") + (
                " — seen from the street" if axis == 0 else " — seen along the façade"),
                fontsize=9)
    save_png(fig, path, DPI)
    return (f"The crown beside its points: the vegetation returns of {file} (grey dots, "
            f"{len(views.points)} returns 0.5 m or more above ground) placed as the crown "
            f"builder places them (the centre of its outline on the trunk axis), and the built "
            f"slats of one crown (green, {len(views.slats)} triangles), seen from the street "
            "(u–z, top) and along the façade (n–z, bottom); dashed: the points' convex "
            "outline in each view; metres from the trunk axis and the street.")
