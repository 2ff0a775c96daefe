"""Office-block results per hour and grid (reference case §5): statistics, false-colour maps, report data.

Reads only the tidy results table ``PROJECT/results/illuminance.csv`` and writes

* ``PROJECT/results/summary.csv`` — one row per scenario × hour × grid × room: ``scenario,
  model, tree, time, grid, n_points, mean_lux, min_lux, max_lux, uniformity, pct_below_300,
  pct_300_2000, pct_above_2000, storey, room`` (``room`` ``"STOREY-BAY"``, storey 0 = the
  ground floor, :mod:`radtree.site.office`; both empty for a table without rooms). ``tree`` is
  ``without`` when the scenario's model is ``none``, else ``with``. Uniformity is min/mean. The office grids are equal-area grids
  (every point the centre of an equal cell), so the percentage of points in a band is the
  percentage of grid area: below 300 lx, 300–2000 lx (both bounds included: the "useful"
  band), above 2000 lx.
* ``PROJECT/report/office/<grid>_<HHMM>.png`` — false-colour maps of each grid and hour, one
  panel per scenario side by side (with and without the tree), on a **logarithmic** colour
  scale shared by all hours and scenarios of the grid, lux legend, cell values written in. A
  grid that is not one plane (work planes of several storeys) is drawn per storey,
  ``<grid>_s<STOREY>_<HHMM>.png``; a façade grid over several rooms is one elevation.
* ``PROJECT/report/office/<grid>_hourly.png`` — the hourly mean and the area bands of the
  whole grid (every sensed room: the rooms' equal-area cells pooled).

:func:`office_section_data` gives the report's office section (tables + maps) as plain data.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from radtree.config import Project
from radtree.errors import RadtreeError
from radtree.fileio import atomic_path
from radtree.office_rooms import fmt as _f
from radtree.office_rooms import room_names, rooms_data, scenario_pair, whole_grid
from radtree.pipeline.assemble import facade_frame
from radtree.pipeline.results import read_results
from radtree.site.frame import FacadeFrame

LOW_LUX = 300.0
HIGH_LUX = 2000.0
SUMMARY_COLUMNS = [
    "scenario", "model", "tree", "time", "grid", "n_points", "mean_lux", "min_lux", "max_lux",
    "uniformity", "pct_below_300", "pct_300_2000", "pct_above_2000", "storey", "room",
]
GRID_TITLES = {"facade": "Façade (outside the glazing, vertical)",
               "workplane": "Work plane (horizontal)"}


# ---------------------------------------------------------------- statistics
def area_fractions(lux: np.ndarray, low: float = LOW_LUX, high: float = HIGH_LUX
                   ) -> tuple[float, float, float]:
    """Percent of equal-area points below ``low``, in [low, high] (both included), above
    ``high``. The three add up to 100."""
    v = np.asarray(lux, float).ravel()
    if v.size == 0:
        raise ValueError("no illuminance values")
    if not np.all(np.isfinite(v)):
        raise ValueError("illuminance values must be finite")
    below = float(np.count_nonzero(v < low))
    above = float(np.count_nonzero(v > high))
    useful = v.size - below - above
    return 100.0 * below / v.size, 100.0 * useful / v.size, 100.0 * above / v.size


def grid_statistics(lux: np.ndarray) -> dict[str, float]:
    """Mean, min, max, uniformity (min/mean) and the three area bands of one grid and hour."""
    v = np.asarray(lux, float).ravel()
    below, useful, above = area_fractions(v)
    mean = float(v.mean())
    return {
        "n_points": float(v.size), "mean_lux": mean, "min_lux": float(v.min()),
        "max_lux": float(v.max()),
        "uniformity": float(v.min() / mean) if mean > 0 else math.nan,
        "pct_below_300": below, "pct_300_2000": useful, "pct_above_2000": above,
    }


def tree_label(model: str) -> str:
    return "without" if str(model) == "none" else "with"


def summarise(table: pd.DataFrame) -> pd.DataFrame:
    """The per scenario × hour × grid × room summary of a results table (see module doc)."""
    need = {"scenario", "model", "time", "grid", "lux"}
    missing = need - set(table.columns)
    if missing:
        raise RadtreeError(f"results table lacks column(s) {', '.join(sorted(missing))}")
    rooms = "room" in table.columns and bool(table["room"].notna().any())
    table = table.assign(room=room_names(table) if rooms else "")
    rows = []
    order = list(dict.fromkeys(table["scenario"].astype(str)))
    for (scen, time, grid, room), g in table.groupby(["scenario", "time", "grid", "room"],
                                                     sort=False):
        models = g["model"].astype(str).unique()
        model = models[0]
        stats = grid_statistics(g["lux"].to_numpy(float))
        storey = int(g["storey"].iloc[0]) if room and "storey" in g.columns else None
        rows.append({"scenario": str(scen), "model": model, "tree": tree_label(model),
                     "time": str(time), "grid": str(grid), **stats, "storey": storey,
                     "room": room})
    out = pd.DataFrame(rows, columns=SUMMARY_COLUMNS)
    out["n_points"] = out["n_points"].astype(int)
    out["storey"] = out["storey"].astype("Int64")
    rank = {s: i for i, s in enumerate(order)}
    room_rank = {r: i for i, r in enumerate(dict.fromkeys(table["room"]))}
    out = out.sort_values(["grid", "room", "time", "scenario"],
                          key=lambda c: c.map(rank) if c.name == "scenario" else
                          c.map(room_rank) if c.name == "room" else c)
    return out.reset_index(drop=True)


def summary_path(project: Project) -> Path:
    return project.results_dir / "summary.csv"


def office_dir(project: Project) -> Path:
    return project.report_dir / "office"


def write_summary(project: Project, maps: bool = True) -> Path:
    """Write ``results/summary.csv`` (and the maps in ``report/office/``); return its path."""
    table = read_results(project)
    summary = summarise(table)
    out = summary_path(project)
    with atomic_path(out) as tmp:
        summary.to_csv(tmp, index=False, float_format="%.6g")
    if maps:
        write_maps(project, table)
        write_hourly_charts(project, summary)
    return out


# ---------------------------------------------------------------- maps
def _plane_axes(local: np.ndarray) -> tuple[np.ndarray, np.ndarray, str, str, bool]:
    """The two in-plane coordinates of a planar grid (façade frame), their labels, and
    whether the second axis is drawn downwards (plan view: façade at the top)."""
    spread = local.max(axis=0) - local.min(axis=0)
    normal_axis = int(np.argmin(spread))
    if normal_axis == 2:                         # horizontal: plan, depth behind the façade
        return local[:, 0], -local[:, 1], "along the façade u (m)", "depth behind the façade (m)", True
    if normal_axis == 1:                         # vertical, parallel to the façade
        return local[:, 0], local[:, 2], "along the façade u (m)", "height above the street (m)", False
    return local[:, 1], local[:, 2], "n (m)", "height above the street (m)", False


def _cells(a: np.ndarray, b: np.ndarray, values: np.ndarray
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Cell edges along both axes and the value image (NaN where a cell has no point)."""
    ua = np.unique(np.round(a, 4))
    ub = np.unique(np.round(b, 4))

    def edges(c: np.ndarray) -> np.ndarray:
        if len(c) == 1:
            return np.array([c[0] - 0.25, c[0] + 0.25])
        mid = 0.5 * (c[1:] + c[:-1])
        return np.concatenate([[c[0] - (mid[0] - c[0])], mid, [c[-1] + (c[-1] - mid[-1])]])

    img = np.full((len(ub), len(ua)), np.nan)
    ia = np.searchsorted(ua, np.round(a, 4))
    ib = np.searchsorted(ub, np.round(b, 4))
    img[ib, ia] = values
    return edges(ua), edges(ub), img


def _nice_limits(lo: float, hi: float) -> tuple[float, float]:
    """Round a positive range outwards to 1-2-5 steps (for a log colour scale)."""
    lo = max(lo, 1.0)
    hi = max(hi, lo * 1.01)

    def down(x: float) -> float:
        e = 10 ** math.floor(math.log10(x))
        return max(m * e for m in (1, 2, 5) if m * e <= x * (1 + 1e-9))

    def up(x: float) -> float:
        e = 10 ** math.floor(math.log10(x))
        return min(m * e for m in (1, 2, 5, 10) if m * e >= x * (1 - 1e-9))

    return down(lo), up(hi)


def _fmt_lux(v: float) -> str:
    if not np.isfinite(v):
        return ""
    if v >= 9950:
        return f"{v / 1000:.0f}k"
    if v >= 995:
        return f"{v / 1000:.1f}k"
    return f"{v:.0f}"


def _time_label(t: str) -> str:
    return str(t).replace(":", "")


def map_filename(grid: str, time: str, storey: int | None = None) -> str:
    """``<grid>_<HHMM>.png``, or ``<grid>_s<storey>_<HHMM>.png`` for one storey's part."""
    part = "" if storey is None else f"_s{storey}"
    return f"{grid}{part}_{_time_label(time)}.png"


def _map_parts(gt: pd.DataFrame, frame: FacadeFrame) -> list[tuple[int | None, pd.DataFrame]]:
    """A grid's rows as drawn: whole when its points lie in one plane (one room, or a façade
    over several rooms), else one part per storey (work planes of several storeys)."""
    local = frame.to_local(gt[["x", "y", "z"]].to_numpy(float))
    planar = float(np.ptp(local, axis=0).min()) < 1e-6
    if planar or "storey" not in gt.columns or gt["storey"].nunique() <= 1:
        return [(None, gt)]
    return [(int(k), part) for k, part in gt.groupby("storey", sort=True)]


def _map_panel(ax: Any, st: pd.DataFrame, scen: str, frame: Any, norm: Any) -> Any:
    """One scenario's false-colour panel of a map (its sensors' lux written on the cells,
    clipped to the norm's range); returns the colour mesh."""
    lo, hi = norm.vmin, norm.vmax
    st = st.sort_values("sensor")
    local = frame.to_local(st[["x", "y", "z"]].to_numpy(float))
    a, b, xlabel, ylabel, flip = _plane_axes(local)
    ea, eb, img = _cells(a, b, st["lux"].to_numpy(float))
    mesh = ax.pcolormesh(ea, eb, np.clip(img, lo, hi), norm=norm, cmap="inferno", shading="flat")
    ua = 0.5 * (ea[1:] + ea[:-1])
    ub = 0.5 * (eb[1:] + eb[:-1])
    for ib, bv in enumerate(ub):
        for ia, av in enumerate(ua):
            v = img[ib, ia]
            if np.isfinite(v):
                light = norm(max(v, lo)) < 0.6
                ax.text(av, bv, _fmt_lux(v), ha="center", va="center", fontsize=6,
                        color="white" if light else "black")
    ax.set_aspect("equal")
    if flip:
        ax.invert_yaxis()
    model = str(st["model"].iloc[0])
    ax.set_title(f"{scen} — {tree_label(model)} tree ({model})\n"
                 f"mean {st['lux'].mean():,.0f} lx", fontsize=9)
    ax.set_xlabel(xlabel, fontsize=8)
    ax.set_ylabel(ylabel, fontsize=8)
    ax.tick_params(labelsize=7)
    return mesh


def write_maps(project: Project, table: pd.DataFrame, out_dir: Path | None = None
               ) -> list[Path]:
    """One PNG per grid and hour: a false-colour panel per scenario, log lux scale."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm
    from matplotlib.ticker import FixedLocator, NullLocator

    out_dir = out_dir or office_dir(project)
    out_dir.mkdir(parents=True, exist_ok=True)
    frame = facade_frame(project)
    scen_order = list(dict.fromkeys(table["scenario"].astype(str)))
    written = []
    for grid, gt in table.groupby("grid", sort=False):
        lo, hi = _nice_limits(float(gt["lux"].clip(lower=1.0).min()), float(gt["lux"].max()))
        norm = LogNorm(vmin=lo, vmax=hi)
        ticks = [v for v in (1, 2, 5, 10, 20, 50, 100, 200, 300, 500, 1000, 2000, 5000, 10000,
                             20000, 50000, 100000, 200000) if lo <= v <= hi]
        for (time, storey, ht) in [(t, k, p) for t, tt in gt.groupby("time", sort=True)
                                   for k, p in _map_parts(tt, frame)]:
            scens = [s for s in scen_order if s in set(ht["scenario"].astype(str))]
            a0, b0, *_ = _plane_axes(frame.to_local(ht[["x", "y", "z"]].to_numpy(float)))
            ratio = (np.ptp(a0) + 0.5) / (np.ptp(b0) + 0.5)     # panel width / height
            panel_w = float(np.clip(3.8 * ratio, 2.4, 4.8))
            fig, axes = plt.subplots(1, len(scens), figsize=(panel_w * len(scens) + 1.4, 4.4),
                                     squeeze=False, constrained_layout=True)
            mesh = None
            for ax, scen in zip(axes[0], scens):
                mesh = _map_panel(ax, ht[ht["scenario"].astype(str) == scen], scen, frame, norm)
            assert mesh is not None
            cb = fig.colorbar(mesh, ax=list(axes[0]), shrink=0.9)
            cb.set_label("illuminance (lx), log scale", fontsize=8)
            cb.ax.yaxis.set_major_locator(FixedLocator(ticks))
            cb.ax.yaxis.set_minor_locator(NullLocator())
            cb.ax.set_yticklabels([f"{t:,}" for t in ticks], fontsize=7)
            title = GRID_TITLES.get(str(grid), str(grid))
            where = "" if storey is None else f" — storey {storey}"
            fig.suptitle(f"{title}{where} — {time} local — {project.site.date}", fontsize=10)
            path = out_dir / map_filename(str(grid), str(time), storey)
            with atomic_path(path) as tmp:
                fig.savefig(tmp, format="png", dpi=110)
            plt.close(fig)
            written.append(path)
    return written


def write_hourly_charts(project: Project, summary: pd.DataFrame, out_dir: Path | None = None
                        ) -> list[Path]:
    """Per grid: hourly mean illuminance (log) and the area bands, per scenario."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import FuncFormatter

    out_dir = out_dir or office_dir(project)
    out_dir.mkdir(parents=True, exist_ok=True)
    written = []
    plain = FuncFormatter(lambda v, _pos: f"{v:,.0f}")
    scen_order = list(dict.fromkeys(summary["scenario"].astype(str)))
    for grid, g in summary.groupby("grid", sort=False):
        g = whole_grid(g)
        times = sorted(g["time"].astype(str).unique())
        fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 3.6), constrained_layout=True)
        width = 0.8 / max(1, len(scen_order))
        x = np.arange(len(times))
        for i, scen in enumerate(scen_order):
            s = g[g["scenario"] == scen].set_index("time").reindex(times)
            if s["mean_lux"].isna().all():
                continue
            label = f"{scen} ({s['tree'].dropna().iloc[0]} tree)"
            ax1.plot(times, s["mean_lux"], marker="o", label=label)
            xs = x + (i - (len(scen_order) - 1) / 2) * width
            bottom = np.zeros(len(times))
            for col, colour in (("pct_below_300", "#4c72b0"), ("pct_300_2000", "#55a868"),
                                ("pct_above_2000", "#dd8452")):
                vals = s[col].fillna(0).to_numpy(float)
                ax2.bar(xs, vals, width * 0.95, bottom=bottom, color=colour,
                        edgecolor="white", linewidth=0.5,
                        label={"pct_below_300": "< 300 lx", "pct_300_2000": "300–2000 lx",
                               "pct_above_2000": "> 2000 lx"}[col] if i == 0 else None)
                bottom += vals
            for xx in xs:
                ax2.text(xx, 101, scen, ha="center", va="bottom", fontsize=6, rotation=90)
        ax1.set_yscale("log")
        ax1.yaxis.set_major_formatter(plain)
        ax1.yaxis.set_minor_formatter(plain)
        ax1.tick_params(axis="y", which="both", labelsize=7)
        ax1.set_ylabel("mean illuminance (lx), log scale")
        ax1.set_xlabel("local time")
        ax1.axhline(LOW_LUX, color="grey", lw=0.6, ls=":")
        ax1.axhline(HIGH_LUX, color="grey", lw=0.6, ls=":")
        ax1.legend(fontsize=8)
        ax1.grid(alpha=0.3, which="both")
        ax2.set_xticks(x, times)
        ax2.set_ylim(0, 118)
        ax2.set_ylabel("% of grid area")
        ax2.set_xlabel("local time (bars: " + ", ".join(scen_order) + ")")
        ax2.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.0, 0.5))
        fig.suptitle(GRID_TITLES.get(str(grid), str(grid)) + " — hourly", fontsize=10)
        path = out_dir / f"{grid}_hourly.png"
        with atomic_path(path) as tmp:
            fig.savefig(tmp, format="png", dpi=110)
        plt.close(fig)
        written.append(path)
    return written


# ---------------------------------------------------------------- report section
def _summary_for_report(project: Project) -> pd.DataFrame:
    """The summary, (re)written when missing or older than the results table."""
    results = project.results_dir / "illuminance.csv"
    out = summary_path(project)
    maps_ok = office_dir(project).exists()
    if (not out.exists() or not maps_ok
            or (results.exists() and results.stat().st_mtime > out.stat().st_mtime)):
        write_summary(project)
    return pd.read_csv(out, dtype={"time": str, "scenario": str, "grid": str})


#: The columns of a grid's office table per scenario: summary column, label, decimals.
GRID_COLUMNS = [("mean_lux", "mean lx", 0), ("uniformity", "U₀ min/mean", 2),
                ("pct_below_300", "% < 300", 0), ("pct_300_2000", "% 300–2000", 0),
                ("pct_above_2000", "% > 2000", 0)]


def _grid_data(g: pd.DataFrame, scen_order: list[str]) -> dict[str, Any]:
    """One grid's consultant-style table: per hour (and the day mean) and scenario the mean,
    uniformity and area bands, and the with / without ratio when there is one of each."""
    times = sorted(g["time"].astype(str).unique())
    scens, tree_of, pair = scenario_pair(g, scen_order)
    cols = GRID_COLUMNS
    rows = []
    idx = g.set_index(["scenario", "time"])
    for t in [*times, "day"]:
        cells: list[dict[str, Any]] = []
        means = {}
        for s in scens:
            if t == "day":
                sub = g[g["scenario"] == s]
                vals = {c: float(sub[c].mean()) for c, _, _ in cols}
            else:
                if (s, t) not in idx.index:
                    cells.extend({"text": "–", "num": False} for _ in cols)
                    continue
                r = idx.loc[(s, t)]
                vals = {c: float(r[c]) for c, _, _ in cols}
            means[s] = vals["mean_lux"]
            cells.extend({"text": _f(vals[c], d), "num": True} for c, _, d in cols)
        if pair:
            w, wo = means.get(pair[0]), means.get(pair[1])
            cells.append({"text": f"{100 * w / wo:.0f} %" if w is not None and wo and wo > 0
                          else "–", "num": True})
        rows.append({"label": "day mean" if t == "day" else t, "total": t == "day",
                     "cells": cells})
    return {"scenarios": [{"name": s, "tree": tree_of[s]} for s in scens],
            "columns": [c[1] for c in cols], "pair": pair is not None, "rows": rows}


def _maps(project: Project, grid: str, times: list[str], prefix: str) -> list[dict[str, str]]:
    """The grid's map images per hour as written (whole, or per storey)."""
    folder = office_dir(project)
    out = []
    for t in times:
        whole = map_filename(grid, t)
        parts = sorted(folder.glob(f"{grid}_s*_{_time_label(t)}.png"),
                       key=lambda p: int(p.name[len(grid) + 2:].split("_")[0]))
        if (folder / whole).exists() or not parts:
            out.append({"src": prefix + whole, "time": t})
        else:
            out += [{"src": prefix + p.name,
                     "time": f"{t}, storey {p.name[len(grid) + 2:].split('_')[0]}"}
                    for p in parts]
    return out


def office_section_data(project: Project, image_prefix: str = "office/") -> dict[str, Any]:
    """The report's office section as the data ``templates/sections/office.html.j2`` renders:
    per grid a consultant-style table (hour × scenario: mean lux, uniformity and the area bands
    in % of grid area) and the false-colour maps. Image paths are ``image_prefix + name`` (maps
    live in ``PROJECT/report/office/``, so the default suits ``PROJECT/report/*.html``)."""
    summary = _summary_for_report(project)
    scen_order = [s.name for s in project.scenarios if s.name in set(summary["scenario"])]
    scen_order += [s for s in dict.fromkeys(summary["scenario"]) if s not in scen_order]
    o = project.office
    description = None
    if o is not None:
        from radtree.site.office import office_layout

        lay = office_layout(project)
        floors = ", ".join(f"{n} (floor {lay.floor_z(k):g} m)" for n, k, _ in lay.sensed)
        description = (
            f"{o.bays} × {o.storeys} offices ({o.width_m:g} m wide, "
            f"{lay.room_height:g} m high, {o.depth_m:g} m deep) behind the façade, "
            f"glazing Tn {o.glazing_transmittance:g} with {100 * o.frame_fraction:g} % "
            f"frame; results in {len(lay.sensed)} office(s), named STOREY-BAY (storey 0 = "
            f"ground floor, bay 0 = leftmost seen from the street): {floors}. "
            f"Façade grid: {o.facade_grid_spacing_m:g} m cells just outside the glazing, "
            f"facing the street. Work plane: {o.workplane_height_m:g} m above the floor, "
            f"{o.grid_spacing_m:g} m cells, {o.wall_offset_m:g} m from the walls. "
            "Area bands use equal-area cells: < 300 lx, 300–2000 lx (both bounds "
            "included, 'useful'), > 2000 lx. U₀ = min/mean.")
    sky = None   # the light of each hour: the report's "light traced" section (manifest)
    grids = []
    for grid, g in summary.groupby("grid", sort=False):
        times = sorted(g["time"].astype(str).unique())
        grids.append({
            "title": GRID_TITLES.get(str(grid), str(grid)),
            **_grid_data(whole_grid(g), scen_order), "rooms": rooms_data(g, scen_order),
            "hourly_image": f"{image_prefix}{grid}_hourly.png",
            "maps": _maps(project, str(grid), times, image_prefix)})
    return {"description": description, "sky": sky, "grids": grids}
