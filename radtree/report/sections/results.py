"""The result sections' tables: scenarios, hourly, statistics, sensor rows, timing, ground
reflection and -ab convergence, as :class:`~radtree.report.tables.Table` (formatted cells).

Illuminance in lux, times in seconds, nRMSE/nMBE as fractions of the mean measured value.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from typing import Any

import pandas as pd

from radtree.report.data import FORM_LABELS, ReportData, ScenarioInfo
from radtree.report.tables import Table, lux, lux_pm, num, seconds, text

BOOTSTRAP = {"n_boot": 2000, "level": 0.95, "seed": 0}  # stats.compare defaults


def _grouped(infos: list[ScenarioInfo], names: Iterable[str]) -> list[tuple[str | None, str]]:
    """Scenario names in report order with a form heading before each group of forms.

    Returns (group label or None, scenario name) pairs; a pair with a label starts a group.
    """
    wanted = set(names)
    out: list[tuple[str | None, str]] = []
    last = None
    for info in infos:
        if info.name not in wanted:
            continue
        if info.form != last:
            out.append((FORM_LABELS.get(info.form, info.form), info.name))
            last = info.form
        else:
            out.append((None, info.name))
    return out


def _add_grouped(table: Table, data: ReportData, names: Iterable[str],
                 row: Callable[[ScenarioInfo], list[list[Any]]]) -> None:
    pairs = _grouped(data.scenarios, names)
    multiple = len({data.scenario(n).form for _, n in pairs}) > 1
    for group, name in pairs:
        if group is not None and multiple:
            table.add_group(f"crown form: {group}")
        for cells in row(data.scenario(name)):
            table.add(*cells)


# --------------------------------------------------------------------------- tables


def scenario_table(data: ReportData) -> Table:
    t = Table("scenarios", "Scenarios in the results, grouped by crown form.",
              ["scenario", "crown model", "crown form", "ground-reflected light", "sky",
               "engine", "-ab", "triangles", "description"],
              [False, False, False, False, False, False, True, True, False])
    _add_grouped(t, data, data.names, lambda s: [[
        s.name + (" (stand-in)" if s.stand_in else ""), s.model_label,
        s.form_label + ("" if s.form_source != "project file"
                                               else " (from the project file)"),
        s.reflection or "—", s.sky, text(s.engine), num(s.build.get("ab")),
        num(s.build.get("triangles")), text(s.description)]])
    return t


def hourly_table(data: ReportData) -> Table:
    names = data.names
    t = Table("hourly", "Hourly mean vertical illuminance of the façade sensors (lx): measured "
              "and simulated per scenario (± Monte Carlo standard error of the mean where the "
              "engine gives one).",
              ["time", "measured (lx)", *[f"{n} (lx)" for n in names]],
              [False, True, *[True] * len(names)])
    sim = data.hourly_sim.set_index(["scenario", "time"])
    for _, r in data.hourly.iterrows():
        cells = [r["time"], lux(r["measured_lux"])]
        for n in names:
            if (n, r["time"]) in sim.index:
                v = sim.loc[(n, r["time"])]
                cells.append(lux_pm(v["lux"], v["lux_stderr"]))
            else:
                cells.append(lux(math.nan))
        t.add(*cells)
    basis = data.hourly.dropna(subset=["measured_lux"]) if data.measured is not None \
        else data.hourly
    if len(basis) > 1:
        label = "mean (measured hours)" if data.measured is not None else "mean"
        t.add(label, lux(basis["measured_lux"].mean()),
              *[lux(basis[n].mean()) if n in basis.columns else lux(math.nan) for n in names])
    return t


def statistics_table(data: ReportData) -> Table:
    level = int(BOOTSTRAP["level"] * 100)
    t = Table("statistics",
              "Statistics per scenario against the measured hourly means (reference case §3): "
              "normalised RMSE and MBE (fractions of the mean measured value; MBE > 0 = the "
              f"model under-predicts), {level} % bootstrap interval on nRMSE (resampling hours), "
              "Pearson r, R² = 1 − SS_res/SS_tot, RMSE and MBE in lux, and the Monte Carlo "
              "standard error of nRMSE.",
              ["scenario", "crown model", "ground-reflected light", "nRMSE", f"{level} % low",
               f"{level} % high", "nMBE", "r", "R²", "n hours", "RMSE (lx)", "MBE (lx)",
               "MC SE of nRMSE"],
              [False, False, False, True, True, True, True, True, True, True, True, True, True])
    if data.stats is None:
        return t
    stats = data.stats.set_index("scenario")
    _add_grouped(t, data, list(stats.index), lambda s: [[
        s.name, s.model_label, s.reflection or "—", num(stats.loc[s.name, "rmse"], 3),
        num(stats.loc[s.name, "rmse_low"], 3), num(stats.loc[s.name, "rmse_high"], 3),
        num(stats.loc[s.name, "mbe"], 3), num(stats.loc[s.name, "r"], 3),
        num(stats.loc[s.name, "r2"], 3), num(stats.loc[s.name, "n_hours"]),
        lux(stats.loc[s.name, "rmse_lux"]), lux(stats.loc[s.name, "mbe_lux"]),
        num(stats.loc[s.name, "rmse_mc_se"], 4)]])
    return t


def rows_table(data: ReportData) -> Table | None:
    if data.rows is None:
        return None
    caption = ("Per sensor row: simulated daily mean illuminance (lx, mean over the hours and "
               "the row's sensors, ± Monte Carlo standard error)")
    if data.rows_measured:
        caption += (" against the measured daily mean of the row (only daily means were "
                    "measured per row); ratio = simulated / measured, difference = simulated − "
                    "measured (lx).")
    else:
        caption += "; no per-row measurements in this project."
    t = Table("rows", caption,
              ["scenario", "row", "simulated (lx)", "measured (lx)", "simulated / measured",
               "difference (lx)"],
              [False, False, True, True, True, True])
    rows = data.rows

    def cells(s: ScenarioInfo) -> list[list[Any]]:
        out = []
        for _, r in rows[rows["scenario"] == s.name].iterrows():
            out.append([s.name, r["row"], lux_pm(r["simulated_mean_lux"], r["simulated_stderr"]),
                        lux(r["measured_mean_lux"]), num(r["ratio"], 2),
                        lux(r["difference_lux"])])
        return out

    _add_grouped(t, data, data.names, cells)
    return t


def rows_between_table(data: ReportData) -> Table | None:
    b = data.rows_between
    if b is None or b.empty:
        return None
    ref = str(b["reference"].iloc[0])
    t = Table("rows_between",
              f"Per sensor row, hourly statistics of each scenario against scenario {ref} (a "
              "comparison between models, not with measurement: only daily means were measured "
              f"per row). nRMSE and nMBE are normalised by {ref}'s mean; nMBE > 0 = below {ref}.",
              ["scenario", "row", "nRMSE", "nMBE", "r", "R²", "n hours"],
              [False, False, True, True, True, True, True])
    for _, r in b.iterrows():
        t.add(r["scenario"], r["row"], num(r["nrmse"], 3), num(r["nmbe"], 3), num(r["r"], 3),
              num(r["r2"], 3), num(r["n_hours"]))
    return t


def timing_table(data: ReportData) -> Table | None:
    if data.timing is None:
        return None
    t = Table("timing", "Wall-clock time per scenario (s): (1) scene/property preparation, "
              "(2) geometry preparation, (3) ray tracing (summed over hours).",
              ["scenario", "engine", "preparation (s)", "geometry (s)", "tracing (s)",
               "total (s)"],
              [False, False, True, True, True, True])
    tm = data.timing.drop_duplicates("scenario", keep="last").set_index("scenario")

    def cells(s: ScenarioInfo) -> list[list[Any]]:
        if s.name not in tm.index:
            return [[s.name, text(s.engine), "—", "—", "—", "—"]]
        r = tm.loc[s.name]
        parts = [float(r[p]) for p in ("preparation_s", "geometry_s", "tracing_s")]
        return [[s.name, text(r.get("engine", s.engine)), *[seconds(p) for p in parts],
                 seconds(sum(p for p in parts if math.isfinite(p)))]]

    _add_grouped(t, data, data.names, cells)
    return t


def reflection_table(data: ReportData) -> Table:
    t = Table("reflection", "Ground-reflected light per scenario (reference case §2): traced through "
              "the scene, or calculated as E_refl = ρ(α)·E_ground·F with a black ground in the "
              "traced part.",
              ["scenario", "mode", "handling"], [False, False, False])
    _add_grouped(t, data, data.names, lambda s: [[s.name, s.reflection or "—",
                                                   s.reflection_note or "—"]])
    return t


def convergence_tables(data: ReportData) -> tuple[Table | None, Table | None]:
    c = data.convergence
    if c is None:
        return None, None
    has_time = "time" in c.columns
    full = Table("convergence", "Ambient-bounce convergence run: façade sensor mean (lx) per "
                 "-ab and its relative change from the previous step (%).",
                 ["scenario", "time", "-ab", "-ad", "façade mean (lx)", "change (%)",
                  "recommended -ab"],
                 [False, False, True, True, True, True, True])
    for _, r in c.iterrows():
        change = r.get("change", math.nan)
        full.add(r["scenario"], r["time"] if has_time else "—", num(r["ab"]),
                 num(r.get("ad", math.nan)), lux(r["facade_mean_lux"]),
                 num(float(change) * 100 if not pd.isna(change) else math.nan, 1),
                 num(r.get("model_recommended_ab", math.nan)))
    summary = Table("convergence_summary", "Is the -ab used converged? Façade mean at the -ab "
                    "the simulation used (build manifest, else the model's recommendation) "
                    "against the highest -ab of the run; difference relative to the latter (%).",
                    ["scenario", "time", "-ab used", "mean at -ab used (lx)", "highest -ab",
                     "mean at highest -ab (lx)", "difference (%)"],
                    [False, False, True, True, True, True, True])
    keys = ["scenario"] + (["time"] if has_time else [])
    known = set(data.names)
    for key, g in c.groupby(keys, sort=True):
        key = key if isinstance(key, tuple) else (key,)
        name = str(key[0])
        used: Any = math.nan
        if name in known and data.scenario(name).build.get("ab") is not None:
            used = data.scenario(name).build["ab"]
        elif "model_recommended_ab" in g.columns:
            used = g["model_recommended_ab"].iloc[0]
        g = g.sort_values("ab")
        top = g.iloc[-1]
        at = g[g["ab"] == used] if not pd.isna(used) else g.iloc[0:0]
        mean_used = float(at["facade_mean_lux"].iloc[0]) if len(at) else math.nan
        diff = ((mean_used - float(top["facade_mean_lux"])) / float(top["facade_mean_lux"]) * 100
                if float(top["facade_mean_lux"]) != 0 else math.nan)
        summary.add(name, key[1] if has_time else "—", num(used), lux(mean_used),
                    num(top["ab"]), lux(top["facade_mean_lux"]), num(diff, 1))
    return full, summary
