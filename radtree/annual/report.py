"""Figures and the HTML fragment of the annual run.

Reads only what :func:`radtree.annual.run.write_annual` wrote:
``results/annual.csv``, ``results/annual_summary.csv``, ``results/annual_monthly.csv``,
``results/annual/hourly.npz`` and ``results/annual/annual_meta.json``. Figures go to
``results/annual/figures/`` (outside ``report/``, which the report builder replaces whole);
:func:`annual_report_section` embeds them as inline PNG so the fragment works wherever it
is pasted.
"""

from __future__ import annotations

import base64
import html
import json
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.colors import LogNorm
from matplotlib.figure import Figure

from radtree.annual import metrics
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
    in_leaf = data["in_leaf"]
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
    fig.suptitle(f"Month × hour mean illuminance on the {grid} grid — crown in leaf "
                 f"{meta.get('leaf_on')} → {meta.get('leaf_off')} (MM-DD); dashed: occupancy",
                 fontsize=10)
    return _save(fig, out)


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


def _img(path: Path, alt: str) -> str:
    if not path.exists():
        return f"<p><em>figure missing: {html.escape(path.name)}</em></p>"
    b64 = base64.b64encode(path.read_bytes()).decode()
    return (f'<figure><img alt="{html.escape(alt)}" src="data:image/png;base64,{b64}" '
            f'style="max-width:100%"><figcaption>{html.escape(alt)}</figcaption></figure>')


def grid_summary(project: Project) -> pd.DataFrame:
    """Per grid and tree: sDA, ASE and the mean UDI bins / DA over the sensors."""
    p = _paths(project)
    annual = pd.read_csv(p["annual"])
    summary = pd.read_csv(p["summary"])
    means = annual.groupby(["grid", "tree"], sort=False)[
        ["udi_below_100", "udi_100_300", "udi_300_3000", "udi_above_3000", "da_300",
         "ase_hours"]].mean().reset_index()
    first = summary.drop_duplicates(["grid", "tree"])[["grid", "tree", "sda_300_50",
                                                       "ase_1000_250"]]
    return first.merge(means, on=["grid", "tree"])


def annual_report_section(project: Project) -> str:
    """An HTML fragment (``<section>``) with the annual results of ``project``."""
    p = _paths(project)
    if not (p["annual"].exists() and p["summary"].exists() and p["meta"].exists()):
        return ('<section class="annual"><h2>Annual daylight</h2><p>No annual results: run '
                f"<code>radtree annual {html.escape(str(project.root))}</code>.</p></section>")
    meta = json.loads(p["meta"].read_text())
    if not all((p["figures"] / f"annual_maps_{g}.png").exists() for g in meta["grids"]):
        write_figures(project)
    table = grid_summary(project)
    monthly = pd.read_csv(p["monthly"])
    w = meta["weather"]
    esc = html.escape
    parts = ['<section class="annual">', "<h2>Annual daylight with a deciduous tree</h2>"]
    if w.get("generated"):
        parts.append('<p class="warning"><strong>Weather: GENERATED clear-sky year</strong> '
                     f"({esc(w['description'])}) — not measured data; every day is clear, so "
                     "daylight autonomy and sunlight exposure are upper bounds. Point "
                     "<code>[light] epw</code> at a measured or typical-year EPW.</p>")
    else:
        parts.append(f"<p>Weather: {esc(w['description'])}.</p>")
    r = meta["rcontrib"]
    parts.append(
        "<p>Method: daylight coefficients (<code>rcontrib</code>, sky in Reinhart MF "
        f"{meta['sky_mf']} patches, <code>-ab {r['ab']} -ad {r['ad']} -lw {r['lw']:g}</code>) × "
        "the <code>gendaymtx -s</code> sky of every hour; direct sun from a 0.533° sun at each "
        "hour's exact position (<code>gendaymtx -D</code>, <code>-ab 0</code>); sunlight "
        f"reflected by the scene from unit suns at Reinhart MF {meta['sun_mf']} patch centres, "
        "interpolated to each hour's sun. All 8760 hours; night hours are 0 lx. "
        f"Occupancy {meta['occupancy'][0]:g}–{meta['occupancy'][1]:g} h every day "
        f"({meta['occupied_hours']} hours). Crown in leaf from {esc(meta['leaf_on'])} to "
        f"{esc(meta['leaf_off'])} (MM-DD, {meta['leaf_days']} days; an assumption for "
        "<em>Morus alba</em> in Mendoza), bare branches otherwise. Scenarios: with tree "
        f"'{esc(meta['scenarios']['with'])}', without '{esc(meta['scenarios']['without'])}'."
        "</p>")
    parts.append("<table><thead><tr><th>grid</th><th>tree</th><th>sDA300/50% (%)</th>"
                 "<th>ASE1000,250 (%)</th><th>UDI &lt;100</th><th>UDI 100–300</th>"
                 "<th>UDI 300–3000</th><th>UDI &gt;3000</th><th>DA300</th>"
                 "<th>direct-sun hours</th></tr></thead><tbody>")
    for row in table.itertuples(index=False):
        parts.append(
            f"<tr><td>{esc(str(row.grid))}</td><td>{esc(TREE_LABEL.get(row.tree, row.tree))}"
            f"</td><td>{row.sda_300_50:.1f}</td><td>{row.ase_1000_250:.1f}</td>"
            f"<td>{row.udi_below_100:.1f}</td><td>{row.udi_100_300:.1f}</td>"
            f"<td>{row.udi_300_3000:.1f}</td><td>{row.udi_above_3000:.1f}</td>"
            f"<td>{row.da_300:.1f}</td><td>{row.ase_hours:.0f}</td></tr>")
    parts.append("</tbody></table><p><small>UDI and DA: % of occupied hours, mean over the "
                 "grid's sensors (UDI bins: E &lt; 100, 100 ≤ E &lt; 300, 300 ≤ E ≤ 3000, "
                 "E &gt; 3000 lx). sDA and ASE are IES LM-83 metrics of the horizontal work "
                 "plane (no blinds operated); on a façade grid they are shown for comparison "
                 "only.</small></p>")
    parts.append("<h3>Monthly means (occupied hours)</h3><table><thead><tr><th>grid</th>"
                 + "".join(f"<th>{m}</th>" for m in MONTHS) + "</tr></thead><tbody>")
    for g in meta["grids"]:
        for tree in ("without", "with"):
            sub = monthly[(monthly.grid == g) & (monthly.tree == tree)].sort_values("month")
            cells = "".join(
                f"<td>{v:.0f}{'*' if tree == 'with' and c != 'leaf' else ''}</td>"
                for v, c in zip(sub.mean_lux, sub.crown))
            parts.append(f"<tr><td>{esc(g)}, {TREE_LABEL[tree]}</td>{cells}</tr>")
    parts.append("</tbody></table><p><small>lx; * months with bare (or partly bare) "
                 "crowns.</small></p>")
    for g in meta["grids"]:
        parts.append(_img(p["figures"] / f"annual_maps_{g}.png",
                          f"Annual metric maps on the {g} grid, with and without the tree"))
        parts.append(_img(p["figures"] / f"annual_heatmap_{g}.png",
                          f"Month × hour mean illuminance on the {g} grid"))
        parts.append(_img(p["figures"] / f"annual_monthly_{g}.png",
                          f"Monthly mean illuminance on the {g} grid"))
    if meta.get("notes"):
        parts.append("<h3>Notes</h3><ul>" + "".join(f"<li>{esc(n)}</li>" for n in meta["notes"])
                     + "</ul>")
    t = meta.get("timing", {})
    if t:
        parts.append(f"<p><small>Wall time {t.get('total_s', float('nan')):.0f} s "
                     f"(scenes {t.get('scenes_s', 0):.0f} s, weather "
                     f"{t.get('weather_s', 0):.0f} s, "
                     + ", ".join(f"{k[:-2]} {v:.0f} s" for k, v in t.items()
                                 if k[:-2] in ("without", "leaf_on", "leaf_off"))
                     + ").</small></p>")
    parts.append("</section>")
    return "\n".join(parts)
