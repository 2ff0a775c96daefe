"""The report's façade section of an inventory project (``[site] buildings``): a site plan
coloured by façade illuminance and a table per building — shown only when
``results/facades.geojson`` exists (written by ``simulate``).
"""

from __future__ import annotations

import base64
import json
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from radtree.config import Project
from radtree.stats import FACADE_GRID

PLAN_FILE = "facades_plan.png"


def as_one_facade_grid(results: pd.DataFrame) -> pd.DataFrame:
    """The façade-chunk grids of an inventory project (rows with a ``facade``) as the one
    ``facade`` grid the core report sections read: its hourly means are then the means over
    every simulated façade sensor; sensors renumbered per scenario × hour."""
    if "facade" not in results.columns or results["facade"].isna().all():
        return results
    out = results.copy()
    on = out["facade"].notna()
    out.loc[on, "grid"] = FACADE_GRID
    out.loc[on, "sensor"] = out[on].groupby(["scenario", "time"]).cumcount()
    return out


def _scenarios(props: list[dict[str, Any]]) -> list[str]:
    """Scenario names with a period mean ``lux_<scenario>`` in the features, in file order."""
    names: list[str] = []
    for p in props:
        for k in p:
            if k.startswith("lux_") and k.count("_") >= 1 and ":" not in k:
                name = k[4:]
                if name not in names:
                    names.append(name)
    return names


def site_plan(project: Project, features: list[dict], scenarios: list[str], path: Path) -> str:
    """One panel per scenario: footprints (grey), crowns (green discs, to scale), façades as
    thick segments coloured by their mean illuminance over the hours (lx, one colour scale)."""
    from matplotlib import colormaps
    from matplotlib.collections import LineCollection
    from matplotlib.colors import Normalize
    from matplotlib.patches import Circle, Polygon

    from radtree.figures import new_figure, save_png
    from radtree.site.district import load_district

    inputs = load_district(project)
    facades = {f.id: f for f in inputs.facades}
    values = [f["properties"].get(f"lux_{s}") for f in features for s in scenarios]
    finite = [v for v in values if v is not None]
    norm = Normalize(min(finite), max(finite)) if finite else Normalize(0, 1)
    cmap = colormaps["viridis"]
    n = max(1, len(scenarios))
    fig = new_figure(5.2 * n + 0.8, 5.0, 150)
    axes = fig.subplots(1, n, squeeze=False)[0]
    for ax, scen in zip(axes, scenarios or [""]):
        for b in inputs.buildings:
            ax.add_patch(Polygon(np.asarray(b.polygon.exterior.coords), closed=True,  # type: ignore[attr-defined]
                                 facecolor="0.85", edgecolor="0.5", linewidth=0.5))
        segs, cols = [], []
        for f in features:
            fac = facades.get(f["properties"]["facade"])
            v = f["properties"].get(f"lux_{scen}")
            if fac is None or v is None:
                continue
            segs.append([fac.start + 0.6 * fac.normal, fac.end + 0.6 * fac.normal])
            cols.append(cmap(norm(v)))
        ax.add_collection(LineCollection(segs, colors=cols, linewidths=3.5))
        with_trees = any(f"lux_{scen}" in f["properties"] for f in features) and \
            scen in _tree_scenarios(project)
        if with_trees:
            for t in inputs.trees:
                ax.add_patch(Circle((t.x, t.y), t.crown_radius_m, facecolor=(0.2, 0.6, 0.2, 0.35),
                                    edgecolor=(0.1, 0.4, 0.1, 0.8), linewidth=0.4))
        ax.set_aspect("equal")
        ax.autoscale_view()
        ax.set_title(f"scenario {scen}" + (" (with trees)" if with_trees else ""))
        ax.set_xlabel("x east (m)")
        ax.set_ylabel("y north (m)")
    from matplotlib.cm import ScalarMappable

    fig.colorbar(ScalarMappable(norm=norm, cmap=cmap), ax=list(axes),
                 label="façade illuminance, mean over the hours (lx)")
    save_png(fig, path, 150)
    return ("Site plan: building footprints (grey), tree crowns to scale (green), each simulated "
            "façade coloured by its illuminance averaged over its sensors, storeys and the "
            "simulated hours (lx).")


def _tree_scenarios(project: Project) -> set[str]:
    return {s.name for s in project.scenarios if s.model != "none"}


def facades_data(project: Project, out: Path) -> dict[str, Any] | None:
    """The section's data (None without ``results/facades.geojson``); writes the plan PNG."""
    path = project.results_dir / "facades.geojson"
    if not path.exists():
        return None
    fc = json.loads(path.read_text(encoding="utf-8"))
    features = fc.get("features") or []
    if not features:
        return None
    props = [f["properties"] for f in features]
    scenarios = _scenarios(props)
    png = out / PLAN_FILE
    caption = site_plan(project, features, scenarios, png)
    by_b: dict[str, dict[str, list[float]]] = {}
    for p in props:
        for s in scenarios:
            if f"lux_{s}" in p:
                by_b.setdefault(p["building"], {}).setdefault(s, []).append(p[f"lux_{s}"])
    rows = [{"building": b, "facades": str(max(len(v) for v in d.values())),
             "cells": [f"{np.mean(d[s]):.0f}" if s in d else "–" for s in scenarios]}
            for b, d in sorted(by_b.items())]
    return {"features": len(features), "buildings": len(by_b), "scenarios": scenarios,
            "rows": rows, "caption": caption, "file": PLAN_FILE,
            "data": base64.b64encode(png.read_bytes()).decode("ascii")}
