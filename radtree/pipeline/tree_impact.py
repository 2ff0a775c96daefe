"""Which tree: ``results/tree_impact.csv``, the light each tree takes from each façade or room.

Written by ``radtree simulate`` when the project has a with/without-trees pair — a scenario
without trees (model ``none``: the template's ``open``, the district's ``bare``) beside
scenarios whose trees have ids (inventory trees: their ``id``; :attr:`radtree.scene.Mesh.owners`).
For every such scenario and hour the engine traces the scene with and without its trees on the
same paths and gives each tree what removing it alone gives back
(:mod:`radtree.engines.numpy.attribution` states the method and how overlapping crowns share).
An engine that cannot attribute (:attr:`radtree.engines.base.Engine.attributes_trees` False,
e.g. Radiance) hands the attribution to the first registered engine that can, and says so.

Columns (one row per scenario × hour × tree × target where the tree changes the target):

* ``scenario``, ``time`` (HH:MM), ``tree`` (the tree's id), ``target`` (the façade id of a
  district sensor, else the grid — an office room), ``grid``;
* ``lux_removed`` — the mean over the target's sensors of the illuminance the tree takes:
  what felling that tree alone gives back (lux; positive = less light with the tree, negative
  = its leaves add light);
* ``lux_removed_stderr`` — its Monte Carlo standard error (sensors independent);
* ``share`` — ``lux_removed`` over the target's whole change (mean ``without − with`` over
  all the trees, the same paths) at that hour. The shares of a target add up to 1 when no two
  crowns take the same light; the remainder (1 − Σ share) is the light several crowns take
  jointly (any one of them would block it), which removing one tree does not give back.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from radtree.config import Project, Scenario, effective_project
from radtree.engines.base import Engine, TreeAttribution
from radtree.engines.registry import attributing_engine
from radtree.fileio import atomic_path
from radtree.log import progress
from radtree.pipeline.build import hour_grids
from radtree.pipeline.realisations import is_later_realisation, parent_name

if TYPE_CHECKING:
    from radtree.config import EngineParams
    from radtree.light.sky import SkyState
    from radtree.pipeline.assemble import BuiltScene
    from radtree.scene import Scene

COLUMNS = ["scenario", "time", "tree", "target", "grid", "lux_removed", "lux_removed_stderr",
           "share"]
FILE = "tree_impact.csv"

log = logging.getLogger(__name__)


def tree_impact_path(project: Project) -> Path:
    """``PROJECT/results/tree_impact.csv``."""
    return project.results_dir / FILE


def has_baseline(project: Project) -> bool:
    """True when the project has a scenario without trees (model ``none``)."""
    return any(s.model == "none" for s in project.scenarios)


def target_rows(scenario: str, time_: str, grid: str, labels: dict[str, list],
                att: TreeAttribution) -> pd.DataFrame:
    """The rows of one grid and hour: per tree and target (façade label, else the grid) the
    mean removed illuminance, its standard error and its share of the target's change."""
    n_s = att.removed.shape[1]
    target = np.asarray(labels["facade"], dtype=object) if "facade" in labels else \
        np.full(n_s, grid, dtype=object)
    change = att.without.lux - att.with_trees.lux
    out = []
    for tg in dict.fromkeys(target.tolist()):
        m = target == tg
        n = int(m.sum())
        lux = att.removed[:, m].mean(axis=1)
        se = np.sqrt((att.stderr[:, m] ** 2).sum(axis=1)) / n
        total = float(change[m].mean())
        keep = (lux != 0.0) | (se != 0.0)
        if not keep.any():
            continue
        out.append(pd.DataFrame({
            "scenario": scenario, "time": time_, "tree": np.asarray(att.owners)[keep],
            "target": str(tg), "grid": grid, "lux_removed": lux[keep],
            "lux_removed_stderr": se[keep],
            "share": lux[keep] / total if total != 0.0 else np.nan}))
    return pd.concat(out, ignore_index=True) if out else pd.DataFrame(columns=COLUMNS)


def scenario_impact(project: Project, sc: Scenario, built: BuiltScene, states: list[SkyState],
                    engine: Engine, grids: list[str] | None = None) -> pd.DataFrame:
    """The tree-impact rows of one scenario at its hours."""
    scene = built.scene
    params = effective_project(project, sc).engine
    frames = []
    for st in progress(states, desc=f"tree impact ({parent_name(sc.name)})"):
        use = hour_grids(project, st.time, list(scene.grids), grids, sc)
        got = engine.attribute_trees(scene, st, params, built.ab, use)
        for g, att in got.items():
            frames.append(target_rows(parent_name(sc.name), st.time, g, scene.grids[g].labels,
                                      att))
    return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame(columns=COLUMNS)


def tree_impact(project: Project, engine: Engine, scenarios: list[Scenario],
                built: dict[str, tuple[BuiltScene, list[SkyState]]], *,
                grids: list[str] | None = None) -> pd.DataFrame | None:
    """The table for the ``scenarios`` with trees that have ids (``built``: each one's scene
    and hour states), or None when the project has no pair or no engine can attribute."""
    with_ids = [sc for sc in scenarios if sc.model != "none"
                and not is_later_realisation(sc.name) and built[sc.name][0].scene.owners()]
    if not with_ids or not has_baseline(project):
        return None
    eng = engine
    if not engine.attributes_trees:
        other = attributing_engine()
        if other is None:
            log.info("  tree impact: the %s engine does not attribute light to trees and no "
                     "engine here does; %s not written", engine.name, FILE)
            return None
        eng = other
        log.info("  tree impact: the %s engine does not attribute light to trees; attributed "
                 "by the %s engine (same scene, hours and sampling settings)", engine.name,
                 eng.name)
    frames = [scenario_impact(project, sc, *built[sc.name], eng, grids) for sc in with_ids]
    return pd.concat(frames, ignore_index=True)[COLUMNS]


def write_tree_impact(project: Project, table: pd.DataFrame) -> Path:
    """Write ``results/tree_impact.csv`` (atomically; the scenarios in ``table`` replace their
    earlier rows)."""
    path = tree_impact_path(project)
    if path.exists():
        old = pd.read_csv(path, dtype={"tree": str, "target": str})
        old = old[~old["scenario"].astype(str).isin(set(table["scenario"].astype(str)))]
        table = pd.concat([old, table], ignore_index=True)
    with atomic_path(path) as tmp:
        table.to_csv(tmp, index=False, float_format="%.6g")
    return path


def removal_check(engine: Engine, scene: Scene, state: SkyState, params: EngineParams, ab: int,
                  top: int = 5, grids: list[str] | None = None, removal_seed: int | None = None
                  ) -> pd.DataFrame:
    """The attribution checked against removing the tree: for the ``top`` trees that take the
    most light from one target (façade or room; one target per tree, its most affected) at
    hour ``state``, the attributed ``lux_removed`` beside the change when that tree alone is
    removed and the scene re-traced (``removal``: the engine's trace without the tree minus
    its trace with all trees, on paired paths of another seed, ``removal_seed``, so the two
    estimates are independent), their standard errors, the difference in standard errors
    ``z`` and ``same_seed``: the removal traced with the attribution's own seed minus the
    attributed light (0 when the attribution is exactly the removal, path for path)."""
    full = engine.attribute_trees(scene, state, params, ab, grids)
    rows = pd.concat([target_rows("", state.time, g, scene.grids[g].labels, a)
                      for g, a in full.items()], ignore_index=True)
    best = (rows.sort_values("lux_removed", ascending=False).drop_duplicates("tree")
            .head(top))
    seed = params.seed + 1 if removal_seed is None else removal_seed
    out = []
    for r in best.itertuples():
        alone = engine.attribute_trees(scene, state, params, ab, [r.grid], {str(r.tree)},
                                       seed)[r.grid]
        again = target_rows("", state.time, r.grid, scene.grids[r.grid].labels, alone)
        hit = again[again["target"] == r.target]
        rem, rem_se = ((float(hit["lux_removed"].iloc[0]), float(hit["lux_removed_stderr"]
                        .iloc[0])) if len(hit) else (0.0, 0.0))
        twin = engine.attribute_trees(scene, state, params, ab, [r.grid], {str(r.tree)})[r.grid]
        tw = target_rows("", state.time, r.grid, scene.grids[r.grid].labels, twin)
        tw = tw[tw["target"] == r.target]
        same = (float(tw["lux_removed"].iloc[0]) if len(tw) else 0.0) - r.lux_removed
        se = float(np.hypot(r.lux_removed_stderr, rem_se))
        out.append({"time": state.time, "tree": r.tree, "target": r.target, "grid": r.grid,
                    "attributed": r.lux_removed, "attributed_se": r.lux_removed_stderr,
                    "removal": rem, "removal_se": rem_se,
                    "z": (r.lux_removed - rem) / se if se > 0 else np.nan,
                    "same_seed": same})
    return pd.DataFrame(out)
