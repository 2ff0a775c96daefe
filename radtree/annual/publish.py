"""Publishing an annual run: the tables (``annual.csv``, ``annual_summary.csv``,
``annual_monthly.csv``), the hourly arrays (``annual/hourly.npz``), the run's facts
(``annual/annual_meta.json``), the standards table and the figures, each written to a
temporary name first (:mod:`radtree.fileio`)."""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
import pandas as pd

import radtree.annual.standards as standards
from radtree.annual.run import AnnualOptions, AnnualResult, compute_annual
from radtree.annual.tables import annual_tables
from radtree.config import Project
from radtree.fileio import atomic_path, write_text


@dataclass
class AnnualOutcome:
    result: AnnualResult
    annual_csv: Path
    summary_csv: Path
    monthly_csv: Path
    hourly: Path
    meta: Path
    figures: list[Path]


def _write_csv(df: pd.DataFrame, path: Path) -> Path:
    with atomic_path(path) as tmp:
        df.to_csv(tmp, index=False, float_format="%.6g")
    return path


def write_annual(result: AnnualResult, figures: bool = True) -> AnnualOutcome:
    """Write the tables, the hourly arrays, the run's facts and the figures."""
    project = result.project
    res = project.results_dir
    annual, summary, monthly = annual_tables(result)
    a = _write_csv(annual, res / "annual.csv")
    s = _write_csv(summary, res / "annual_summary.csv")
    m = _write_csv(monthly, res / "annual_monthly.csv")
    hourly = res / "annual" / "hourly.npz"
    arrays: dict[str, np.ndarray] = {
        "month": result.wea.month, "day": result.wea.day, "hour": result.wea.hour,
        "in_leaf": result.in_leaf, "occupied": result.occupied,
    }
    if result.leaf_fraction is not None and result.leaf_weight is not None:
        arrays["leaf_fraction"] = result.leaf_fraction
        arrays["leaf_weight"] = result.leaf_weight
    for g, geo in result.grids.items():
        arrays[f"points__{g}"] = geo["points"]
        arrays[f"normals__{g}"] = geo["normals"]
        for key in ("with", "without", "leaf_on", "leaf_off"):
            arrays[f"total__{key}__{g}"] = result.total[key][g]
            arrays[f"direct__{key}__{g}"] = result.direct[key][g]
    hourly.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(hourly) as tmp:
        with open(tmp, "wb") as fh:
            np.savez_compressed(fh, **arrays)  # type: ignore[arg-type]
    o = result.options
    meta = {
        "weather": {"path": str(result.weather.path), "generated": result.weather.generated,
                    "description": result.weather.description},
        "scenarios": result.scenarios,
        "leaf_on": o.season.leaf_on, "leaf_off": o.season.leaf_off,
        "leaf_days": o.season.leaf_days(), "leaf_source": o.season.source,
        "occupancy": list(o.occupancy), "occupied_hours": int(result.occupied.sum()),
        "sky_mf": o.mf, "sun_mf": o.sun_mf, "method": o.method,
        "rcontrib": {"ab": result.trace.ab, "ad": result.trace.ad, "lw": result.trace.lw,
                     "sun_ad": result.sun_trace.ad, "sun_lw": result.sun_trace.lw,
                     "processes": result.trace.nproc},
        "ground_reflectance": result.ground_reflectance,
        "branches": asdict(o.branches),
        "grids": {g: len(v["points"]) for g, v in result.grids.items()},
        "notes": result.notes, "timing": result.timing,
    }
    if result.phenology is not None:
        meta["phenology"] = {"species": result.phenology.species.key,
                             "latitude": result.phenology.latitude_deg,
                             "describe": result.phenology.describe()}
    standards.write_standards(project, standards.standards_table(
        result.scenarios, list(result.grids), result.total, result.direct, result.wea.dhi,
        result.occupied, result.sunlight, result.options.sunlight_date))
    if result.uncertainty is not None:
        meta["replicates"] = result.trace.replicates
        _write_csv(result.uncertainty, res / "annual" / "uncertainty.csv")
    mp = write_text(res / "annual" / "annual_meta.json", json.dumps(meta, indent=2,
                                                                     default=str))
    figs: list[Path] = []
    if figures:
        from radtree.annual.report import write_figures

        figs = write_figures(project)
    return AnnualOutcome(result, a, s, m, hourly, mp, figs)


def run_annual(project: Project, *, options: AnnualOptions | None = None,
               figures: bool = True) -> AnnualOutcome:
    """Compute (the default ``dc`` method, :func:`radtree.annual.run.compute_annual`) and
    write the annual results; :func:`radtree.annual.methods.run` picks the method."""
    return write_annual(compute_annual(project, options=options), figures=figures)
