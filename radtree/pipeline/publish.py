"""``simulate``'s publish step: the traced rows become the project's result files, at once.

Under the results folder's publish lock (:func:`radtree.lock.folder_lock`, so that a reader —
``radtree report`` — sees one run's files together): ``results/illuminance.csv`` (the
scenarios traced replace their earlier rows), ``realisations.csv`` (per crown realisation),
``direct_sun.csv`` (perforated crowns), the district's ``facades.geojson``, ``tree_impact.csv``,
``timing.csv`` (seconds per scenario) and ``manifest.json``.
"""

from __future__ import annotations

import json
import logging
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pandas as pd

from radtree.config import Project, Scenario
from radtree.engines.base import Engine
from radtree.fileio import atomic_path, write_text
from radtree.light.sky import SkyState
from radtree.lock import PUBLISH_NAME, folder_lock
from radtree.pipeline.jobs import Prepared
from radtree.pipeline.manifest import manifest, weather_record
from radtree.pipeline.realisations import merge_realisations, parent_name
from radtree.pipeline.results import in_column_order, merge_write, results_path

log = logging.getLogger(__name__)


@dataclass
class SimulationOutcome:
    """What ``simulate`` wrote: the results ``table`` (read back from ``path``), per-scenario
    ``timing`` (s), hours ``computed`` and ``reused`` from earlier parts, the ``engine`` name."""

    table: pd.DataFrame
    path: Path
    timing: pd.DataFrame
    computed: int
    reused: int
    engine: str


@dataclass(frozen=True)
class Run:
    """What the publish step needs of a run: the project, engine, the chosen scenarios and
    their preparations, the grids asked for, the scenarios traced (not all reused)."""

    project: Project
    engine: Engine
    chosen: Sequence[Scenario]
    prepared: dict[str, Prepared]
    grids: tuple[str, ...] | None
    traced: frozenset[str]
    #: attribute the light each tree takes (:attr:`RunOptions.tree_impact`)
    tree_impact: bool = True


def publish(run: Run, frames: list[pd.DataFrame], timing: dict[str, dict[str, float]],
            counts: tuple[int, int]) -> SimulationOutcome:
    """Write every result file of the run (see the module text); ``counts``: parts
    (computed, reused)."""
    project = run.project
    table, parents = _results_table(run, frames)
    impact = _tree_impact(run)
    out = results_path(project)
    tdf = _timing_table(timing, run.engine.name)
    with folder_lock(project.results_dir, "radtree simulate", wait=True, name=PUBLISH_NAME):
        merge_write(out, table, parents)   # table, timing and manifest: one reader sees all
        _write_direct_sun(project, run.chosen, run.prepared)
        if project.district is not None and project.district.buildings is not None:
            from radtree.pipeline.district import write_facades_geojson

            write_facades_geojson(project, pd.read_csv(out, dtype={"facade": str,
                                                                   "building": str}))
        if impact is not None:
            from radtree.pipeline.tree_impact import write_tree_impact

            log.info("  tree impact: %s", write_tree_impact(project, impact))
        _merge_timing(project.results_dir / "timing.csv", tdf)
        write_text(project.results_dir / "manifest.json", json.dumps(
            manifest(project, extra={"engine": run.engine.name,
                                     "scenarios": [s.name for s in run.chosen],
                                     "weather": _weather(project, run.prepared)}),
            indent=2, default=str))
    return SimulationOutcome(pd.read_csv(out), out, tdf, *counts, run.engine.name)


def _results_table(run: Run, frames: list[pd.DataFrame]) -> tuple[pd.DataFrame, list[str]]:
    """The rows of the run, realisations averaged into their scenario (their own rows to
    ``realisations.csv``), in the project's column order; and the parent scenarios."""
    project = run.project
    table = pd.concat(frames, ignore_index=True)
    parents = list(dict.fromkeys(parent_name(sc.name) for sc in run.chosen))
    table, per_realisation = merge_realisations(
        table, {p: project.params_hash(project.scenario(p)) for p in parents})
    if per_realisation is not None:
        merge_write(project.results_dir / "realisations.csv", per_realisation, parents)
    return in_column_order(table, [s.name for s in project.scenarios]), parents


def _weather(project: Project, prepared: dict[str, Prepared]) -> dict[str, Any]:
    """The manifest's weather record: this run's scenarios' hour states, and the earlier
    runs' record of the scenarios the results table still holds."""
    old: dict[str, Any] = {}
    path = project.results_dir / "manifest.json"
    if path.is_file():
        try:
            old = json.loads(path.read_text(encoding="utf-8")).get("weather") or {}
        except (OSError, ValueError):
            old = {}
    states: dict[str, list[SkyState]] = {}
    for name, prep in prepared.items():
        states.setdefault(parent_name(name), prep.states)
    return {**old, **weather_record(project, states)}


def _timing_table(timing: dict[str, dict[str, float]], engine: str) -> pd.DataFrame:
    """Seconds per scenario (realisations summed into their scenario)."""
    summed: dict[str, dict[str, float]] = {}
    for name, v in timing.items():
        acc = summed.setdefault(parent_name(name), dict.fromkeys(v, 0.0))
        for k, x in v.items():
            acc[k] += x
    return pd.DataFrame([{"scenario": k, "engine": engine, **v} for k, v in summed.items()])


def _merge_timing(out: Path, tdf: pd.DataFrame) -> None:
    if out.exists():
        old = pd.read_csv(out)
        old = old[~old["scenario"].astype(str).isin(tdf["scenario"].astype(str))]
        tdf = pd.concat([old, tdf], ignore_index=True)
    with atomic_path(out) as tmp:
        tdf.to_csv(tmp, index=False)


def _tree_impact(run: Run) -> pd.DataFrame | None:
    """The tree-impact table (:mod:`radtree.pipeline.tree_impact`) of the chosen scenarios,
    unless every one of them was reused from earlier parts and the table is there."""
    from radtree.pipeline.tree_impact import tree_impact, tree_impact_path

    path = tree_impact_path(run.project)
    if not run.tree_impact:
        if path.exists():
            log.warning("  tree impact: not attributed in this run (--no-tree-impact); %s is "
                        "from an earlier run", path)
        return None
    if not run.traced and path.exists():
        return None
    return tree_impact(run.project, run.engine, list(run.chosen),
                       {n: (p.built, p.states) for n, p in run.prepared.items()},
                       grids=list(run.grids) if run.grids else None)


def _write_direct_sun(project: Project, chosen: Sequence[Scenario],
                      prepared: dict[str, Prepared]) -> None:
    """``results/direct_sun.csv``: whether the sun beam reaches each sensor at each hour, per
    crown realisation, for the perforated scenarios (:mod:`radtree.pipeline.sunreach`)."""
    from radtree.pipeline.sunreach import direct_sun_rows

    rows = [direct_sun_rows(sc.name, prepared[sc.name].built.scene, prepared[sc.name].states)
            for sc in chosen if sc.model == "perforated"
            and "facade" in prepared[sc.name].built.scene.grids]
    if rows:
        table = pd.concat(rows, ignore_index=True)
        merge_write(project.results_dir / "direct_sun.csv", table,
                    list(dict.fromkeys(table["scenario"].astype(str))))
