"""The optional studies' report sections: office block, sensitivity sweep, crown realisations,
permeability scan, diagnosis and annual daylight — each present only when its outputs exist.

Each ``*_data`` function returns the plain data its template renders (formatted text cells:
lux as whole numbers, nRMSE/nMBE as fractions with 3 decimals), or None when there is nothing
to show.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import pandas as pd

from radtree.config import Project
from radtree.report.sections import Section


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


def extra_sections(project: Project, out: Path, echo: Callable[[str], None],
                   table: pd.DataFrame | None = None) -> list[Section]:
    """The sections of the studies that exist for this project, in page order (the HTML and
    the Markdown report show the same). Their figures are written into ``out`` (the report
    folder). ``table``: the results table, when already read."""
    secs: list[Section] = []
    if project.office is not None:
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
        secs.append(Section("office", office_section_data(project), "Office block"))
        echo("  office block: summary table and false-colour maps")
    if project.district is not None:
        from radtree.report.sections.facades import facades_data

        facades = facades_data(project, out)
        if facades is not None:
            secs.append(Section("facades", facades, "Every façade"))
            echo(f"  every façade: site plan of {facades['features']} façades")
    if (project.results_dir / "annual_summary.csv").exists():
        from radtree.annual.report import annual_section_data

        secs.append(Section("annual", annual_section_data(project), "Annual daylight"))
        echo("  annual: metric maps and month × hour heat maps")
    from radtree.pipeline.results import read_results
    from radtree.report.sections.models3d import honeybee_data, view3d_data

    table = read_results(project) if table is None else table
    for name, title, make in (("honeybee", "Honeybee model", honeybee_data),
                              ("view3d", "3-D view", view3d_data)):
        data = make(project, table, out, echo)
        if data is not None:
            secs.append(Section(name, data, title))
    from radtree.sweep.sensitivity import sweep_section_data

    sweep = sweep_section_data(project.root)
    if sweep is not None:
        secs.append(Section("sweep", sweep, "Sensitivity sweep"))
        echo("  sweep: sensitivity section")
    crowns = realisations_data(project)
    if crowns is not None:
        secs.append(Section("realisations", crowns, "Crown realisations"))
        echo("  crown realisations section")
    from radtree.calibrate.scan import scan_section_data

    scan = scan_section_data(project, out)
    if scan is not None:
        secs.append(Section("permeability_scan", scan, "Permeability scan"))
        echo("  permeability scan section")
    diagnosis = diagnose_data(project.root / "diagnose")
    if diagnosis["steps"] is not None:
        secs.append(Section("diagnose", diagnosis, "Diagnosis"))

    from radtree.report.sections.photo import photo_sections

    secs += photo_sections(project, out)

    from radtree.report.sections.method import method_section_data

    method = method_section_data(project, out)
    if method is not None:
        secs.append(Section("method", method, "The study's method"))
        echo("  the study's method: variants, findings, dome-radius scan")
    return secs
