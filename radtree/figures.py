"""Matplotlib figures without pyplot (thread-safe, no display): create and save PNGs."""

from __future__ import annotations

from pathlib import Path

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from radtree.fileio import atomic_path


def new_figure(width: float, height: float, dpi: int) -> Figure:
    """A constrained-layout figure of ``width`` × ``height`` inches on an Agg canvas."""
    fig = Figure(figsize=(width, height), dpi=dpi, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def save_png(fig: Figure, path: Path, dpi: int) -> Path:
    """Write ``fig`` as a PNG (no software stamp, so reruns give the same bytes), atomically."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi, format="png", metadata={"Software": None})
    return path
