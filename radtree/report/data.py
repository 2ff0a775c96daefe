"""Everything the report shows, read from the results layout and reduced with radtree.stats.

Reads only ``PROJECT/results/`` (illuminance.csv, timing.csv, manifest.json, convergence.csv),
``PROJECT/build/<scenario>/manifest.json`` and ``model.png``, and the project's measurement
files. Nothing here knows which engine produced the numbers.
"""

from __future__ import annotations

import json
import logging
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from radtree.config import Project
from radtree.errors import RadtreeError
from radtree.measurements import (
    MeasuredShape,
)
from radtree.pipeline.results import read_results, results_path
from radtree.report.measured import compare_measured, row_tables
from radtree.stats import (
    FACADE_GRID,
    Comparison,
    hourly_means,
)

MAP_GRID = "facade_map"
FORM_ORDER = ("dome", "free")
FORM_LABELS = {"dome": "sensor dome (study form)", "free": "free-standing crown",
               "unknown": "crown form not recorded"}
MODEL_LABELS = {"none": "none (open street)"}
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
TIMING_PARTS = ("preparation_s", "geometry_s", "tracing_s")
log = logging.getLogger(__name__)


@dataclass
class ScenarioInfo:
    """What the report knows about one scenario of the results table."""

    name: str
    model: str
    form: str
    form_source: str
    reflection: str
    reflection_note: str
    sky: str
    description: str
    engine: str
    params_hash: str
    current_hash: str | None
    in_project: bool
    build: dict[str, Any] = field(default_factory=dict)
    build_manifest_found: bool = False
    picture: Path | None = None
    picture_problem: str = ""
    stand_in: bool = False   # a crown from a stand-in input (see :func:`is_stand_in`)

    @property
    def form_label(self) -> str:
        return FORM_LABELS.get(self.form, self.form)

    @property
    def model_label(self) -> str:
        return MODEL_LABELS.get(self.model, self.model)

    @property
    def label(self) -> str:
        return f"{self.name}: {self.model_label}, {self.reflection or 'reflection ?'}"


@dataclass
class ReportData:
    project: Project
    results: pd.DataFrame
    scenarios: list[ScenarioInfo]
    hourly_sim: pd.DataFrame                 # hourly_means on the façade grid
    hourly: pd.DataFrame                     # time, measured_lux, one column per scenario
    measured: pd.DataFrame | None            # time, measured_lux (grid mean)
    measured_shape: MeasuredShape | None
    comparison: Comparison | None
    stats: pd.DataFrame | None               # comparison.stats in scenario order
    rows: pd.DataFrame | None                # per-row daily means (vs measured when known)
    rows_measured: bool
    rows_between: pd.DataFrame | None
    timing: pd.DataFrame | None
    convergence: pd.DataFrame | None
    results_manifest: dict[str, Any] | None
    map_time: str | None
    map_time_reason: str
    notes: list[str] = field(default_factory=list)

    @property
    def names(self) -> list[str]:
        return [s.name for s in self.scenarios]

    def scenario(self, name: str) -> ScenarioInfo:
        for s in self.scenarios:
            if s.name == name:
                return s
        raise KeyError(name)


# --------------------------------------------------------------------------- reading


def _read_json(path: Path, notes: list[str]) -> dict[str, Any] | None:
    if not path.is_file():
        return None
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        notes.append(f"{path} could not be read ({exc}); its facts are left out")
        return None
    if not isinstance(data, dict):
        notes.append(f"{path} is not a JSON object; its facts are left out")
        return None
    return data


def _read_csv(path: Path, required: tuple[str, ...], notes: list[str]) -> pd.DataFrame | None:
    if not path.is_file():
        return None
    try:
        df = pd.read_csv(path, dtype={"scenario": str})
    except (OSError, ValueError) as exc:
        notes.append(f"{path} could not be read ({exc}); it is left out")
        return None
    missing = [c for c in required if c not in df.columns]
    if missing:
        notes.append(f"{path} lacks column(s) {', '.join(missing)}; it is left out")
        return None
    return df


def _is_png(path: Path) -> bool:
    try:
        with open(path, "rb") as f:
            return f.read(8) == PNG_SIGNATURE
    except OSError:
        return False


def _unique(series: pd.Series) -> list[str]:
    return [str(v) for v in pd.unique(series.dropna()) if str(v) != ""]


# --------------------------------------------------------------------------- scenarios


def _reflection_notes(project: Project, notes: list[str]) -> dict[str, str]:
    from radtree.light.ground import reflection_notes

    try:
        return reflection_notes(project)
    except (RadtreeError, ValueError) as exc:
        notes.append(f"ground-reflection description failed: {exc}")
        out = {}
        for sc in project.scenarios:
            out[sc.name] = ("calculated (details unavailable)" if sc.reflection == "calculated"
                            else "traced: sun → street → façade through the crown model")
        return out


SKY_LABELS = {"none": "sun only", "perez": "sun + Perez sky"}


def _sky_label(project: Project, sky: str) -> str:
    """The sky model in words (its values per hour: the manifest's weather record)."""
    return SKY_LABELS.get(sky, sky)


def is_stand_in(sc: Any) -> bool:
    """A scenario whose crown comes from a stand-in input (its description says "stand-in",
    or a switch names a ``standin`` file): shown, marked, never the scale of a figure."""
    return ("stand-in" in sc.description.lower()
            or any(re.search(r"standin\b|stand-in", str(v).lower()) for v in sc.switches.values()))


def is_reference_study(project: Project) -> bool:
    """A project run by the reference study's method: the sensor-dome crown form, or measured
    daily means per sensor row. Only such a report shows the study's sections."""
    return (project.measured_rows is not None or project.tree.form == "dome"
            or any(s.form == "dome" for s in project.scenarios))


def _build_record(project: Project, name: str, notes: list[str]
                  ) -> tuple[dict[str, Any] | None, dict[str, Any], Path | None, str]:
    """Scenario ``name``'s build manifest (None when absent), its ``build`` record, and its
    crown picture ``model.png`` (None, with the reason when the file is not a PNG)."""
    folder = project.build_dir / name
    if not folder.exists() and (project.build_dir / f"{name}@1").exists():
        folder = project.build_dir / f"{name}@1"   # crown realisations: the first one
    mf = _read_json(folder / "manifest.json", notes)
    build = mf.get("build", {}) if mf else {}
    build = build if isinstance(build, dict) else {}
    picture, problem = None, ""
    png = folder / "model.png"
    if png.is_file():
        if png.stat().st_size > 0 and _is_png(png):
            picture = png
        else:
            problem = f"{png} is not a valid PNG picture"
    return mf, build, picture, problem


def _hash_notes(name: str, hashes: list[str], current: str | None, notes: list[str]) -> None:
    """A note when the results mix parameter hashes or differ from the project file's."""
    if len(hashes) > 1:
        notes.append(f"scenario {name}: the results mix parameter hashes "
                     f"{', '.join(hashes)}")
    elif hashes and current is not None and hashes[0] != current:
        notes.append(f"scenario {name}: the results were computed with parameters "
                     f"{hashes[0]}, but the project file (read by this radtree) now gives "
                     f"{current} — the report shows the stored results; run `radtree "
                     "simulate` to update them")


def scenario_infos(project: Project, results: pd.DataFrame,
                   notes: list[str]) -> list[ScenarioInfo]:
    """One entry per scenario in the results, grouped by crown form, project order inside."""
    in_project = {s.name: s for s in project.scenarios}
    order = {s.name: i for i, s in enumerate(project.scenarios)}
    refl_notes = _reflection_notes(project, notes)
    infos = []
    for name in _unique(results["scenario"]):
        rows = results[results["scenario"] == name]
        sc = in_project.get(name)
        models = _unique(rows["model"])
        model = models[0] if models else (sc.model if sc else "?")
        refl_col = _unique(rows["reflection"]) if "reflection" in rows.columns else []
        reflection = refl_col[0] if refl_col else (sc.reflection if sc else "")
        hashes = _unique(rows["params_hash"]) if "params_hash" in rows.columns else []
        engines = _unique(rows["engine"]) if "engine" in rows.columns else []
        mf, build, picture, problem = _build_record(project, name, notes)
        if build.get("form"):
            form, source = str(build["form"]), "build manifest"
        elif sc is not None:
            form, source = sc.form or project.tree.form, "project file"
        else:
            form, source = "unknown", ""
        if sc is not None:
            note = refl_notes.get(name, "")
        else:
            note = (f"{reflection} (scenario not in the project file; mode from the results)"
                    if reflection else "not recorded")
            notes.append(f"scenario {name} is in the results but not in the project file "
                         f"{project.source.name}; it is reported from the results alone")
        current = project.params_hash(sc) if sc is not None else None
        _hash_notes(name, hashes, current, notes)
        infos.append(ScenarioInfo(
            name=name, model=model, form=form, form_source=source, reflection=reflection,
            reflection_note=note,
            sky=_sky_label(project, sc.sky or project.light.sky) if sc is not None else "?",
            description=sc.description if sc is not None else "",
            engine=", ".join(engines), params_hash=", ".join(hashes), current_hash=current,
            in_project=sc is not None, build=build, build_manifest_found=mf is not None,
            picture=picture, picture_problem=problem,
            stand_in=sc is not None and is_stand_in(sc),
        ))

    def key(info: ScenarioInfo) -> tuple[int, str, int, str]:
        f = FORM_ORDER.index(info.form) if info.form in FORM_ORDER else len(FORM_ORDER)
        return (f, info.form, order.get(info.name, len(order)), info.name)

    return sorted(infos, key=key)


# --------------------------------------------------------------------------- assembly


def _no_map_reason(project: Project) -> str:
    """Why the results hold no dense façade grid, and what to do — from the project."""
    if project.district is not None:
        return ("an inventory project traces every façade's sensors instead of one dense "
                "façade map; the site plan and the per-façade tables show every façade")
    if project.sensors.dense_grid:
        return ("the results hold no dense façade grid ('facade_map') although "
                "sensors.dense_grid is on: they predate it, or none of sensors.dense_hours was "
                "simulated — run `radtree simulate` again")
    return "sensors.dense_grid is off (set it to true and simulate again for a façade map)"


def _map_time(results: pd.DataFrame, measured: pd.DataFrame | None,
              hourly_sim: pd.DataFrame, project: Project) -> tuple[str | None, str]:
    maps = results[results["grid"].astype(str) == MAP_GRID]
    if maps.empty:
        return None, _no_map_reason(project)
    times = set(maps["time"])
    if measured is not None:
        m = measured[measured["time"].isin(times)]
        if not m.empty:
            best = m.loc[m["measured_lux"].idxmax()]
            return str(best["time"]), (f"{best['time']}, the hour of highest measured façade "
                                       f"illuminance ({best['measured_lux']:.0f} lx)")
    sim = hourly_sim[hourly_sim["time"].isin(times)]
    if sim.empty:
        t = sorted(times)[0]
        return t, f"{t}, the first hour of the dense grid"
    mean = sim.groupby("time")["lux"].mean()
    t = str(mean.idxmax())
    return t, (f"{t}, the hour of highest simulated façade illuminance (mean over the "
               "scenarios; no measurements)")


def one_level_as_facade(project: Project, results: pd.DataFrame, notes: list[str]
                        ) -> pd.DataFrame:
    """A street with sensors at several heights (``facade@<h>m``, :mod:`radtree.sensor_grid`):
    the circle (and map) nearest ``sensors.height_m`` becomes the ``facade`` grid the core
    sections read, and a note gives every storey's mean over the hours per scenario."""
    from radtree.sensor_grid import LEVEL_MARK, level_name

    grid = results["grid"].astype(str)
    levels = project.sensors.levels
    if len(levels) < 2 or not grid.str.startswith(FACADE_GRID + LEVEL_MARK).any():
        return results
    h = min(levels, key=lambda v: (abs(v - project.sensors.height_m), v))
    means = (results[grid.str.startswith(FACADE_GRID + LEVEL_MARK)]
             .groupby(["scenario", "storey", "grid"])["lux"].mean())
    per = "; ".join(f"{scen} " + ", ".join(f"storey {int(k)} ({g.split(LEVEL_MARK)[1]}) "
                                           f"{v:,.0f} lx" for (_, k, g), v in sub.items())
                    for scen, sub in means.groupby(level=0, sort=False))
    notes.append(f"façade sensors at {len(levels)} heights ([sensors] heights_m): the report's "
                 f"façade grid is the circle at {h:g} m (nearest sensors.height_m "
                 f"{project.sensors.height_m:g} m); mean over the hours per storey: {per}")
    out = results.copy()
    out.loc[grid == level_name(FACADE_GRID, h), "grid"] = FACADE_GRID
    out.loc[grid == level_name(MAP_GRID, h), "grid"] = MAP_GRID
    return out


def _hourly_table(hourly_sim: pd.DataFrame, measured: pd.DataFrame | None,
                  order: list[str]) -> pd.DataFrame:
    """Every simulated or measured hour: time, measured_lux (blank where not measured), one
    column per scenario (lux)."""
    wide = hourly_sim.pivot(index="time", columns="scenario", values="lux")
    wide = wide.reindex(columns=order)
    if measured is not None:
        hourly = measured[["time", "measured_lux"]].merge(
            wide.reset_index(), on="time", how="outer")
    else:
        hourly = wide.reset_index()
        hourly.insert(1, "measured_lux", math.nan)
    hourly = hourly.sort_values("time").reset_index(drop=True)
    hourly.columns = [str(c) for c in hourly.columns]
    return hourly


def _run_files(project: Project, order: list[str], notes: list[str]
               ) -> tuple[pd.DataFrame | None, pd.DataFrame | None, dict[str, Any] | None]:
    """``results/timing.csv``, ``convergence.csv`` and ``manifest.json`` (None when absent,
    with a note)."""
    timing = _read_csv(project.results_dir / "timing.csv", ("scenario", *TIMING_PARTS), notes)
    if timing is None:
        notes.append("no results/timing.csv: wall-clock times unavailable")
    else:
        timing = timing.assign(scenario=timing["scenario"].astype(str))
        absent = [n for n in order if n not in set(timing["scenario"])]
        if absent:
            notes.append(f"timing.csv has no entry for scenario(s) {', '.join(absent)}")
    convergence = _read_csv(project.results_dir / "convergence.csv",
                            ("scenario", "ab", "facade_mean_lux"), notes)
    if convergence is not None:
        convergence = convergence.assign(scenario=convergence["scenario"].astype(str))
    return timing, convergence, _read_json(project.results_dir / "manifest.json", notes)


def collect(project: Project) -> ReportData:
    """Read the results layout and compute every table the report shows."""
    notes: list[str] = []
    results = read_results(project)
    if project.district is not None:   # every façade of an inventory: one façade grid here
        from radtree.report.sections.facades import as_one_facade_grid

        results = as_one_facade_grid(results)
    results = one_level_as_facade(project, results, notes)
    if results[results["grid"].astype(str) == FACADE_GRID].empty:
        raise RadtreeError(f"{results_path(project)}: no rows for the façade sensor grid "
                           f"'{FACADE_GRID}'")
    scenarios = scenario_infos(project, results, notes)
    order = [s.name for s in scenarios]
    rank = {n: i for i, n in enumerate(order)}
    hourly_sim = hourly_means(results)
    hourly_sim = (hourly_sim.assign(_s=hourly_sim["scenario"].map(rank))
                  .sort_values(["_s", "time"]).drop(columns="_s").reset_index(drop=True))
    m = compare_measured(project, results, {s.name: s.reflection for s in scenarios}, order,
                         notes)
    hourly = _hourly_table(hourly_sim, m.hourly, order)
    rows, rows_measured, between = row_tables(project, results, m.tidy, m.times, order, notes)
    timing, convergence, manifest = _run_files(project, order, notes)
    map_time, reason = _map_time(results, m.hourly, hourly_sim, project)
    return ReportData(
        project=project, results=results, scenarios=scenarios, hourly_sim=hourly_sim,
        hourly=hourly, measured=m.hourly, measured_shape=m.shape, comparison=m.comparison,
        stats=m.stats, rows=rows, rows_measured=rows_measured, rows_between=between,
        timing=timing, convergence=convergence, results_manifest=manifest, map_time=map_time,
        map_time_reason=reason, notes=notes)


# --------------------------------------------------------------------------- geometry


def facade_coordinates(x: np.ndarray, y: np.ndarray,
                       azimuth_deg: float) -> tuple[np.ndarray, np.ndarray]:
    """Horizontal coordinate along the façade for world points (x, y), and the axis used.

    The axis is the principal direction of the points' x/y spread (PCA), oriented like the
    façade frame's "along" axis of ``azimuth_deg`` (to the right seen from the street); for a
    degenerate spread (one column of points) the frame's axis itself.
    """
    a = math.radians(azimuth_deg)
    frame_along = np.array([math.cos(a), -math.sin(a)])
    xy = np.column_stack([np.asarray(x, float), np.asarray(y, float)])
    axis = frame_along
    if len(xy) >= 2:
        centred = xy - xy.mean(axis=0)
        _, s, vt = np.linalg.svd(centred, full_matrices=False)
        if s[0] > 1e-6 and (len(s) < 2 or s[0] > 5 * s[1]):
            axis = vt[0]
            if float(axis @ frame_along) < 0:
                axis = -axis
    return xy @ axis, axis
