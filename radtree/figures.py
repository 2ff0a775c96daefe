"""Matplotlib figures without pyplot (thread-safe, no display): create and save PNGs."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from radtree.fileio import atomic_path

if TYPE_CHECKING:   # matplotlib (0.5 s) is imported by the first figure, not by every command
    from matplotlib.figure import Figure


def new_figure(width: float, height: float, dpi: int) -> Figure:
    """A constrained-layout figure of ``width`` × ``height`` inches on an Agg canvas."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), dpi=dpi, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def save_png(fig: Figure, path: Path, dpi: int) -> Path:
    """Write ``fig`` as a PNG (no software stamp, so reruns give the same bytes), atomically."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi, format="png", metadata={"Software": None})
    return path


def compact_png(src: Path, dst: Path, max_px: int = 700, colors: int = 128) -> Path:
    """A copy of the PNG ``src`` for a report: at most ``max_px`` on its longer side and an
    adaptive palette of ``colors`` (Pillow), so that a report of many pictures stays light."""
    from PIL import Image

    with Image.open(src) as opened:
        rgb = opened.convert("RGB")
    rgb.thumbnail((max_px, max_px))
    rgb.quantize(colors=colors, method=Image.Quantize.MEDIANCUT).save(dst, optimize=True)
    return dst
