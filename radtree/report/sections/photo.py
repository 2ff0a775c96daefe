"""The photo sections of the report: how often direct sun reaches the sensors through the
perforated crowns' gaps (``results/direct_sun.csv``), and the crown against its photo
(``results/photo_check.csv`` and the images ``radtree hemi check`` writes beside it) — each
shown only when its file exists."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from radtree.config import Project
from radtree.figures import compact_png
from radtree.report.sections import Section
from radtree.report.tables import num


def direct_sun_data(project: Project) -> dict[str, Any] | None:
    """Per perforated scenario: the share of sensor-hours the sun reaches a sensor (mean ± s.d.
    over gap-pattern realisations) and the share of realisations where it reaches any."""
    path = project.results_dir / "direct_sun.csv"
    if not path.is_file():
        return None
    from radtree.pipeline.sunreach import direct_sun_summary

    summary = direct_sun_summary(pd.read_csv(path))
    rows = [{"scenario": str(r["scenario"]), "realisations": str(int(r["realisations"])),
             "sensor_hours": str(int(r["sensor_hours"])),
             "reach": f"{100 * r['reach_share']:.1f} %" + (
                 "" if np.isnan(r["reach_share_sd"]) else
                 f" ± {100 * r['reach_share_sd']:.1f} %"),
             "any": f"{100 * r['realisations_reaching']:.0f} %"} for _, r in summary.iterrows()]
    return {"rows": rows}


def photo_check_data(project: Project, out: Path) -> dict[str, Any] | None:
    """Per scenario checked against its photo: RMS over ring × segment cells, gap fraction per
    ring (photo, model), LAI and openness of both, and the two fisheye images (copied into the
    report folder ``out``)."""
    path = project.results_dir / "photo_check.csv"
    if not path.is_file():
        return None
    table = pd.read_csv(path)
    metrics_path = project.results_dir / "photo_check_metrics.csv"
    metrics = pd.read_csv(metrics_path) if metrics_path.is_file() else None
    scenarios = []
    for sc, g in table.groupby("scenario", sort=False):
        d = g["gap_fraction_model"] - g["gap_fraction_photo"]
        ring = g.groupby("ring", sort=True).agg(
            zmin=("zenith_min_deg", "first"), zmax=("zenith_max_deg", "first"),
            photo=("gap_fraction_photo", "mean"), model=("gap_fraction_model", "mean"))
        ring_rms = float(np.sqrt(np.nanmean((ring["model"] - ring["photo"]) ** 2)))
        item: dict[str, Any] = {
            "scenario": str(sc), "rms": f"{float(np.sqrt(np.nanmean(d ** 2))):.4f}",
            "ring_rms": f"{ring_rms:.4f}",
            "rings": [{"zenith": f"{r.zmin:g}–{r.zmax:g}°", "photo": num(r.photo, 3),
                       "model": num(r.model, 3)} for r in ring.itertuples()],
            "metrics": [], "images": []}
        if metrics is not None:
            for _, m in metrics[metrics["scenario"].astype(str) == str(sc)].iterrows():
                item["metrics"].append({"what": str(m["image"]), "lai": num(m["lai_eff"], 3),
                                        "openness": num(m["openness"], 4)})
        out.mkdir(parents=True, exist_ok=True)
        for kind in ("photo", "model"):
            src = project.results_dir / "photo_check" / f"{sc}_{kind}.png"
            if src.is_file():
                compact_png(src, out / f"photo_check_{sc}_{kind}.png")
                item["images"].append({"kind": kind, "file": f"photo_check_{sc}_{kind}.png"})
        scenarios.append(item)
    return {"scenarios": scenarios}


def photo_sections(project: Project, out: Path) -> list[Section]:
    """The photo sections that exist for this project (HTML and Markdown alike)."""
    secs: list[Section] = []
    sun = direct_sun_data(project)
    if sun is not None:
        secs.append(Section("direct_sun", sun, "Direct sun through the gaps"))
    check = photo_check_data(project, out)
    if check is not None:
        secs.append(Section("photo_check", check, "Crown against its photo"))
    return secs
