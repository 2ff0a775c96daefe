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
    PROJECT/report/impact.csv       what the trees do, per façade / storey / room and hour
                                    (:mod:`radtree.report.impact`; with a with/without pair)

The page is one ordered list of sections (:func:`page_sections`), rendered alike by
``report.html.j2`` and ``report.md.j2``: what the trees do first (when the project has a
with/without-trees pair), the light traced (from the manifest's weather record), the results
the project has (measurement statistics only with measurements, sensor rows only in the
reference study, façades for an inventory, rooms for an office), then an appendix with the
research sections (ground reflection, convergence, timing, provenance).
"""

from __future__ import annotations

import json
import logging
import multiprocessing
from collections.abc import Callable
from concurrent.futures import Future, ProcessPoolExecutor
from dataclasses import dataclass, field
from datetime import datetime, timezone
from functools import partial
from pathlib import Path
from typing import Any

import pandas as pd

import radtree.report.figures as figures
from radtree.config import Project
from radtree.figures import compact_png
from radtree.fileio import atomic_dir
from radtree.lock import PUBLISH_NAME, folder_lock
from radtree.pipeline.processes import usable_cores
from radtree.pipeline.results import read_results
from radtree.report.data import (
    ReportData,
    collect,
    is_reference_study,
)
from radtree.report.impact import tree_pairs
from radtree.report.light import light_description, weather_records
from radtree.report.sections import Section, environment
from radtree.report.sections.extras import extra_sections
from radtree.report.sections.impact import impact_data
from radtree.report.sections.provenance import (
    ModelPicture,
    model_pictures,
    parameters_table,
    provenance_tables,
)
from radtree.report.sections.results import (
    BOOTSTRAP,
    convergence_tables,
    hourly_table,
    reflection_table,
    rows_between_table,
    rows_table,
    scenario_table,
    statistics_table,
    timing_table,
)
from radtree.report.tables import Table
from radtree.stats import STATS_COLUMNS

COMPASS = ("north", "north-east", "east", "south-east", "south", "south-west", "west",
           "north-west")
#: The columns of statistics.csv every reader may rely on (reference case §3, normalised).
STATISTICS_CONTRACT = ["scenario", "model", "reflection", "rmse", "rmse_low", "rmse_high", "mbe",
                       "r", "r2", "n_hours"]
STATISTICS_EXTRA = ["rmse_lux", "mbe_lux", "rmse_mc_se", "form"]
log = logging.getLogger(__name__)


@dataclass
class FigureRef:
    """A figure in the report: file relative to the report folder, caption, alt text."""

    file: str
    caption: str
    alt: str
    number: int = 0


@dataclass
class PageContext:
    """Everything the page templates and their core sections render (as ``c``)."""

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
    sections: list[Section] = field(default_factory=list)    # the page, in order (html = md)


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


def _warnings(data: ReportData) -> list[str]:
    """First-page warnings from the builds: a crown built from a photo fit the user accepted
    although it does not describe the photo (``[tree] accept_poor_fit``)."""
    out = []
    for name in data.names:
        for note in data.scenario(name).build.get("notes", []) or []:
            if str(note).startswith("POOR PHOTO FIT ACCEPTED"):
                out.append(f"WARNING — scenario {name}: {note} Its crown is not what the "
                           "photo shows; read its results with that in mind.")
    return out


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


class _Figures:
    """The report's figures: the two façade-map figures (half of the drawing time) in a spawned
    worker process while everything else of the report is made here (when there is a second
    core), the others drawn at once. :meth:`results` waits for the worker."""

    def __init__(self, data: ReportData, folder: Path):
        plan: list[tuple[str, str, Callable[[ReportData, Path], str], bool]] = [
            ("hourly", "Hourly measured and simulated façade illuminance", figures.hourly_plot,
             True),
            ("scatter", "Measured against simulated illuminance", figures.scatter_plot,
             data.comparison is not None),
            ("facade_map", "False-colour façade maps", figures.facade_maps,
             data.map_time is not None),
            ("facade_map_all", "Façade maps for every hour", figures.facade_maps_all_hours,
             data.map_time is not None and len(set(data.hourly["time"])) > 1),
            ("timing", "Wall-clock time per scenario", figures.timing_plot,
             data.timing is not None),
            ("convergence", "-ab convergence", figures.convergence_plot,
             data.convergence is not None),
        ]
        self.wanted = [(key, alt, draw) for key, alt, draw, want in plan if want]
        self.problems: list[str] = []
        apart = [k for k, _, _ in self.wanted if k.startswith("facade_map")]
        self.pool = (ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn"))
                     if len(apart) > 1 and usable_cores() > 1 else None)
        self.done: dict[str, Any] = {}
        for key, _, draw in self.wanted:
            path = folder / f"figures/{key}.png"
            if self.pool is not None and key in apart:
                self.done[key] = self.pool.submit(draw, data, path)
            else:
                self.done[key] = self._draw(key, partial(draw, data, path))

    def _draw(self, key: str, call: Callable[[], str]) -> str | None:
        try:
            return call()
        except Exception as exc:  # a broken figure must not hide the others
            self.problems.append(f"figure '{key}' could not be drawn: {type(exc).__name__}: "
                                 f"{exc}")
            log.warning("%s", self.problems[-1])
            return None

    def results(self) -> tuple[dict[str, FigureRef], list[str]]:
        """The figures drawn (numbered in order) and the problems of those that were not."""
        figs: dict[str, FigureRef] = {}
        try:
            for key, alt, _ in self.wanted:
                got = self.done[key]
                caption = (self._draw(key, got.result) if isinstance(got, Future) else got)
                if caption is not None:
                    figs[key] = FigureRef(f"figures/{key}.png", caption, alt)
        finally:
            if self.pool is not None:
                self.pool.shutdown(wait=True, cancel_futures=True)
        for i, ref in enumerate(figs.values(), start=1):
            ref.number = i
        return figs, self.problems


def light_data(data: ReportData) -> dict[str, Any]:
    """The light section: a line from the manifest's weather record and its hours."""
    records = weather_records(data.results_manifest)
    shown = {n: records[n] for n in data.names if n in records}
    groups: dict[str, list[str]] = {}
    for name, recs in shown.items():
        groups.setdefault(json.dumps(recs, sort_keys=True), []).append(name)
    first = next(iter(shown.values()), [])
    if len(groups) <= 1:
        description = "Every scenario: " + light_description(first) + "."
    else:
        description = "; ".join(f"scenario(s) {', '.join(names)}: "
                                f"{light_description(json.loads(key))}"
                                for key, names in groups.items()) + "."
    table = None
    if shown:
        sources = {str(r["source"]) for recs in shown.values() for r in recs}
        one = next(iter(sources)) if len(sources) == 1 else None
        caption = ("The light of each hour traced, as recorded by `radtree simulate` in "
                   "results/manifest.json: direct normal and diffuse horizontal illuminance "
                   "(lx), sky model" + (f"; every hour's source: {one}." if one else
                                        " and source."))
        table = Table("light", caption, ["scenarios", "hour", "direct normal (lx)",
                                         "diffuse horizontal (lx)", "sky"]
                      + ([] if one else ["source"]),
                      [False, False, True, True, False] + ([] if one else [False]))
        for key, names in groups.items():
            for r in json.loads(key):
                table.add(", ".join(names), r["time"], f"{float(r['direct_normal_lux']):,.0f}",
                          f"{float(r['diffuse_horizontal_lux']):,.0f}", r["sky"],
                          *([] if one else [r["source"]]))
    return {"description": description, "table": table, "first": light_description(first)
            if len(groups) <= 1 else "per scenario (see 'The light traced')"}


def _subtitle(data: ReportData, light: dict[str, Any]) -> str:
    p = data.project
    if p.district is not None:
        where = "every façade of the inventory's buildings"
    else:
        az = p.street.facade_azimuth_deg
        where = f"façade facing {COMPASS[round(az / 45) % 8]} (azimuth {az:g}°)"
    return f"{p.site.name}, {p.site.date}; {where}; light: {light['first']}"


def page_sections(data: ReportData, tables: dict[str, Table], first: list[Section],
                  extras: list[Section], has_maps: bool) -> list[Section]:
    """The page's sections in order, each only when the project has its data: ``first`` (what
    the trees do, the light traced), the results, ``extras``, then the appendix."""
    reference = is_reference_study(data.project)
    out: list[Section] = list(first)
    out.append(Section("scenarios", {}, "Scenarios"))
    out.append(Section("hourly", {}, "Hourly façade illuminance"))
    if data.comparison is not None:
        out.append(Section("statistics", {}, "Statistics against measurement"))
    if "rows" in tables and (reference or data.rows_measured):
        out.append(Section("rows", {}, "Sensor rows"))
    if has_maps:
        out.append(Section("maps", {}, "False-colour façade maps"))
    out.extend(extras)
    if any(s.model != "none" for s in data.scenarios):
        out.append(Section("models", {}, "Crown models"))
    out.append(Section("reflection", {}, "Ground-reflected light", appendix=True))
    if "convergence" in tables:
        out.append(Section("convergence", {}, "-ab convergence", appendix=True))
    if "timing" in tables:
        out.append(Section("timing", {}, "Timing", appendix=True))
    out.append(Section("provenance", {}, "Provenance", appendix=True))
    return out


def report_tables(data: ReportData, created: str) -> dict[str, Table]:
    """Every table the page may show, by key (those without data left out)."""
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
    return tables


def page_context(data: ReportData, raw: pd.DataFrame, created: str, folder: Path
                 ) -> PageContext:
    """The page's context before its figures and sections: tables, what the trees do (its
    figures written into ``folder``), headline, notes, method and parameters."""
    p = data.project
    tables = report_tables(data, created)
    pairs = tree_pairs(p, data.names)
    impact = impact_data(p, raw, pairs, folder) if pairs else None
    if impact is not None:
        log.info("  what the trees do: %s against %s", ", ".join(x.trees for x in pairs),
                 pairs[0].baseline)
    light = light_data(data)
    ctx = PageContext(
        title=f"radtree report — {p.name}", subtitle=_subtitle(data, light), created=created,
        headline=(_warnings(data) + (impact["lines"] if impact else []) + _headline(data)),
        notes=data.notes, has_measured=data.comparison is not None, tables=tables,
        models=model_pictures(data), map_reason=data.map_time_reason,
        method={"measured": (str(p.measured.name) if p.measured is not None else ""),
                "measured_rows": (str(p.measured_rows.name) if p.measured_rows is not None
                                  else "")},
        parameters=parameters_table(data),
    )
    ctx.sections = [Section("impact", impact, "What the trees do")] if impact is not None else []
    ctx.sections.append(Section("light", light, "The light traced"))
    return ctx


def write_pages(ctx: PageContext, data: ReportData, folder: Path) -> None:
    """The CSVs, index.html and index.md into ``folder``; the charts as palette PNGs."""
    statistics_frame(data).to_csv(folder / "statistics.csv", index=False)
    hourly_frame(data).to_csv(folder / "hourly.csv", index=False)
    rf = rows_frame(data)
    if rf is not None:
        rf.to_csv(folder / "rows.csv", index=False)
    html = environment(html=True).get_template("report.html.j2").render(c=ctx)
    md = environment(html=False).get_template("report.md.j2").render(c=ctx)
    (folder / "index.html").write_text(html, encoding="utf-8")
    (folder / "index.md").write_text(md, encoding="utf-8")
    for png in sorted((folder / "figures").glob("*.png")) if (folder / "figures").is_dir() else []:
        compact_png(png, png, max_px=1800, colors=256)   # charts: a palette, same size


def build_report(project: Project) -> Path:
    """Write ``PROJECT/report/`` (index.html, index.md, CSVs, figures); return index.html.
    Progress messages go to this module's logger (:mod:`radtree.log`).

    Raises RadtreeError when there are no results, and passes on the RadtreeError of
    :func:`radtree.stats.compare` when a measured hour has no simulated counterpart.
    """
    log.info("report for %s", project.name)
    with folder_lock(project.results_dir, "radtree report", wait=True, name=PUBLISH_NAME,
                     shared=True):                 # one simulate's table, timing and manifest
        data = collect(project)
        raw = read_results(project)
    created = datetime.now(timezone.utc).isoformat(timespec="seconds")
    with atomic_dir(project.report_dir) as tmp:
        drawing = _Figures(data, tmp)
        (tmp / "models").mkdir()
        for s in data.scenarios:
            if s.picture is not None:
                compact_png(s.picture, tmp / "models" / f"{s.name}.png")
        ctx = page_context(data, raw, created, tmp)
        extras = extra_sections(project, tmp, raw)
        ctx.figs, ctx.figure_problems = drawing.results()
        if data.map_time is None and project.district is None:
            ctx.notes.append(f"No façade map: {data.map_time_reason}.")
        ctx.sections = page_sections(data, ctx.tables, ctx.sections, extras,
                                     "facade_map" in ctx.figs)
        write_pages(ctx, data, tmp)
    index = project.report_dir / "index.html"
    log.info("report written to %s", index)
    return index
