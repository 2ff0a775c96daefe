"""Figures and the HTML fragment of the annual run.

Reads only what :func:`radtree.annual.run.write_annual` wrote:
``results/annual.csv``, ``results/annual_summary.csv``, ``results/annual_monthly.csv``,
``results/annual/hourly.npz`` and ``results/annual/annual_meta.json``. Figures go to
``results/annual/figures/`` (outside ``report/``, which the report builder replaces whole);
:func:`annual_section_data` embeds them as inline PNG so the section works wherever it
is pasted.
"""

from __future__ import annotations

import base64
import json
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from matplotlib.colors import LogNorm
from matplotlib.figure import Figure

import radtree.annual.metrics as metrics
from radtree.config import Project
from radtree.figures import new_figure, save_png

DPI = 150
MONTHS = ["Jan", "Feb", "Mar", "Apr", "May", "Jun", "Jul", "Aug", "Sep", "Oct", "Nov", "Dec"]
TREE_LABEL = {"with": "with tree", "without": "without tree"}


def _paths(project: Project) -> dict[str, Path]:
    res = project.results_dir
    return {"annual": res / "annual.csv", "summary": res / "annual_summary.csv",
            "monthly": res / "annual_monthly.csv", "hourly": res / "annual" / "hourly.npz",
            "meta": res / "annual" / "annual_meta.json", "figures": res / "annual" / "figures"}


def _figure(w: float, h: float) -> Figure:
    return new_figure(w, h, DPI)


def _save(fig: Figure, path: Path) -> Path:
    return save_png(fig, path, DPI)


def plane_coordinates(points: np.ndarray, normals: np.ndarray) -> tuple[np.ndarray, np.ndarray,
                                                                        str, str]:
    """2-D coordinates for a map of a planar grid: plan (x, y) for a horizontal grid, (along
    the wall, height) for a vertical one."""
    n = np.asarray(normals, float).mean(axis=0)
    if abs(n[2]) > 0.7:
        return points[:, 0], points[:, 1], "x (m, east)", "y (m, north)"
    along = np.array([n[1], -n[0], 0.0])
    along /= max(np.linalg.norm(along), 1e-12)
    return points @ along, points[:, 2], "along the façade (m)", "height (m)"


def _map_grid(project: Project, data: dict, annual: pd.DataFrame, grid: str, out: Path) -> Path:
    pts, nrm = data[f"points__{grid}"], data[f"normals__{grid}"]
    u, v, xl, yl = plane_coordinates(pts, nrm)
    span = max(np.ptp(u), np.ptp(v), 1.0)
    cols = [("da_300", "DA300 (% of occupied hours)", (0, 100), "viridis"),
            ("udi_300_3000", "UDI 300–3000 lx (% of occupied hours)", (0, 100), "viridis"),
            ("ase_hours", "direct sun > 1000 lx (occupied hours)", None, "magma")]
    fig = _figure(11.0, 6.2 if np.ptp(v) > 0.5 * np.ptp(u) else 4.8)
    axes = fig.subplots(2, 3, squeeze=False)
    vmax_ase = max(float(annual.loc[annual.grid == grid, "ase_hours"].max()), 250.0)
    for r, tree in enumerate(("without", "with")):
        sub = annual[(annual.grid == grid) & (annual.tree == tree)].sort_values("sensor")
        for c, (col, label, lim, cmap) in enumerate(cols):
            ax = axes[r][c]
            lo, hi = lim if lim is not None else (0.0, vmax_ase)
            n = max(len(sub), 1)
            size = (0.9 * 72 * 3.2 * (np.sqrt(np.ptp(u) * max(np.ptp(v), 0.1) / n) / span)) ** 2
            sc = ax.scatter(u, v, c=sub[col].to_numpy(), cmap=cmap, vmin=lo, vmax=hi,
                            marker="s", s=max(size, 20.0), edgecolors="none")
            ax.set_aspect("equal", adjustable="datalim")
            ax.set_title(f"{TREE_LABEL[tree]}: {label.split(' (')[0]}", fontsize=9)
            ax.tick_params(labelsize=7)
            if r == 1:
                ax.set_xlabel(xl, fontsize=8)
            if c == 0:
                ax.set_ylabel(yl, fontsize=8)
            cb = fig.colorbar(sc, ax=ax, shrink=0.85)
            cb.set_label(label, fontsize=7)
            cb.ax.tick_params(labelsize=7)
    fig.suptitle(f"Annual daylight metrics on the {grid} grid ({project.name})", fontsize=10)
    return _save(fig, out)


def _heatmap_grid(project: Project, data: dict, meta: dict, grid: str, out: Path) -> Path:
    month, hour = data["month"], data["hour"]
    with_ = metrics.month_hour_mean(data[f"total__with__{grid}"], month, hour)
    without = metrics.month_hour_mean(data[f"total__without__{grid}"], month, hour)
    in_leaf = data["leaf_fraction"] if "leaf_fraction" in data else data["in_leaf"]
    leaf_frac = np.array([in_leaf[month == m].mean() for m in range(1, 13)])
    state = ["leaf" if f > 0.999 else "bare" if f < 0.001 else f"{100 * f:.0f}% leaf"
             for f in leaf_frac]
    vmax = max(float(np.max(with_)), float(np.max(without)), 10.0)
    norm = LogNorm(vmin=max(vmax / 1e3, 1.0), vmax=vmax)
    fig = _figure(12.0, 4.6)
    axes = fig.subplots(1, 3)
    ratio = np.where(without > 1.0, with_ / np.maximum(without, 1e-9), np.nan)
    panels = [(without, "without tree: mean illuminance (lx)", "viridis", norm),
              (with_, "with tree: mean illuminance (lx)", "viridis", norm),
              (ratio, "with / without tree", "RdBu", None)]
    for ax, (arr, title, cmap, nrm) in zip(axes, panels):
        a = np.where(arr > 0, arr, np.nan) if nrm is not None else arr
        kw = {"norm": nrm} if nrm is not None else {"vmin": 0.0, "vmax": 2.0}
        im = ax.imshow(a, aspect="auto", origin="upper", cmap=cmap,
                       extent=(0, 24, 12, 0), **kw)
        ax.set_xticks(range(0, 25, 3))
        ax.set_yticks(np.arange(12) + 0.5)
        ax.set_yticklabels([f"{MONTHS[m]} ({state[m]})" for m in range(12)], fontsize=7)
        ax.set_xlabel("hour of the day (local standard time)", fontsize=8)
        ax.set_title(title, fontsize=9)
        ax.tick_params(labelsize=7)
        occ = meta.get("occupancy", [8, 18])
        for x in occ:
            ax.axvline(x, color="white" if nrm is not None else "black", lw=0.6, ls="--")
        fig.colorbar(im, ax=ax, shrink=0.85).ax.tick_params(labelsize=7)
    season = (f"phenology of {meta['phenology']['species']}" if "phenology" in meta else
              f"in leaf {meta.get('leaf_on')} → {meta.get('leaf_off')} (MM-DD)")
    fig.suptitle(f"Month × hour mean illuminance on the {grid} grid — crown {season}; "
                 "dashed: occupancy", fontsize=10)
    return _save(fig, out)


def season_text(meta: dict) -> str:
    """How the crown's season was set, from the run's record (never a default sentence)."""
    if "phenology" in meta:
        ph = meta["phenology"]
        return ph.get("describe") or f"in leaf by the phenology of {ph.get('species')}"
    return (f"in leaf from {meta['leaf_on']} to {meta['leaf_off']} (MM-DD, "
            f"{meta['leaf_days']} days; {meta.get('leaf_source', 'dates given')}), bare "
            "branches otherwise")


def _monthly_grid(monthly: pd.DataFrame, grid: str, out: Path) -> Path:
    fig = _figure(7.0, 3.6)
    ax = fig.subplots()
    for tree, style in (("without", "--"), ("with", "-")):
        sub = monthly[(monthly.grid == grid) & (monthly.tree == tree)].sort_values("month")
        ax.plot(sub.month, sub.mean_lux, style, marker="o", label=TREE_LABEL[tree])
    w = monthly[(monthly.grid == grid) & (monthly.tree == "with")].sort_values("month")
    for m, ld, d in zip(w.month, w.leaf_on_days, w.days):
        if ld < d:
            ax.axvspan(m - 0.5, m + 0.5, color="0.85", alpha=1.0 - ld / d, lw=0, zorder=0)
    ax.set_xticks(range(1, 13))
    ax.set_xticklabels(MONTHS, fontsize=8)
    ax.set_ylabel("mean illuminance, occupied hours (lx)", fontsize=8)
    ax.set_title(f"{grid}: monthly means (grey: months with bare crowns)", fontsize=9)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    return _save(fig, out)


def write_figures(project: Project) -> list[Path]:
    """Metric maps, month × hour heat maps and monthly means, one set per grid."""
    p = _paths(project)
    annual = pd.read_csv(p["annual"])
    monthly = pd.read_csv(p["monthly"])
    meta = json.loads(p["meta"].read_text())
    out: list[Path] = []
    with np.load(p["hourly"]) as npz:
        data = {k: npz[k] for k in npz.files}
    for g in meta["grids"]:
        out.append(_map_grid(project, data, annual, g, p["figures"] / f"annual_maps_{g}.png"))
        out.append(_heatmap_grid(project, data, meta, g, p["figures"] / f"annual_heatmap_{g}.png"))
        out.append(_monthly_grid(monthly, g, p["figures"] / f"annual_monthly_{g}.png"))
    return out


def _img(path: Path, alt: str) -> dict[str, str | None]:
    """A figure as inline PNG: ``data`` (base64, None when the file is missing), ``alt``."""
    data = base64.b64encode(path.read_bytes()).decode() if path.exists() else None
    return {"alt": alt, "data": data, "file": path.name}


def grid_summary(project: Project) -> pd.DataFrame:
    """Per grid and tree: sDA, ASE and the mean UDI bins / DA over the sensors."""
    p = _paths(project)
    return summarise(pd.read_csv(p["annual"]), pd.read_csv(p["summary"]))


def summarise(annual: pd.DataFrame, summary: pd.DataFrame) -> pd.DataFrame:
    """:func:`grid_summary` of the tables of :func:`radtree.annual.run.annual_tables`."""
    means = annual.groupby(["grid", "tree"], sort=False)[
        ["udi_below_100", "udi_100_300", "udi_300_3000", "udi_above_3000", "da_300",
         "ase_hours"]].mean().reset_index()
    first = summary.drop_duplicates(["grid", "tree"])[["grid", "tree", "sda_300_50",
                                                       "ase_1000_250"]]
    return first.merge(means, on=["grid", "tree"])


def annual_section_data(project: Project) -> dict[str, Any]:
    """The annual results of ``project`` as the data ``templates/sections/annual.html.j2``
    renders (``results`` False when there are none): metrics in % of occupied hours, monthly
    means in lux, figures as inline PNG."""
    p = _paths(project)
    if not (p["annual"].exists() and p["summary"].exists() and p["meta"].exists()):
        return {"results": False, "root": str(project.root)}
    meta = json.loads(p["meta"].read_text())
    if not all((p["figures"] / f"annual_maps_{g}.png").exists() for g in meta["grids"]):
        write_figures(project)
    table = grid_summary(project)
    monthly = pd.read_csv(p["monthly"])
    r = meta["rcontrib"]
    rows = [[str(row.grid), TREE_LABEL.get(row.tree, row.tree), f"{row.sda_300_50:.1f}",
             f"{row.ase_1000_250:.1f}", f"{row.udi_below_100:.1f}", f"{row.udi_100_300:.1f}",
             f"{row.udi_300_3000:.1f}", f"{row.udi_above_3000:.1f}", f"{row.da_300:.1f}",
             f"{row.ase_hours:.0f}"] for row in table.itertuples(index=False)]
    months = []
    for g in meta["grids"]:
        for tree in ("without", "with"):
            sub = monthly[(monthly.grid == g) & (monthly.tree == tree)].sort_values("month")
            months.append({"label": f"{g}, {TREE_LABEL[tree]}", "cells": [
                f"{v:.0f}{'*' if tree == 'with' and c != 'leaf' else ''}"
                for v, c in zip(sub.mean_lux, sub.crown)]})
    figures = []
    for g in meta["grids"]:
        figures += [
            _img(p["figures"] / f"annual_maps_{g}.png",
                 f"Annual metric maps on the {g} grid, with and without the tree"),
            _img(p["figures"] / f"annual_heatmap_{g}.png",
                 f"Month × hour mean illuminance on the {g} grid"),
            _img(p["figures"] / f"annual_monthly_{g}.png",
                 f"Monthly mean illuminance on the {g} grid")]
    t = meta.get("timing", {})
    timing = None
    if t:
        timing = (f"Wall time {t.get('total_s', float('nan')):.0f} s (scenes "
                  f"{t.get('scenes_s', 0):.0f} s, weather {t.get('weather_s', 0):.0f} s, "
                  + ", ".join(f"{k[:-2]} {v:.0f} s" for k, v in t.items()
                              if k[:-2] in ("without", "leaf_on", "leaf_off")) + ").")
    return {
        "results": True, "weather": meta["weather"], "sky_mf": meta["sky_mf"],
        "sun_mf": meta["sun_mf"], "rcontrib": f"-ab {r['ab']} -ad {r['ad']} -lw {r['lw']:g}",
        "occupancy": f"{meta['occupancy'][0]:g}–{meta['occupancy'][1]:g}",
        "occupied_hours": meta["occupied_hours"], "leaf_on": meta["leaf_on"],
        "leaf_off": meta["leaf_off"], "leaf_days": meta["leaf_days"],
        "season": season_text(meta),
        "scenarios": meta["scenarios"], "rows": rows, "months": list(MONTHS),
        "monthly": months, "figures": figures, "notes": [str(n) for n in meta.get("notes", [])],
        "timing": timing,
    }
