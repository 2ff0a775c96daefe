"""The batch: one photo or every photo of a folder through
:func:`~radtree.hemi.analyse.analyse_image`, writing CSV, GeoJSON and overlay PNGs.

Outputs of :func:`run_batch` (all written atomically, into ``out_dir``):

* ``summary.csv``: one row per image (columns in :data:`SUMMARY_COLUMNS`; DIFN in percent).
* ``rings.csv``: one row per image × ring × segment (rings and segments numbered from 1):
  ``gap_fraction`` (solid-angle weighted sky share of the cell) and ``gap_fraction_cos``
  (cosine weighted), the cell's exact solid angle and its weights in openness
  (``weight_openness`` × gap_fraction sums to openness) and in the SVF (``weight_svf`` ×
  gap_fraction_cos sums to svf).
* ``<stem>_gaps.geojson``: the gap outlines of each image, and ``gaps.geojson``: all images'
  gaps in one FeatureCollection (each feature names its image), so a single photo gives both
  ``gaps.geojson`` and ``<stem>_gaps.geojson`` with the same features.
* ``<stem>_overlay.png``: classified sky, mask, rings, segments and gap outlines.
"""

from __future__ import annotations

import csv
import io
import logging
import math
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from radtree.errors import RadtreeError
from radtree.fileio import write_text

from .analyse import HemiConfig, HemiResult, analyse_image
from .image import find_images
from .outlines import merge_collections, write_geojson

SUMMARY_COLUMNS = (
    "image", "threshold", "gap_fraction", "openness", "svf", "difn", "lai_eff", "lai",
    "clumping_lx", "ellipsoid_x", "mean_tilt_deg", "ellipsoid_lai", "threshold_method",
    "channel", "gamma", "lens", "mask_cx", "mask_cy", "mask_radius", "full_frame", "axis",
    "north_deg", "mirror", "zenith_from", "zenith_to", "rings", "segments", "gap_floor",
    "pixels", "sky_pixels", "gaps",
)
RING_COLUMNS = (
    "image", "ring", "zenith_from", "zenith_to", "segment", "azimuth_from", "azimuth_to",
    "gap_fraction", "gap_fraction_cos", "pixels", "sky_pixels", "solid_angle_sr", "weight_openness", "weight_svf",
    "threshold",
)

log = logging.getLogger(__name__)


# -- CSV --------------------------------------------------------------------------------------
def _fmt(v: Any) -> str:
    if isinstance(v, (bool, np.bool_)):
        return "true" if v else "false"
    if isinstance(v, (float, np.floating)):
        return "" if not math.isfinite(float(v)) else format(float(v), ".10g")
    return str(v)


def csv_text(rows: list[dict[str, Any]], columns: tuple[str, ...]) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(columns)
    for r in rows:
        w.writerow([_fmt(r.get(c, "")) for c in columns])
    return buf.getvalue()


@dataclass
class BatchReport:
    """What :func:`run_batch` did: summary rows, failures (file, message) and files written."""

    rows: list[dict[str, Any]] = field(default_factory=list)
    failures: list[tuple[str, str]] = field(default_factory=list)
    written: list[Path] = field(default_factory=list)


def run_batch(
    source: str | os.PathLike,
    out_dir: str | os.PathLike,
    config: HemiConfig | None = None,
    *,
    overlay: bool = True,
    keep_going: bool = False,
    on_result: Callable[[HemiResult], None] | None = None,
) -> BatchReport:
    """Analyse one image or every image of a folder and write the outputs into ``out_dir``.

    Fails on the first bad image unless ``keep_going`` (then bad images are logged as
    warnings and listed in the report; an error is raised only if no image could be
    analysed).
    """
    config = config or HemiConfig()
    src = Path(source)
    files = find_images(src) if src.is_dir() else [src]
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise RadtreeError(f"{out}: exists and is not a folder")
    report = BatchReport()
    ring_rows: list[dict[str, Any]] = []
    collections: list[dict[str, Any]] = []
    for f in files:
        try:
            result = analyse_image(f, config)
        except RadtreeError as exc:
            if not keep_going:
                raise
            report.failures.append((str(f), str(exc)))
            log.warning("skipped %s", exc)
            continue
        report.rows.append(result.summary_row())
        ring_rows.extend(result.ring_rows())
        collection = result.geojson()
        collections.append(collection)
        report.written.append(write_geojson(out / f"{result.stem}_gaps.geojson", collection))
        if overlay:
            from .overlay import write_overlay  # matplotlib: only when drawing

            report.written.append(write_overlay(result, out / f"{result.stem}_overlay.png"))
        if on_result:
            on_result(result)
    if not report.rows:
        raise RadtreeError(
            f"{src}: no image could be analysed ({len(report.failures)} failed; first: "
            f"{report.failures[0][1] if report.failures else 'none'})"
        )
    report.written.append(write_geojson(out / "gaps.geojson", merge_collections(collections)))
    report.written.append(write_text(out / "summary.csv", csv_text(report.rows, SUMMARY_COLUMNS)))
    report.written.append(write_text(out / "rings.csv", csv_text(ring_rows, RING_COLUMNS)))
    return report
