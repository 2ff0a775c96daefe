"""The crown against its photo: ``results/photo_check.csv`` (one row per ring × segment of
the photo analysis: ``scenario, ring, segment, zenith_min_deg, zenith_max_deg,
gap_fraction_photo, gap_fraction_model``), ``results/photo_check_metrics.csv`` (LAI,
openness, … of the photo and the model) and ``results/photo_check/<scenario>_photo.png`` /
``_model.png`` (the two fisheyes, side by side in the report).

Gap fractions are the sky share of each cell's solid angle (:mod:`radtree.hemi.metrics`), of
the photo as ``radtree hemi`` reads it and of the model's rendering
(:mod:`radtree.photo.render`) on the same grid. RMS = √(mean over cells with pixels of
(model − photo)²); the per-ring RMS compares the ring means. Several photos (a folder): the
photo column is their mean.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
from PIL import Image

from radtree.config import Project, Scenario
from radtree.fileio import atomic_path
from radtree.hemi import HemiResult
from radtree.photo.render import DEFAULT_SIZE, Rendering, render_scenario
from radtree.pipeline.results import merge_write
from radtree.trees.photo import analyse_photo

CHECK_COLUMNS = ["scenario", "ring", "segment", "zenith_min_deg", "zenith_max_deg",
                 "gap_fraction_photo", "gap_fraction_model"]
METRIC_COLUMNS = ["scenario", "image", "openness", "gap_fraction", "lai_eff", "lai",
                  "clumping_lx", "ellipsoid_x", "mean_tilt_deg", "seconds"]
PREVIEW_PX = 600


@dataclass
class CheckOutcome:
    """One scenario's check: the rows, RMS over cells and over rings, both analyses."""

    rows: pd.DataFrame
    rms: float
    ring_rms: float
    photos: list[HemiResult]
    model: HemiResult
    rendering: Rendering


def check_rows(name: str, photos: list[HemiResult], model: HemiResult) -> pd.DataFrame:
    grid = model.table.grid
    ze = grid.ring_edges
    photo_gap = np.nanmean(np.stack([p.table.gap for p in photos]), axis=0)
    rows = []
    for i in range(grid.rings):
        for j in range(grid.segments):
            rows.append({"scenario": name, "ring": i + 1, "segment": j + 1,
                         "zenith_min_deg": float(ze[i]), "zenith_max_deg": float(ze[i + 1]),
                         "gap_fraction_photo": float(photo_gap[i, j]),
                         "gap_fraction_model": float(model.table.gap[i, j])})
    return pd.DataFrame(rows, columns=CHECK_COLUMNS)


def rms_of(rows: pd.DataFrame) -> tuple[float, float]:
    """(RMS over ring × segment cells, RMS over the ring means)."""
    d = rows["gap_fraction_model"] - rows["gap_fraction_photo"]
    ring = rows.groupby("ring")[["gap_fraction_photo", "gap_fraction_model"]].mean()
    r = ring["gap_fraction_model"] - ring["gap_fraction_photo"]
    return float(np.sqrt(np.nanmean(d ** 2))), float(np.sqrt(np.nanmean(r ** 2)))


def check_scenario(project: Project, sc: Scenario, size: int = DEFAULT_SIZE) -> CheckOutcome:
    """Render the scenario's crown, analyse it and its photo(s), compare."""
    rendering = render_scenario(project, sc, size)
    model = rendering.analyse()
    src = rendering.source
    photos = [analyse_photo(p, src) for p in src.images]
    rows = check_rows(sc.name, photos, model)
    rms, ring_rms = rms_of(rows)
    return CheckOutcome(rows, rms, ring_rms, photos, model, rendering)


def _metric_row(name: str, image: str, r: HemiResult, seconds: float) -> dict:
    m = r.metrics
    return {"scenario": name, "image": image, "openness": m.openness,
            "gap_fraction": m.gap_fraction, "lai_eff": m.lai_eff, "lai": m.lai,
            "clumping_lx": m.clumping_lx, "ellipsoid_x": m.ellipsoid_x,
            "mean_tilt_deg": m.mean_tilt_deg, "seconds": seconds}


def _preview(pixels: np.ndarray, path) -> None:
    im = Image.fromarray(np.clip(pixels, 0, 255).astype(np.uint8))
    im.thumbnail((PREVIEW_PX, PREVIEW_PX))
    with atomic_path(path) as tmp:
        im.save(tmp, format="PNG")


def write_check(project: Project, outcomes: list[CheckOutcome]) -> None:
    """Write (merge by scenario) the check tables and the preview images."""
    out = project.results_dir
    out.mkdir(parents=True, exist_ok=True)
    names = [o.rows["scenario"].iloc[0] for o in outcomes]
    merge_write(out / "photo_check.csv", pd.concat([o.rows for o in outcomes]), names)
    metrics = []
    for o, name in zip(outcomes, names):
        secs = o.rendering.seconds["cast"]
        for p in o.photos:
            metrics.append(_metric_row(name, f"photo {p.name}", p, float("nan")))
        metrics.append(_metric_row(name, "model", o.model, secs))
        (out / "photo_check").mkdir(exist_ok=True)
        p0 = o.photos[0]
        box = p0.geometry.bounds()
        _preview(p0.image.display_rgb()[box], out / "photo_check" / f"{name}_photo.png")
        _preview(o.rendering.image, out / "photo_check" / f"{name}_model.png")
    merge_write(out / "photo_check_metrics.csv", pd.DataFrame(metrics, columns=METRIC_COLUMNS),
                names)
