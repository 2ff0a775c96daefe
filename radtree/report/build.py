"""``build_report``: statistics, tables, figures and the HTML/Markdown report of a project.

Writes, atomically (the whole folder is assembled beside it and renamed into place):

    PROJECT/report/index.html       the report (self-contained: inline CSS, relative images)
    PROJECT/report/index.md         the same in Markdown
    PROJECT/report/statistics.csv   scenario, model, reflection, rmse, rmse_low, rmse_high, mbe,
                                    r, r2, n_hours (+ rmse_lux, mbe_lux, rmse_mc_se, form)
    PROJECT/report/hourly.csv       time, measured_lux, one column of simulated lux per scenario
    PROJECT/report/rows.csv         per-row daily means (simulated vs measured)
    PROJECT/report/figures/*.png    150 dpi figures
    PROJECT/report/models/*.png     the crown-model pictures copied from build/<scenario>/
"""

from __future__ import annotations

import importlib.metadata
import json
import math
import platform
import shutil
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

import pandas as pd
from jinja2 import Environment, PackageLoader, StrictUndefined

import radtree
from radtree.config import Project
from radtree.fileio import atomic_dir
from radtree.report import figures
from radtree.report.data import FORM_LABELS, ReportData, ScenarioInfo, collect
from radtree.report.tables import Table, lux, lux_pm, num, seconds, text
from radtree.stats import STATS_COLUMNS

#: The columns of statistics.csv every reader may rely on (SPEC.md §3, normalised).
STATISTICS_CONTRACT = ["scenario", "model", "reflection", "rmse", "rmse_low", "rmse_high", "mbe",
                       "r", "r2", "n_hours"]
STATISTICS_EXTRA = ["rmse_lux", "mbe_lux", "rmse_mc_se", "form"]
BOOTSTRAP = {"n_boot": 2000, "level": 0.95, "seed": 0}  # stats.compare defaults


@dataclass
class FigureRef:
    """A figure in the report: file relative to the report folder, caption, alt text."""

    file: str
    caption: str
    alt: str
    number: int = 0


@dataclass
class ModelPicture:
    scenario: str
    title: str
    file: str | None
    missing: str
    notes: list[str]
    info: Table | None


@dataclass
class Context:
    """Everything the templates render."""

    title: str
    subtitle: str
    created: str
    headline: list[str]
    notes: list[str]
    has_measured: bool
    tables: dict[str, Table] = field(default_factory=dict)
    figs: dict[str, FigureRef] = field(default_factory=dict)
    figure_problems: list[str] = field(default_factory=list)
    models: list[ModelPicture] = field(default_factory=list)
    map_reason: str = ""
    method: dict[str, str] = field(default_factory=dict)
    parameters: Table | None = None


# --------------------------------------------------------------------------- grouping helper


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
        s.name, s.model_label, s.form_label + ("" if s.form_source != "project file"
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
              "Statistics per scenario against the measured hourly means (SPEC.md §3): "
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
    t = Table("reflection", "Ground-reflected light per scenario (SPEC.md §2): traced through "
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


def _flatten(d: Any, prefix: str = "") -> list[tuple[str, str]]:
    if isinstance(d, dict):
        out = []
        for k, v in d.items():
            out += _flatten(v, f"{prefix}.{k}" if prefix else str(k))
        return out
    if isinstance(d, list) and d and any(isinstance(v, dict | list) for v in d):
        out = []
        for i, v in enumerate(d):
            out += _flatten(v, f"{prefix}[{i}]")
        return out
    return [(prefix, json.dumps(d, ensure_ascii=False, default=str)
             if not isinstance(d, str) else d)]


def _version(dist: str) -> str:
    try:
        return importlib.metadata.version(dist)
    except importlib.metadata.PackageNotFoundError:
        return "—"


def provenance_tables(data: ReportData, created: str) -> dict[str, Table]:
    mf = data.results_manifest or {}
    facts = Table("provenance", "Provenance of the results (results/manifest.json) and of this "
                  "report.", ["item", "value"], [False, False])
    facts.add("project file", str(data.project.source))
    for key, label in (("created", "results written"), ("engine", "engine"),
                       ("radtree_version", "radtree (simulation)"),
                       ("radiance_version", "Radiance"), ("radiance_origin", "Radiance from"),
                       ("python", "Python (simulation)")):
        facts.add(label, text(mf.get(key)))
    seeds = mf.get("seeds")
    if isinstance(seeds, dict):
        for k, v in seeds.items():
            facts.add(f"seed: {k}", text(v))
    facts.add("bootstrap", f"{BOOTSTRAP['n_boot']} resamples of the hours, "
              f"{int(BOOTSTRAP['level'] * 100)} % percentile interval, seed {BOOTSTRAP['seed']}")
    facts.add("report written", created)
    facts.add("radtree (report)", radtree.__version__)
    facts.add("Python (report)", platform.python_version())
    for dist in ("numpy", "pandas", "matplotlib", "jinja2", "pyradiance"):
        facts.add(dist, _version(dist))
    if not mf:
        facts.add("results manifest", "missing (results/manifest.json not found)")

    inputs = Table("inputs", "Input files and their SHA-256 (from results/manifest.json).",
                   ["input", "file", "sha256"], [False, False, False])
    raw_inputs = mf.get("inputs") if isinstance(mf.get("inputs"), dict) else {}
    for k, v in (raw_inputs or {}).items():
        fname, _, digest = str(v).partition(" sha256:")
        inputs.add(k, fname, digest or "—")

    hashes = Table("hashes", "Parameter hash per scenario: in the results table, in the build "
                   "folder's manifest, and from the project file now (they agree when the "
                   "results are current).",
                   ["scenario", "results", "build manifest", "project file now", "status"],
                   [False, False, False, False, False])
    for s in data.scenarios:
        built = text(s.build.get("params_hash")) if s.build_manifest_found else "no manifest"
        now = s.current_hash or "not in project"
        status = ("current" if s.current_hash and s.params_hash == s.current_hash
                  else "stale" if s.current_hash else "—")
        hashes.add(s.name, text(s.params_hash), built, now, status)
    return {"provenance": facts, "inputs": inputs, "hashes": hashes}


def parameters_table(data: ReportData) -> Table:
    mf = data.results_manifest or {}
    params = mf.get("parameters") if isinstance(mf.get("parameters"), dict) else None
    source = "results/manifest.json"
    if params is None:
        params, source = data.project.to_dict(), "the project file (no results manifest)"
    t = Table("parameters", f"Every parameter, from {source}.", ["parameter", "value"],
              [False, False])
    for k, v in _flatten(params):
        t.add(k, v)
    return t


def model_pictures(data: ReportData) -> list[ModelPicture]:
    out = []
    for s in data.scenarios:
        info = s.build.get("info") if isinstance(s.build.get("info"), dict) else {}
        table = None
        if info:
            numeric = all(isinstance(v, int | float) and not isinstance(v, bool)
                          for v in info.values())
            table = Table(f"info_{s.name}", f"Crown model facts of scenario {s.name}.",
                          ["quantity", "value"], [False, numeric])
            for k, v in info.items():
                table.add(k, f"{v:.6g}" if numeric else text(v))
        notes = [str(n) for n in s.build.get("notes", [])] if s.build_manifest_found else []
        if s.picture is not None:
            missing = ""
        elif s.picture_problem:
            missing = f"no picture ({s.picture_problem})"
        elif s.model == "none":
            missing = "no picture (no crown: open street)"
        else:
            missing = f"no picture (build/{s.name}/model.png not found)"
        if not s.build_manifest_found:
            notes = [f"no build manifest (build/{s.name}/manifest.json): run `radtree build` "
                     "to record how the crown was read"]
        out.append(ModelPicture(
            scenario=s.name, title=f"{s.name}: {s.model_label}, {s.form_label}",
            file=f"models/{s.name}.png" if s.picture is not None else None,
            missing=missing, notes=notes, info=table))
    return out


# --------------------------------------------------------------------------- CSV outputs


def statistics_frame(data: ReportData) -> pd.DataFrame:
    """statistics.csv: the contract columns, then rmse_lux, mbe_lux, rmse_mc_se, form."""
    cols = STATISTICS_CONTRACT + STATISTICS_EXTRA
    if data.stats is None:
        return pd.DataFrame(columns=cols)
    df = data.stats.copy()
    df["form"] = [data.scenario(n).form for n in df["scenario"]]
    missing = [c for c in STATS_COLUMNS if c not in df.columns]
    if missing:  # pragma: no cover - guards against a change in stats.compare
        raise RuntimeError(f"stats.compare no longer gives {missing}")
    return df[cols]


def hourly_frame(data: ReportData) -> pd.DataFrame:
    return data.hourly[["time", "measured_lux", *data.names]]


def rows_frame(data: ReportData) -> pd.DataFrame | None:
    if data.rows is None:
        return None
    cols = ["scenario", "model", "row", "simulated_mean_lux", "simulated_stderr",
            "measured_mean_lux", "ratio", "difference_lux"]
    return data.rows[[c for c in cols if c in data.rows.columns]]


# --------------------------------------------------------------------------- assembly


def _headline(data: ReportData) -> list[str]:
    p = data.project
    hours = sorted(set(data.hourly["time"]))
    lines = [f"{len(data.names)} scenario(s) ({', '.join(data.names)}), {len(hours)} hour(s) "
             f"({hours[0]}–{hours[-1]}) on {p.site.date} at {p.site.name} "
             f"(latitude {p.site.latitude:g}°, longitude {p.site.longitude:g}°)."]
    if data.stats is not None and len(data.stats):
        best = data.stats.sort_values("rmse").iloc[0]
        lines.append(f"Closest to the measurements: scenario {best['scenario']} "
                     f"({data.scenario(str(best['scenario'])).model_label}, "
                     f"{best['reflection'] or 'reflection ?'}) with nRMSE "
                     f"{best['rmse']:.3f} ({int(BOOTSTRAP['level'] * 100)} % bootstrap "
                     f"{best['rmse_low']:.3f}–{best['rmse_high']:.3f}) and nMBE "
                     f"{best['mbe']:+.3f}.")
    else:
        lines.append("No measurements: the report shows simulated values only.")
    return lines


def _figures(data: ReportData, folder: Path, echo: Callable[[str], None]
             ) -> tuple[dict[str, FigureRef], list[str]]:
    figs: dict[str, FigureRef] = {}
    problems: list[str] = []
    plan: list[tuple[str, str, Callable[[ReportData, Path], str], bool]] = [
        ("hourly", "Hourly measured and simulated façade illuminance", figures.hourly_plot, True),
        ("scatter", "Measured against simulated illuminance", figures.scatter_plot,
         data.comparison is not None),
        ("facade_map", "False-colour façade maps", figures.facade_maps,
         data.map_time is not None),
        ("facade_map_all", "Façade maps for every hour", figures.facade_maps_all_hours,
         data.map_time is not None and len(set(data.hourly["time"])) > 1),
        ("timing", "Wall-clock time per scenario", figures.timing_plot, data.timing is not None),
        ("convergence", "-ab convergence", figures.convergence_plot,
         data.convergence is not None),
    ]
    for key, alt, draw, wanted in plan:
        if not wanted:
            continue
        rel = f"figures/{key}.png"
        try:
            caption = draw(data, folder / rel)
        except Exception as exc:  # a broken figure must not hide the others
            problems.append(f"figure '{key}' could not be drawn: {type(exc).__name__}: {exc}")
            echo(f"  warning: {problems[-1]}")
            continue
        figs[key] = FigureRef(rel, caption, alt)
    for i, ref in enumerate(figs.values(), start=1):
        ref.number = i
    return figs, problems


def _environment(autoescape: bool) -> Environment:
    env = Environment(loader=PackageLoader("radtree", "templates"), undefined=StrictUndefined,
                      autoescape=autoescape, keep_trailing_newline=True, trim_blocks=True,
                      lstrip_blocks=True)
    return env


def diagnose_section(folder: Path) -> str:
    """The diagnosis in the main report: its steps as *fitted* parameters, each with its
    leave-one-hour-out cross-validated nRMSE (kept apart from the fixed-parameter scenarios)."""
    import html

    intro = ("<section id='diagnose'><h2>Diagnosis: fitted effects (reported separately)</h2>"
             "<p>The model–measurement discrepancy workflow (<code>radtree diagnose</code>) adds "
             "the missing physical effect it names and <em>fits its strength to the measured "
             "hours</em>; these numbers are therefore not comparable with the fixed-parameter "
             "scenarios above. Leave-one-hour-out cross-validation (LOHO-CV) refits without "
             "each hour and predicts it. Full report: <a href='../diagnose/index.html'>"
             "diagnose/index.html</a>.</p>")
    steps_csv = folder / "steps.csv"
    if not steps_csv.exists():
        return intro + "</section>"
    steps = pd.read_csv(steps_csv)
    if steps.empty:
        return intro + "<p>No effect was added: nothing explained the residual.</p></section>"
    rows = "".join(
        f"<tr><td class='num'>{int(r['step'])}</td><td>{html.escape(str(r['effect']))}</td>"
        f"<td>{html.escape(str(r.get('strength_text', '')))}</td>"
        f"<td class='num'>{100 * float(r['explained_fraction']):.0f}</td>"
        f"<td>{float(r['rmse_before']):.3f} → {float(r['rmse_after']):.3f}</td>"
        f"<td>{float(r['cv_rmse_before']):.3f} → {float(r['cv_rmse_after']):.3f}</td></tr>"
        for _, r in steps.iterrows())
    return (intro + "<div class='tablewrap' id='t-diagnose_steps'><table><thead><tr>"
            "<th>step</th><th>effect</th><th>fitted strength</th>"
            "<th>residual explained (%)</th><th>nRMSE</th><th>LOHO-CV nRMSE</th></tr></thead>"
            f"<tbody>{rows}</tbody></table></div></section>")


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


def realisations_section(project: Project) -> str:
    """HTML: each crown realisation of a scenario alone, beside their mean ("" when none)."""
    import html

    t = realisation_frame(project)
    if t is None:
        return ""
    hours = [c for c in t.columns if c not in ("scenario", "realisation", "nrmse", "nmbe")]
    head = "".join(f"<th>{html.escape(str(h))}</th>" for h in hours)
    stats_head = "<th>nRMSE</th><th>nMBE</th>" if "nrmse" in t.columns else ""
    rows = []
    for _, r in t.iterrows():
        cells = "".join(f"<td class='num'>{r[h]:.0f}</td>" for h in hours)
        if "nrmse" in t.columns:
            cells += f"<td class='num'>{r['nrmse']:.3f}</td><td class='num'>{r['nmbe']:+.3f}</td>"
        rows.append(f"<tr><td>{html.escape(str(r['scenario']))}</td>"
                    f"<td class='num'>{int(r['realisation'])}</td>{cells}</tr>")
    spread = ""
    if "nrmse" in t.columns:
        spread = " ".join(
            f"Scenario {html.escape(str(name))}: single crowns give nRMSE "
            f"{g['nrmse'].min():.3f}–{g['nrmse'].max():.3f} (mean {g['nrmse'].mean():.3f})."
            for name, g in t.groupby("scenario"))
    return ("<section id='realisations'><h2>Crown realisations</h2><p>Scenarios with "
            "<code>louvers.realisations</code> &gt; 1 trace several random crowns "
            "(<code>louvers.seed</code>, seed + 1, …); the tables above show their mean, with "
            "the standard error over crowns. Each crown alone (façade mean, lux): "
            f"{spread}</p><div class='tablewrap' id='t-realisations'><table><thead><tr>"
            f"<th>scenario</th><th>realisation</th>{head}{stats_head}</tr></thead><tbody>"
            f"{''.join(rows)}</tbody></table></div></section>")


def markdown_extras(project: Project) -> str:
    """Crown realisations, the permeability scan and the fitted diagnosis steps as Markdown
    ("" when none of them exists)."""
    parts = []
    crowns = realisation_frame(project)
    if crowns is not None:
        cols = [c for c in crowns.columns if c not in ("scenario", "realisation")]
        lines = ["\n## Crown realisations\n", "Each random crown alone (façade mean, lux; "
                 "nRMSE/nMBE against the measured hourly means).", "",
                 "| scenario | realisation | " + " | ".join(cols) + " |",
                 "|---|---|" + "---|" * len(cols)]
        lines += ["| " + " | ".join([str(r["scenario"]), str(int(r["realisation"]))]
                                    + [f"{r[c]:.3f}" if c in ("nrmse", "nmbe") else f"{r[c]:.0f}"
                                       for c in cols]) + " |" for _, r in crowns.iterrows()]
        parts.append("\n".join(lines) + "\n")
    from radtree.permeability_scan import read_scan

    scan = read_scan(project)
    if scan is not None:
        t = scan.table
        lines = [f"\n## Scenario {scan.scenario} against the crown's permeability\n",
                 *[f"- {x}" for x in scan.summary()], "",
                 f"| {scan.field} | permeability, street (%) | permeability, unobstructed (%) "
                 "| nRMSE | nMBE | r |", "|---|---|---|---|---|---|"]
        lines += [f"| {r['value']:g} | {100 * r['permeability_street']:.2f} | "
                  f"{100 * r['permeability_unobstructed']:.2f} | {r['nrmse']:.3f} | "
                  f"{r['nmbe']:+.3f} | {r['r']:.3f} |" for _, r in t.iterrows()]
        parts.append("\n".join(lines) + "\n")
    steps_csv = project.root / "diagnose" / "steps.csv"
    if steps_csv.exists():
        st = pd.read_csv(steps_csv)
        lines = ["\n## Diagnosis: fitted effects (reported separately)\n",
                 "Strengths fitted to the measured hours; LOHO-CV = leave-one-hour-out "
                 "cross-validated nRMSE.", "",
                 "| step | effect | fitted strength | explained (%) | nRMSE | LOHO-CV nRMSE |",
                 "|---|---|---|---|---|---|"]
        lines += [f"| {int(r['step'])} | {r['effect']} | {r.get('strength_text', '')} | "
                  f"{100 * float(r['explained_fraction']):.0f} | {float(r['rmse_before']):.3f} → "
                  f"{float(r['rmse_after']):.3f} | {float(r['cv_rmse_before']):.3f} → "
                  f"{float(r['cv_rmse_after']):.3f} |" for _, r in st.iterrows()]
        parts.append("\n".join(lines) + "\n")
    return "".join(parts)


def extra_sections(project: Project, out: Path, echo: Callable[[str], None]) -> list[str]:
    """HTML sections of the studies that exist for this project: office block, sweep,
    diagnosis, annual. Their figures are written into ``out`` (the report folder)."""
    parts: list[str] = []
    if project.office is not None:
        from radtree.office_summary import (
            office_report_section,
            read_results,
            summarise,
            write_hourly_charts,
            write_maps,
            write_summary,
        )

        write_summary(project, maps=False)
        table = read_results(project)
        write_maps(project, table, out / "office")
        write_hourly_charts(project, summarise(table), out / "office")
        parts.append(office_report_section(project))
        echo("  office block: summary table and false-colour maps")
    from radtree.sweep.sensitivity import sweep_report_section

    sweep = sweep_report_section(project.root)
    if sweep:
        parts.append(sweep)
        echo("  sweep: sensitivity section")
    crowns = realisations_section(project)
    if crowns:
        parts.append(crowns)
        echo("  crown realisations section")
    from radtree.permeability_scan import scan_report_section

    scan = scan_report_section(project, out)
    if scan:
        parts.append(scan)
        echo("  permeability scan section")
    diag = project.root / "diagnose" / "index.html"
    if diag.exists():
        parts.append(diagnose_section(project.root / "diagnose"))
    annual = project.results_dir / "annual_summary.csv"
    if annual.exists():
        from radtree.annual import annual_report_section

        parts.append(annual_report_section(project))
        echo("  annual: metric maps and month × hour heat maps")
    return parts


def _with_extra_sections(project: Project, html: str, out: Path,
                         echo: Callable[[str], None]) -> str:
    parts = extra_sections(project, out, echo)
    if not parts:
        return html
    marker = '<section id="provenance">'
    block = "\n".join(parts) + "\n"
    return html.replace(marker, block + marker, 1) if marker in html else html + block


def build_report(project: Project, echo: Callable[[str], None] = print) -> Path:
    """Write ``PROJECT/report/`` (index.html, index.md, CSVs, figures); return index.html.

    Raises RadtreeError when there are no results, and passes on the RadtreeError of
    :func:`radtree.stats.compare` when a measured hour has no simulated counterpart.
    """
    echo(f"report for {project.name}")
    data = collect(project, echo=echo)
    created = datetime.now(timezone.utc).isoformat(timespec="seconds")
    target = project.report_dir
    with atomic_dir(target) as tmp:
        figs, problems = _figures(data, tmp, echo)
        (tmp / "models").mkdir()
        for s in data.scenarios:
            if s.picture is not None:
                shutil.copyfile(s.picture, tmp / "models" / f"{s.name}.png")
        tables: dict[str, Table] = {
            "scenarios": scenario_table(data), "hourly": hourly_table(data),
            "statistics": statistics_table(data), "reflection": reflection_table(data),
        }
        for key, tb in (("rows", rows_table(data)), ("rows_between", rows_between_table(data)),
                        ("timing", timing_table(data))):
            if tb is not None:
                tables[key] = tb
        conv, conv_summary = convergence_tables(data)
        if conv is not None and conv_summary is not None:
            tables["convergence"], tables["convergence_summary"] = conv, conv_summary
        tables.update(provenance_tables(data, created))
        p = project
        ctx = Context(
            title=f"radtree report — {p.name}",
            subtitle=(f"{p.site.name}, {p.site.date}; façade looking "
                      f"{p.street.facade_azimuth_deg:g}° (compass); " + (
                          f"light: {data.scenarios[0].sky}"
                          if len({s.sky for s in data.scenarios}) == 1
                          else "light per scenario (Table 1)")),
            created=created, headline=_headline(data), notes=data.notes,
            has_measured=data.comparison is not None, tables=tables, figs=figs,
            figure_problems=problems, models=model_pictures(data), map_reason=data.map_time_reason,
            method={
                "measured": (str(p.measured.name) if p.measured is not None else ""),
                "measured_rows": (str(p.measured_rows.name) if p.measured_rows is not None
                                  else ""),
            },
            parameters=parameters_table(data),
        )
        statistics_frame(data).to_csv(tmp / "statistics.csv", index=False)
        hourly_frame(data).to_csv(tmp / "hourly.csv", index=False)
        rf = rows_frame(data)
        if rf is not None:
            rf.to_csv(tmp / "rows.csv", index=False)
        html = _environment(True).get_template("report.html.j2").render(c=ctx)
        html = _with_extra_sections(project, html, tmp, echo)
        md = _environment(False).get_template("report.md.j2").render(c=ctx)
        md += markdown_extras(project)
        (tmp / "index.html").write_text(html, encoding="utf-8")
        (tmp / "index.md").write_text(md, encoding="utf-8")
    index = target / "index.html"
    echo(f"report written to {index}")
    return index

