"""The optional studies' report sections: office block, sensitivity sweep, crown realisations,
permeability scan, diagnosis and annual daylight — each present only when its outputs exist.

Each ``*_data`` function returns the plain data its template renders (formatted text cells:
lux as whole numbers, nRMSE/nMBE as fractions with 3 decimals), or None when there is nothing
to show.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import pandas as pd

from radtree.config import Project
from radtree.report.sections import Section

log = logging.getLogger(__name__)


def realisation_frame(project: Project) -> pd.DataFrame | None:
    """Per scenario with crown realisations, per realisation: façade hourly means, nRMSE and
    nMBE against the measured hourly means (None without ``results/realisations.csv``)."""
    path = project.results_dir / "realisations.csv"
    if not path.exists():
        return None
    from radtree.measurements import hourly_grid_means
    from radtree.stats import nmbe, nrmse

    per = pd.read_csv(path)
    per = per[per["grid"] == "facade"]
    if per.empty:
        return None
    hourly = per.groupby(["scenario", "realisation", "time"])["lux"].mean().unstack("time")
    measured = hourly_grid_means(project.measured) if project.measured is not None else None
    out = hourly.reset_index()
    if measured is not None and set(hourly.columns) <= set(measured.index):
        m = measured.reindex(hourly.columns).to_numpy()
        out["nrmse"] = [nrmse(m, row) for row in hourly.to_numpy()]
        out["nmbe"] = [nmbe(m, row) for row in hourly.to_numpy()]
    return out


def realisations_data(project: Project) -> dict[str, Any] | None:
    """Each crown realisation of a scenario alone: façade means (lx) per hour, and nRMSE / nMBE
    against the measured hourly means when they exist (None without realisations)."""
    t = realisation_frame(project)
    if t is None:
        return None
    hours = [c for c in t.columns if c not in ("scenario", "realisation", "nrmse", "nmbe")]
    stats = "nrmse" in t.columns
    rows = []
    for _, r in t.iterrows():
        cells = [f"{r[h]:.0f}" for h in hours]
        if stats:
            cells += [f"{r['nrmse']:.3f}", f"{r['nmbe']:+.3f}"]
        rows.append({"scenario": str(r["scenario"]), "realisation": str(int(r["realisation"])),
                     "cells": cells})
    spread = [f"Scenario {name}: single crowns give nRMSE {g['nrmse'].min():.3f}–"
              f"{g['nrmse'].max():.3f} (mean {g['nrmse'].mean():.3f})."
              for name, g in t.groupby("scenario")] if stats else []
    return {"columns": [str(h) for h in hours] + (["nRMSE", "nMBE"] if stats else []),
            "rows": rows, "spread": spread}


def diagnose_data(folder: Path) -> dict[str, Any]:
    """The diagnosis (``folder`` = ``PROJECT/diagnose``): its steps as *fitted* parameters, each
    with its leave-one-hour-out cross-validated nRMSE. ``steps`` is None without ``steps.csv``
    and empty when no effect was added."""
    steps_csv = folder / "steps.csv"
    if not steps_csv.exists():
        return {"steps": None}
    steps = pd.read_csv(steps_csv)
    return {"steps": [{
        "step": str(int(r["step"])), "effect": str(r["effect"]),
        "strength": str(r.get("strength_text", "")),
        "explained": f"{100 * float(r['explained_fraction']):.0f}",
        "rmse": f"{float(r['rmse_before']):.3f} → {float(r['rmse_after']):.3f}",
        "cv_rmse": f"{float(r['cv_rmse_before']):.3f} → {float(r['cv_rmse_after']):.3f}",
    } for _, r in steps.iterrows()]}


def _section(key: str, data: dict[str, Any] | None, title: str, message: str = ""
             ) -> list[Section]:
    """``[Section]`` when there is ``data`` (``message`` logged), else ``[]``."""
    if data is None:
        return []
    if message:
        log.info("  %s", message)
    return [Section(key, data, title)]


def _office(project: Project, out: Path) -> list[Section]:
    """The office block's summary, false-colour maps and hourly charts (in ``out/office``)."""
    if project.office is None:
        return []
    from radtree.office_summary import (
        office_section_data,
        read_results,
        summarise,
        write_hourly_charts,
        write_maps,
        write_summary,
    )

    write_summary(project, maps=False)
    office_table = read_results(project)
    write_maps(project, office_table, out / "office")
    write_hourly_charts(project, summarise(office_table), out / "office")
    return _section("office", office_section_data(project), "Office block",
                    "office block: summary table and false-colour maps")


def _inventory_and_annual(project: Project, out: Path) -> list[Section]:
    """Every façade of an inventory (a site plan), and the annual daylight section."""
    secs: list[Section] = []
    if project.district is not None:
        from radtree.report.sections.facades import facades_data

        facades = facades_data(project, out)
        msg = (f"every façade: site plan of {facades['features']} façades"
               if facades is not None else "")
        secs += _section("facades", facades, "Every façade", msg)
    if (project.results_dir / "annual_summary.csv").exists():
        from radtree.annual.report import annual_section_data

        secs += _section("annual", annual_section_data(project), "Annual daylight",
                         "annual: metric maps and month × hour heat maps")
    return secs


def _studies(project: Project, out: Path) -> list[Section]:
    """The sensitivity sweep, crown realisations, permeability scan and diagnosis."""
    from radtree.calibrate.scan import scan_section_data
    from radtree.sweep.sensitivity import sweep_section_data

    diagnosis = diagnose_data(project.root / "diagnose")
    return (_section("sweep", sweep_section_data(project.root), "Sensitivity sweep",
                     "sweep: sensitivity section")
            + _section("realisations", realisations_data(project), "Crown realisations",
                       "crown realisations section")
            + _section("permeability_scan", scan_section_data(project, out),
                       "Permeability scan", "permeability scan section")
            + _section("diagnose", diagnosis if diagnosis["steps"] is not None else None,
                       "Diagnosis"))


def extra_sections(project: Project, out: Path, table: pd.DataFrame | None = None
                   ) -> list[Section]:
    """The sections of the studies that exist for this project, in page order (the HTML and
    the Markdown report show the same). Their figures are written into ``out`` (the report
    folder). ``table``: the results table, when already read."""
    from radtree.pipeline.results import read_results
    from radtree.report.sections.method import method_section_data
    from radtree.report.sections.models3d import honeybee_data, view3d_data
    from radtree.report.sections.photo import photo_sections
    from radtree.report.sections.points import points_sections

    secs = _office(project, out) + _inventory_and_annual(project, out)
    table = read_results(project) if table is None else table
    secs += _section("honeybee", honeybee_data(project, table, out), "Honeybee model")
    secs += _section("view3d", view3d_data(project, table, out), "3-D view")
    secs += _studies(project, out) + photo_sections(project, out)
    secs += points_sections(project, out, table)
    return secs + _section("method", method_section_data(project, out), "The study's method",
                           "the study's method: variants, findings, dome-radius scan")
