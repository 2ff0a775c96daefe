"""The report's first section, "What the trees do": the change each with-trees scenario makes
against the baseline (:mod:`radtree.report.impact`) per façade, storey and room — over the day
and hour by hour, in lux and per cent — the annual metrics with and without trees when the
annual results exist (``results/annual.csv``, ``annual_summary.csv``, ``annual/standards.csv``),
the trees ranked by the light they remove when ``results/tree_impact.csv`` exists, and a site
plan (x east, y north) coloured by the % change.

Also writes the same numbers for spreadsheets and GIS: ``results/rooms.csv`` (rooms: one row per
room × quantity × time; quantity ``illuminance`` in lx at each hour and over the ``day``, then
each annual metric at time ``annual``) and, in an inventory project, the change per façade into
``results/facades.geojson`` (``baseline``, ``trees``, ``change_lux``, ``change_pct`` over the day
and ``change_lux_<HH:MM>``, ``change_pct_<HH:MM>`` per hour, ``lux_without``).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from radtree.config import Project
from radtree.fileio import atomic_path, write_text
from radtree.report.impact import DAY, Pair, impact_frame, is_inventory, sensor_change
from radtree.report.tables import Table, lux, num

PLAN_FILE = "figures/tree_impact_plan.png"
ROOMS_COLUMNS = ["room", "quantity", "time", "unit", "with", "without", "change", "change_pct",
                 "trees", "baseline"]
LEVEL_TITLES = {"façade": "façade", "storey": "storey", "building": "building", "room": "room"}
#: results/annual.csv columns → (label, unit); means over the grid's sensors
ANNUAL_SENSOR = {"udi_below_100": ("UDI < 100 lx", "% of occupied hours"),
                 "udi_100_300": ("UDI 100–300 lx", "% of occupied hours"),
                 "udi_300_3000": ("UDI 300–3000 lx", "% of occupied hours"),
                 "udi_above_3000": ("UDI > 3000 lx", "% of occupied hours"),
                 "da_300": ("DA300", "% of occupied hours"),
                 "ase_hours": ("direct-sun hours > 1000 lx", "h")}
ANNUAL_GRID = {"sda_300_50": ("sDA300/50%", "% of area"),
               "ase_1000_250": ("ASE1000,250", "% of area")}


def pct(value: Any) -> str:
    """A signed per-cent change, one decimal (``—`` if missing)."""
    t = num(value, 1)
    return t if t == "—" or t.startswith("-") or float(t) == 0 else "+" + t


def _signed(value: Any) -> str:
    t = lux(value)
    return t if t == "—" or t.startswith("-") or t == "0" else "+" + t


def _multi(impact: pd.DataFrame) -> bool:
    return impact["trees"].nunique() > 1


def daily_table(impact: pd.DataFrame, level: str, key: str, caption: str) -> Table | None:
    """Per target of ``level`` (largest relative loss first): the day means with and without,
    change in lx and %, and the hour of the largest relative change."""
    d = impact[impact["level"] == level]
    if d.empty:
        return None
    multi = _multi(impact)
    head = ([LEVEL_TITLES[level]] + (["trees"] if multi else []) +
            ["sensors", "with trees (lx)", "without (lx)", "change (lx)", "change (%)",
             "largest change (hour)"])
    t = Table(key, caption, head, [False] + ([False] if multi else []) + [True] * 6)
    order = d[d["time"] == DAY].sort_values(["trees", "change_pct"], kind="stable")
    for trees, target in zip(order["trees"], order["target"]):   # most light taken first
        g = d[(d["trees"] == trees) & (d["target"] == target)]
        day = g[g["time"] == DAY].iloc[0]
        hours = g[(g["time"] != DAY) & g["change_pct"].notna()]
        worst = hours.loc[hours["change_pct"].abs().idxmax()] if len(hours) else None
        change = _signed(day["change_lux"])
        if np.isfinite(day["change_stderr"]):
            change += f" ± {num(day['change_stderr'], 0 if day['change_stderr'] >= 1 else 1)}"
        t.add(target, *([trees] if multi else []), num(day["n_sensors"]), lux(day["with_lux"]),
              lux(day["without_lux"]), change, pct(day["change_pct"]),
              f"{pct(worst['change_pct'])} at {worst['time']}" if worst is not None else "—")
    return t


def hourly_table(impact: pd.DataFrame, level: str, key: str) -> Table | None:
    """Per target of ``level`` and hour: with, without (lx) and the change in lx and %."""
    d = impact[(impact["level"] == level) & (impact["time"] != DAY)]
    if d.empty:
        return None
    multi = _multi(impact)
    t = Table(key, f"Per {LEVEL_TITLES[level]} and hour: mean illuminance with and without "
              "trees (lx), change (lx, with − without) and change (%).",
              [LEVEL_TITLES[level]] + (["trees"] if multi else []) +
              ["hour", "with trees (lx)", "without (lx)", "change (lx)", "change (%)"],
              [False] + ([False] if multi else []) + [False, True, True, True, True])
    for _, r in d.iterrows():
        t.add(r["target"], *([r["trees"]] if multi else []), r["time"], lux(r["with_lux"]),
              lux(r["without_lux"]), _signed(r["change_lux"]), pct(r["change_pct"]))
    return t


# --------------------------------------------------------------------------- annual


def annual_rows(project: Project) -> pd.DataFrame | None:
    """Per grid and annual metric: with, without (the annual run's ``tree`` column), unit,
    from ``results/annual.csv`` (sensor means) and ``annual_summary.csv`` (grid metrics)."""
    res = project.results_dir
    if not (res / "annual.csv").is_file():
        return None
    rows = []
    per = pd.read_csv(res / "annual.csv", dtype={"grid": str})
    means = per.groupby(["grid", "tree"])[[c for c in ANNUAL_SENSOR if c in per.columns]].mean()
    summary = (pd.read_csv(res / "annual_summary.csv", dtype={"grid": str})
               .groupby(["grid", "tree"]).first() if (res / "annual_summary.csv").is_file()
               else None)
    for grid in dict.fromkeys(per["grid"]):
        for col, (label, unit) in ANNUAL_GRID.items():
            if summary is not None and col in summary.columns:
                rows.append(_with_without(grid, label, unit, summary[col], grid))
        for col, (label, unit) in ANNUAL_SENSOR.items():
            if col in means.columns:
                rows.append(_with_without(grid, label, unit, means[col], grid))
    return pd.DataFrame(rows) if rows else None


def _with_without(grid: str, label: str, unit: str, series: pd.Series, key: str) -> dict:
    w = series.get((key, "with"), math.nan)
    o = series.get((key, "without"), math.nan)
    return {"room": grid, "metric": label, "unit": unit, "with": float(w), "without": float(o),
            "difference": float(w) - float(o)}


def standards_rows(project: Project, pair: Pair | None) -> pd.DataFrame | None:
    """``results/annual/standards.csv`` (scenario, target, metric, value, unit, definition) as
    with / without / difference per target and metric."""
    path = project.results_dir / "annual" / "standards.csv"
    if not path.is_file():
        return None
    st = pd.read_csv(path, dtype={"scenario": str, "target": str})
    with_names = {"with", "trees"} | ({pair.trees} if pair else set())
    without_names = {"without", "open"} | ({pair.baseline} if pair else set())
    rows = []
    for (target, metric), g in st.groupby(["target", "metric"], sort=False):
        w = g[g["scenario"].isin(with_names)]["value"]
        o = g[g["scenario"].isin(without_names)]["value"]
        wv = float(w.iloc[0]) if len(w) else math.nan
        ov = float(o.iloc[0]) if len(o) else math.nan
        rows.append({"room": target, "metric": metric, "unit": str(g["unit"].iloc[0]),
                     "with": wv, "without": ov, "difference": wv - ov,
                     "definition": str(g["definition"].iloc[0])})
    return pd.DataFrame(rows) if rows else None


def metric_table(frame: pd.DataFrame, key: str, caption: str, definition: bool = False) -> Table:
    head = ["room", "metric", "with trees", "without", "difference", "unit"]
    t = Table(key, caption, head + (["definition"] if definition else []),
              [False, False, True, True, True, False] + ([False] if definition else []))
    for _, r in frame.iterrows():
        t.add(r["room"], r["metric"], num(r["with"], 1), num(r["without"], 1),
              pct(r["difference"]), r["unit"], *([r["definition"]] if definition else []))
    return t


# --------------------------------------------------------------------------- trees


def tree_ranking(project: Project, pair: Pair | None) -> pd.DataFrame | None:
    """``results/tree_impact.csv`` per tree: light removed summed over targets and hours (lx),
    its standard error, the most affected target and the tree's share of the change there."""
    path = project.results_dir / "tree_impact.csv"
    if not path.is_file():
        return None
    ti = pd.read_csv(path, dtype={"scenario": str, "tree": str, "target": str, "time": str})
    if pair is not None and pair.trees in set(ti["scenario"]):
        ti = ti[ti["scenario"] == pair.trees]
    if ti.empty:
        return None
    rows = []
    for tree, g in ti.groupby("tree", sort=False):
        per_target = g.groupby("target")["lux_removed"].sum()
        top = str(per_target.idxmax())
        rows.append({"tree": tree, "lux_removed": float(g["lux_removed"].sum()),
                     "stderr": float(np.sqrt(np.nansum(g["lux_removed_stderr"] ** 2))),
                     "targets": int((per_target > 0).sum()), "top_target": top,
                     "share": float(g[g["target"] == top]["share"].mean())})
    out = pd.DataFrame(rows).sort_values("lux_removed", ascending=False, kind="stable")
    return out.assign(rank=np.arange(1, len(out) + 1)).reset_index(drop=True)


def tree_table(ranking: pd.DataFrame, n_hours: int, shown: int = 20) -> Table:
    t = Table("tree_ranking", "The trees ranked by the light they remove (results/"
              "tree_impact.csv): mean illuminance removed from each target summed over the "
              f"targets and the {n_hours} simulated hour(s) (lx, ± Monte Carlo standard error), "
              "the targets it darkens, and its share of the total change on the target it "
              f"affects most. {'Top ' + str(shown) + ' shown; ' if len(ranking) > shown else ''}"
              "every tree in tree_impact.csv.",
              ["rank", "tree", "light removed (lx)", "targets darkened", "most affected target",
               "share there (%)"], [True, False, True, True, False, True])
    for _, r in ranking.head(shown).iterrows():
        t.add(int(r["rank"]), r["tree"], f"{lux(r['lux_removed'])} ± {num(r['stderr'], 0)}",
              int(r["targets"]), r["top_target"], num(100 * r["share"], 0))
    return t


# --------------------------------------------------------------------------- plan


def site_plan(project: Project, results: pd.DataFrame, impact: pd.DataFrame, pair: Pair,
              ranking: pd.DataFrame | None, path: Path) -> str:
    """The site plan (x east, y north, m) coloured by the day's % change with trees: in an
    inventory project each façade (footprints grey, crowns green, the five trees that remove
    most light numbered); otherwise each sensor at its position."""
    from matplotlib import colormaps
    from matplotlib.cm import ScalarMappable
    from matplotlib.collections import LineCollection
    from matplotlib.colors import Normalize
    from matplotlib.patches import Circle, Polygon

    from radtree.figures import new_figure, save_png
    from radtree.trees.district import tree_outline

    cmap = colormaps["RdBu"]
    fig = new_figure(7.2, 5.6, 110)
    ax = fig.add_subplot()
    day = impact[(impact["time"] == DAY) & (impact["trees"] == pair.trees)]
    if project.district is not None and is_inventory(results):
        from radtree.site.district import load_district

        inputs = load_district(project)
        change = day[day["level"] == "façade"].set_index("target")["change_pct"]
        lim = max(1.0, float(np.nanmax(np.abs(change)))) if len(change) else 1.0
        norm = Normalize(-lim, lim)
        for b in inputs.buildings:
            ax.add_patch(Polygon(np.asarray(b.polygon.exterior.coords), closed=True,  # type: ignore[attr-defined]
                                 facecolor="0.88", edgecolor="0.5", linewidth=0.5))
        segs, cols = [], []
        for f in inputs.facades:
            if f.id in change.index and np.isfinite(change[f.id]):
                segs.append([f.start + 0.8 * f.normal, f.end + 0.8 * f.normal])
                cols.append(cmap(norm(change[f.id])))
        ax.add_collection(LineCollection(segs, colors=cols, linewidths=4.5))
        ranks = ({str(t): int(r) for t, r in zip(ranking["tree"], ranking["rank"])}
                 if ranking is not None else {})
        for t in inputs.trees:   # a crown following its outline drawn as the outline
            look = {"facecolor": (0.2, 0.6, 0.2, 0.3), "edgecolor": (0.1, 0.4, 0.1, 0.8),
                    "linewidth": 0.5}
            ax.add_patch(Polygon(np.asarray(t.outline), closed=True, **look)
                         if tree_outline(t)[0] is not None
                         else Circle((t.x, t.y), t.crown_radius_m, **look))
            if ranks.get(str(t.id), 99) <= 5:
                ax.annotate(f"#{ranks[str(t.id)]}", (t.x, t.y), ha="center", va="center",
                            fontsize=8, weight="bold")
        what = ("each simulated façade (thick line just outside it) coloured by the change "
                "of its mean illuminance over the day; building footprints grey, tree crowns "
                "green to scale (their outlines where they follow one)"
                + ("; #1–#5: the trees that remove most light (Table 'trees ranked')"
                   if ranks else ""))
    else:
        per = sensor_change(results[~results["grid"].astype(str).isin(["facade_map"])], pair)
        lim = max(1.0, float(np.nanmax(np.abs(per["change_pct"])))) if len(per) else 1.0
        norm = Normalize(-lim, lim)
        ax.scatter(per["x"], per["y"], c=per["change_pct"], cmap=cmap, norm=norm, s=14,
                   edgecolors="0.3", linewidths=0.2)
        what = ("each sensor (seen from above; sensors above one another overlap) coloured by "
                "the change of its mean illuminance over the day")
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.set_xlabel("x east (m)")
    ax.set_ylabel("y north (m)")
    ax.set_title(f"{pair.trees} against {pair.baseline}: change over the day", fontsize=10)
    fig.colorbar(ScalarMappable(norm=norm, cmap=cmap), ax=ax,
                 label="change with trees (%; red = darker)")
    save_png(fig, path, 110)
    return (f"Site plan (x east, y north, m): {what}; red = less light with the trees "
            f"({pair.trees}) than without ({pair.baseline}), blue = more.")


# --------------------------------------------------------------------------- outputs


def rooms_frame(impact: pd.DataFrame, annual: pd.DataFrame | None,
                standards: pd.DataFrame | None, pair: Pair) -> pd.DataFrame:
    """``results/rooms.csv``: the columns :data:`ROOMS_COLUMNS`."""
    d = impact[(impact["level"] == "room") & (impact["trees"] == pair.trees)]
    rows = [{"room": r["target"], "quantity": "illuminance", "time": r["time"], "unit": "lx",
             "with": round(r["with_lux"], 1), "without": round(r["without_lux"], 1),
             "change": round(r["change_lux"], 1), "change_pct": round(r["change_pct"], 2)}
            for _, r in d.iterrows()]
    rooms = set(d["target"])
    for extra in (annual, standards):
        if extra is None:
            continue
        for _, r in extra[extra["room"].isin(rooms)].iterrows():
            rows.append({"room": r["room"], "quantity": r["metric"], "time": "annual",
                         "unit": r["unit"], "with": r["with"], "without": r["without"],
                         "change": r["difference"], "change_pct": (
                             100 * r["difference"] / r["without"] if r["without"] else math.nan)})
    return pd.DataFrame(rows, columns=ROOMS_COLUMNS[:-2]).assign(
        trees=pair.trees, baseline=pair.baseline)


def extend_facades_geojson(project: Project, impact: pd.DataFrame, pair: Pair) -> bool:
    """Add the change with trees per façade to ``results/facades.geojson`` (if it exists)."""
    path = project.results_dir / "facades.geojson"
    if not path.is_file():
        return False
    fc = json.loads(path.read_text(encoding="utf-8"))
    d = impact[(impact["level"] == "façade") & (impact["trees"] == pair.trees)]
    by = {t: g.set_index("time") for t, g in d.groupby("target")}
    for f in fc.get("features") or []:
        p = f["properties"]
        g = by.get(str(p.get("facade")))
        if g is None:
            continue
        p.update({"trees": pair.trees, "baseline": pair.baseline})
        for time, r in g.iterrows():
            tag = "" if time == DAY else f"_{time}"
            if time == DAY:
                p["lux_without"] = round(float(r["without_lux"]), 1)
            p[f"change_lux{tag}"] = round(float(r["change_lux"]), 1)
            p[f"change_pct{tag}"] = (round(float(r["change_pct"]), 2)
                                     if np.isfinite(r["change_pct"]) else None)
    write_text(path, json.dumps(fc, indent=1))
    return True


def _level_tables(impact: pd.DataFrame, pairs: list[Pair], over: str) -> dict[str, Table]:
    """The daily tables per façade, storey, building and room (those with data)."""
    tables: dict[str, Table] = {}
    for level, key in (("façade", "impact_facades"), ("storey", "impact_storeys"),
                       ("building", "impact_buildings"), ("room", "impact_rooms")):
        tb = daily_table(impact, level, key, (
            f"What the trees do per {LEVEL_TITLES[level]}: mean illuminance of its sensors with "
            f"trees ({', '.join(p.trees for p in pairs)}) and without ({pairs[0].baseline}), "
            f"{over}; change = with − without (lx, ± Monte Carlo standard error; negative = "
            "the trees take light) and in % of the value without; the hour of the largest "
            "relative change."))
        if tb is not None:
            tables[key] = tb
    return tables


def _metric_tables(annual: pd.DataFrame | None, standards: pd.DataFrame | None
                   ) -> dict[str, Table]:
    """The annual metrics and the standards with and without trees (those that exist)."""
    tables: dict[str, Table] = {}
    if annual is not None:
        tables["impact_annual"] = metric_table(
            annual, "impact_annual", "Annual metrics per grid with and without trees (results/"
            "annual.csv, annual_summary.csv): UDI bands and DA300 in % of occupied hours (mean "
            "over the grid's sensors), sDA300/50% and ASE1000,250 in % of the grid's area "
            "(IES LM-83); difference = with − without.")
    if standards is not None:
        tables["impact_standards"] = metric_table(
            standards, "impact_standards", "Standards with and without trees (results/annual/"
            "standards.csv): each metric as its definition states; difference = with − "
            "without.", definition=True)
    return tables


def _headline_lines(impact: pd.DataFrame, pair: Pair) -> list[str]:
    """The first page's lines: the day's largest relative change per façade and per room."""
    day = impact[(impact["time"] == DAY) & (impact["trees"] == pair.trees)]
    lines = []
    for level in ("façade", "room"):
        d = day[(day["level"] == level) & day["change_pct"].notna()]
        if len(d):
            worst = d.loc[d["change_pct"].idxmin()]
            head = f"What the trees do ({pair.trees} against {pair.baseline}): "
            vals = (f"{lux(worst['with_lux'])} lx with trees, {lux(worst['without_lux'])} lx "
                    "without")
            if len(d) == 1:
                lines.append(head + f"the mean illuminance over the day on the "
                             f"{LEVEL_TITLES[level]} {worst['target']} changes by "
                             f"{pct(worst['change_pct'])} % ({vals}).")
            else:
                lines.append(head + f"the mean illuminance over the day changes by "
                             f"{pct(d['change_pct'].min())} % to {pct(d['change_pct'].max())} % "
                             f"across {len(d)} {LEVEL_TITLES[level]}s; most on "
                             f"{worst['target']} ({vals}).")
    return lines


def impact_data(project: Project, results: pd.DataFrame, pairs: list[Pair], out: Path
                ) -> dict[str, Any] | None:
    """The section's data (None without a with/without-trees pair); writes the plan PNG into
    the report folder ``out``, ``impact.csv`` beside it, and ``results/rooms.csv`` /
    ``results/facades.geojson`` as the module doc says."""
    impact = impact_frame(results, pairs)
    if impact.empty:
        return None
    pair = pairs[0]
    impact.to_csv(out / "impact.csv", index=False)
    n_hours = impact[impact["time"] != DAY]["time"].nunique()
    tables = _level_tables(impact, pairs, f"mean over the {n_hours} simulated hour(s)")
    hourly = {lv: hourly_table(impact, lv, f"impact_hourly_{i}")
              for i, lv in enumerate(("façade", "storey", "building", "room"))}
    annual = annual_rows(project)
    standards = standards_rows(project, pair)
    ranking = tree_ranking(project, pair)
    tables.update(_metric_tables(annual, standards))
    if ranking is not None:
        tables["tree_ranking"] = tree_table(ranking, n_hours)
    (out / Path(PLAN_FILE).parent).mkdir(parents=True, exist_ok=True)
    caption = site_plan(project, results, impact, pair, ranking, out / PLAN_FILE)
    written = []
    if (impact["level"] == "room").any():
        with atomic_path(project.results_dir / "rooms.csv") as tmp:
            rooms_frame(impact, annual, standards, pair).to_csv(tmp, index=False)
        written.append("results/rooms.csv")
    if extend_facades_geojson(project, impact, pair):
        written.append("results/facades.geojson")
    return {"pairs": [{"trees": p.trees, "baseline": p.baseline} for p in pairs],
            "baseline": pair.baseline, "lines": _headline_lines(impact, pair), "tables": tables,
            "hourly": [t for t in hourly.values() if t is not None],
            "plan": {"file": PLAN_FILE, "caption": caption}, "written": written,
            "tree_impact": ranking is not None}
