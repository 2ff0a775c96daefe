"""PNG overlay of an analysed photo (matplotlib, Agg canvas; no global backend change).

Shows the photo, the classified sky in cyan, the mask circle (white), the ring and segment
grid of the analysis (yellow), the compass letters (or up/right/down/left for horizontal-axis
photos) and the gap outlines (red, holes orange).
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import LineCollection
from matplotlib.figure import Figure
from matplotlib.patches import Circle

from radtree.fileio import atomic_path

if TYPE_CHECKING:
    from .analyse import HemiResult

MAX_DISPLAY_PX = 1200


def write_overlay(result: HemiResult, path: str | os.PathLike, *, size_px: int = 1000) -> Path:
    """Draw the overlay of ``result`` into a PNG of about ``size_px`` pixels, atomically."""
    g = result.geometry
    pf = result.pixel_field
    rows, cols = pf.rows, pf.cols
    step = max(1, math.ceil(max(rows.stop - rows.start, cols.stop - cols.start) / MAX_DISPLAY_PX))
    rgb = result.image.display_rgb()[rows, cols][::step, ::step]
    sky = result.classification.sky[::step, ::step]
    tint = np.zeros(sky.shape + (4,), dtype=np.float32)
    tint[sky] = (0.0, 0.85, 1.0, 0.55)

    fig = Figure(figsize=(size_px / 100, size_px / 100 * 1.08), dpi=100, facecolor="black")
    FigureCanvasAgg(fig)
    ax = fig.add_axes((0.0, 0.0, 1.0, 0.93))
    extent = (cols.start, cols.stop, rows.stop, rows.start)
    ax.imshow(rgb, extent=extent, interpolation="nearest")
    ax.imshow(tint, extent=extent, interpolation="nearest")
    cx, cy, radius = g.mask.cx, g.mask.cy, g.mask.radius
    ax.add_patch(Circle((cx, cy), radius, fill=False, color="white", lw=1.2))

    grid = result.config.grid
    for z in grid.ring_edges:
        if z > 0:
            r = float(g.lens.radius(np.array([z]))[0]) * radius
            ax.add_patch(Circle((cx, cy), r, fill=False, color="yellow", lw=0.7, ls="--"))
    z_line = np.linspace(grid.zenith_start, grid.zenith_end, 50)
    for a in grid.segment_edges[:-1]:
        x, y = g.to_pixel(z_line, np.full_like(z_line, a))
        ax.plot(x, y, color="yellow", lw=0.7, ls="--")

    names = ("N", "E", "S", "W") if g.axis == "up" else ("up", "right", "down", "left")
    for a, text in zip((0.0, 90.0, 180.0, 270.0), names):
        x, y = g.to_pixel(np.array([90.0]), np.array([a]))
        dx, dy = float(x[0]) - cx, float(y[0]) - cy
        ax.text(cx + 1.05 * dx, cy + 1.05 * dy, text, color="white", ha="center", va="center",
                fontsize=12, fontweight="bold")

    ext = [o.exterior_px for o in result.outlines]
    holes = [h for o in result.outlines for h in o.holes_px]
    if ext:
        ax.add_collection(LineCollection(ext, colors="red", linewidths=0.6))
    if holes:
        ax.add_collection(LineCollection(holes, colors="orange", linewidths=0.5))

    pad = 0.12 * radius
    ax.set_xlim(max(cols.start, cx - radius) - pad, min(cols.stop, cx + radius) + pad)
    ax.set_ylim(min(rows.stop, cy + radius) + pad, max(rows.start, cy - radius) - pad)
    ax.set_facecolor("black")
    ax.set_axis_off()
    m = result.metrics
    fig.text(
        0.01, 0.985,
        f"{result.name}   threshold {result.classification.threshold:.1f} "
        f"({result.classification.method}, {result.config.channel})",
        fontsize=10, va="top", color="white",
    )
    lai = f"LAIeff {m.lai_eff:.2f}  LAI {m.lai:.2f}  " if math.isfinite(m.lai_eff) else ""
    fig.text(
        0.01, 0.955,
        f"gap {m.gap_fraction:.3f}  openness {m.openness:.3f}  SVF {m.svf:.3f}  "
        f"DIFN {m.difn:.1f} %  {lai}gaps {len(result.outlines)}",
        fontsize=10, va="top", color="white",
    )
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", facecolor="black")
    return Path(path)
